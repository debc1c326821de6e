// File helpers for the tools: atomic writes (temporary file in the same folder, flush, rename),
// whole-file reads and PFM float images (scanlines bottom to top, as the format says).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/cooker/maps.h"

namespace lightpatch::cooker {

// Writes `size` bytes to `path` atomically: nothing is left at `path` unless the whole write
// succeeded; an existing file stays untouched on failure. Throws CookError.
void write_file_atomic(const std::string& path, const void* data, size_t size);
std::vector<uint8_t> read_file(const std::string& path);  // throws CookError

// PFM: "PF" (3 channels) or "Pf" (1 channel), little-endian (scale -1). FloatImage row 0 is the
// top row, so it is written last.
void write_pfm(const std::string& path, const FloatImage& image);  // atomic; throws CookError
FloatImage read_pfm(const std::string& path);                      // throws CookError

}  // namespace lightpatch::cooker
