// The one place the GLES headers are included. Runtime and tool code include this header, never
// <GLES3/...> directly, so that a platform that needs different headers (or a loader) changes
// only this file.
#pragma once

#include <GLES3/gl3.h>
#include <GLES2/gl2ext.h>
