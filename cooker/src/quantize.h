// 8-bit quantization of a light patch: one scale per patch (its largest magnitude) and an
// encoding (linear, or square = sqrt-encoded, which spends more codes on darks), chosen by
// measuring the error each gives against the float values (lightpatch/patch_decode.h).
#pragma once

#include <cstdint>
#include <vector>

#include "lightpatch/cooker/pack_builder.h"
#include "patch_extract.h"

namespace lightpatch::cooker {

// What 8-bit rounding may cost a significant texel-channel of value v (map units) before the
// patch's encoding is said not to hold it: one output step (twice SourcePatch::threshold), or
// 1/kRelativeAllowance of v where that is more (no 8-bit code keeps a bright texel within a fixed
// step; the square encoding's rounding near its top is about 1/255 of the value). In 8 bits, a
// patch whose values span more than about 255 steps cannot keep its dim texels linearly: the end
// of a torch's bracket 3 cm from the light (390 at intensity 1) and the wall beside it (0.47) in
// one patch rounded the wall's light to 0.
constexpr double kRelativeAllowance = 128.0;
double quantization_allowance(double value, double threshold, double scale);

// Error of one encoding over a patch's significant texels, in final-map units (value * weight).
struct EncodingError {
  double sum_sq_error = 0.0;  // sum of squared errors
  double sum_sq_value = 0.0;  // sum of squared values (for relative RMSE)
  double max_error = 0.0;
  // The largest error over its texel-channel's quantization_allowance (<= 1: every significant
  // texel within its allowance).
  double worst_over_allowance = 0.0;
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

// kAuto: the encoding that keeps every significant texel within its quantization_allowance where
// only one does (the smaller worst_over_allowance where neither does), else the smaller squared
// error.
QuantizedPatch quantize_patch(const SourcePatch& patch, EncodingPolicy policy);

// Appends `patch` and its quantization to `out`, or, where the patch is at level 0 and no
// encoding holds every significant texel within its allowance (a torch's bracket beside the wall
// it lights, in one tile), the pieces it is cut into (cut_patch's rules: pieces shrunk to the
// texels that carry light, empty ones dropped): the box of its texels brighter than linear codes
// keep a step beside (510 steps) and the bands around it, which then hold; then a piece that
// still does not hold into its charts (`regions`, light-map patches: the bracket's faces are
// charts of their own). A piece that still does not hold is kept as it is
// (pack.encoding.patches_beyond_allowance counts them). Returns the patches added.
size_t split_for_range(SourcePatch patch, const std::vector<Region>* regions, EncodingPolicy policy,
                       std::vector<SourcePatch>& out, std::vector<QuantizedPatch>& quantized);

}  // namespace lightpatch::cooker
