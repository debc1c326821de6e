// The one place the GLES headers are included. Runtime and tool code include this header, never
// <GLES3/...> directly, so that a platform that needs different headers (or a loader) changes
// only this file.
#pragma once

// gl2ext.h needs the types gl3.h declares: keep this order.
// clang-format off
#include <GLES3/gl3.h>
#include <GLES2/gl2ext.h>
// clang-format on
