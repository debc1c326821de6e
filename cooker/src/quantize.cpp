#include "quantize.h"

#include <algorithm>
#include <cmath>

#include "lightpatch/pack_format.h"
#include "lightpatch/patch_decode.h"

namespace lightpatch::cooker {

void EncodingError::add(const EncodingError& o) {
  sum_sq_error += o.sum_sq_error;
  sum_sq_value += o.sum_sq_value;
  max_error = std::max(max_error, o.max_error);
  samples += o.samples;
}

uint8_t encode_value(float v, float scale, uint8_t encoding) {
  const double x = std::clamp(double(v) / double(scale), 0.0, 1.0);
  const double t = encoding == pack::kEncodingSquare ? std::sqrt(x) : x;
  const int q0 = static_cast<int>(std::lround(t * 255.0));
  int best = std::clamp(q0, 0, 255);
  float best_err = INFINITY;
  for (int q = std::max(q0 - 1, 0); q <= std::min(q0 + 1, 255); ++q) {
    const float err = std::fabs(scale * patch_decode_unit(uint8_t(q), encoding) - v);
    if (err < best_err) {
      best_err = err;
      best = q;
    }
  }
  return static_cast<uint8_t>(best);
}

QuantizedPatch quantize_patch(const SourcePatch& patch, EncodingPolicy policy) {
  QuantizedPatch out;
  float scale = 0.0f;
  for (float v : patch.values) scale = std::max(scale, v);
  out.scale = scale > 0.0f ? scale : 1.0f;  // extraction guarantees a significant (> 0) value
  std::vector<uint8_t> codes[2];
  for (uint8_t enc = 0; enc < 2; ++enc) {
    codes[enc].resize(patch.values.size());
    EncodingError& e = out.error[enc];
    for (size_t i = 0; i < patch.values.size(); ++i) {
      const uint8_t q = encode_value(patch.values[i], out.scale, enc);
      codes[enc][i] = q;
      if (!patch.significant[i / size_t(patch.channels)]) continue;
      const double v = double(patch.values[i]) * patch.weight;
      const double d = double(out.scale * patch_decode_unit(q, enc)) * patch.weight;
      const double err = std::fabs(d - v);
      e.sum_sq_error += err * err;
      e.sum_sq_value += v * v;
      e.max_error = std::max(e.max_error, err);
      e.samples++;
    }
  }
  switch (policy) {
    case EncodingPolicy::kLinear:
      out.encoding = pack::kEncodingLinear;
      break;
    case EncodingPolicy::kSquare:
      out.encoding = pack::kEncodingSquare;
      break;
    case EncodingPolicy::kAuto:
      // Both cost the same bytes: keep the one with the smaller squared error (ties: linear).
      out.encoding = out.error[1].sum_sq_error < out.error[0].sum_sq_error ? pack::kEncodingSquare
                                                                           : pack::kEncodingLinear;
      break;
  }
  out.codes = std::move(codes[out.encoding]);
  return out;
}

}  // namespace lightpatch::cooker
