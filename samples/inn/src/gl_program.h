// Compiling and linking the sample's small GLSL ES 3.00 programs.
#pragma once

#include <cstdint>

namespace lightpatch::inn {

// Builds a program from vertex and fragment sources, binding attribute i to the i-th name of
// `attributes` (null-terminated list). Returns 0 and writes a message on failure.
uint32_t build_program(const char* vertex_source, const char* fragment_source,
                       const char* const* attributes, char* message, unsigned message_size);

}  // namespace lightpatch::inn
