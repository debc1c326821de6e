// 8-bit quantization of a light patch: one scale per patch (its largest magnitude) and an
// encoding (linear, or square = sqrt-encoded, which spends more codes on darks), chosen by
// measuring the error each gives against the float values (lightpatch/patch_decode.h).
#pragma once

#include <cstdint>
#include <vector>

#include "lightpatch/cooker/pack_builder.h"
#include "patch_extract.h"

namespace lightpatch::cooker {

// Error of one encoding over a patch's significant texels, in final-map units (value * weight).
struct EncodingError {
  double sum_sq_error = 0.0;  // sum of squared errors
  double sum_sq_value = 0.0;  // sum of squared values (for relative RMSE)
  double max_error = 0.0;
  uint64_t samples = 0;  // texel-channels measured
  void add(const EncodingError& o);
};

struct QuantizedPatch {
  float scale = 0.0f;          // > 0
  uint8_t encoding = 0;        // pack::PatchEncoding
  std::vector<uint8_t> codes;  // like SourcePatch::values
  EncodingError error[2];      // measured for linear [0] and square [1]
};

// Code for magnitude v (0 <= v <= scale) minimizing |decode(code) - v| with the runtime's decode.
uint8_t encode_value(float v, float scale, uint8_t encoding);

QuantizedPatch quantize_patch(const SourcePatch& patch, EncodingPolicy policy);

}  // namespace lightpatch::cooker
