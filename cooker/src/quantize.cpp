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
  worst_over_allowance = std::max(worst_over_allowance, o.worst_over_allowance);
  samples += o.samples;
}

double quantization_allowance(double value, double threshold, double scale) {
  // scale / 65536 is under the square encoding's smallest code (scale / 65025): a floor that keeps
  // the allowance > 0 without loosening any code's own error.
  return std::max({2.0 * threshold, value / kRelativeAllowance, scale / 65536.0});
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
      const double allowance =
          quantization_allowance(patch.values[i], patch.threshold, out.scale) * patch.weight;
      if (allowance > 0.0)
        e.worst_over_allowance = std::max(e.worst_over_allowance, err / allowance);
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
    case EncodingPolicy::kAuto: {
      // Both cost the same bytes. The one that holds every significant texel where only one does
      // (or the one that misses least); else the smaller squared error (ties: linear).
      const double w0 = out.error[0].worst_over_allowance, w1 = out.error[1].worst_over_allowance;
      const bool square =
          (w0 > 1.0 || w1 > 1.0) ? w1 < w0 : out.error[1].sum_sq_error < out.error[0].sum_sq_error;
      out.encoding = square ? pack::kEncodingSquare : pack::kEncodingLinear;
      break;
    }
  }
  out.codes = std::move(codes[out.encoding]);
  return out;
}

namespace {

// The box of `patch`'s texels over 510 output steps (1020 half steps) and the bands around it:
// a patch without such texels rounds every texel within a step in linear codes (half a code of a
// 510-step scale is one step), so the bands hold. Empty where the box is the whole patch.
std::vector<SourcePatch> bright_box_cut(const SourcePatch& patch) {
  const float bright = 1020.0f * patch.threshold;
  const int w = patch.dest.w, h = patch.dest.h, ch = patch.channels;
  int x0 = w, y0 = h, x1 = -1, y1 = -1;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < ch; ++c)
        if (patch.values[(size_t(y) * w + x) * ch + c] > bright) {
          x0 = std::min(x0, x);
          y0 = std::min(y0, y);
          x1 = std::max(x1, x);
          y1 = std::max(y1, y);
        }
  if (x1 < 0 || (x0 == 0 && y0 == 0 && x1 == w - 1 && y1 == h - 1)) return {};
  std::vector<Rect> cells;
  for (const Rect& r :
       {Rect{x0, y0, x1 - x0 + 1, y1 - y0 + 1}, Rect{0, 0, w, y0}, Rect{0, y1 + 1, w, h - y1 - 1},
        Rect{0, y0, x0, y1 - y0 + 1}, Rect{x1 + 1, y0, w - x1 - 1, y1 - y0 + 1}})
    if (r.w > 0 && r.h > 0) cells.push_back(r);
  return cut_patch(patch, cells);
}

// The bright box first, then (for a piece that still does not hold) its charts.
size_t split_for_range(SourcePatch patch, const std::vector<Region>* regions, EncodingPolicy policy,
                       std::vector<SourcePatch>& out, std::vector<QuantizedPatch>& quantized,
                       bool box) {
  QuantizedPatch q = quantize_patch(patch, policy);
  std::vector<SourcePatch> pieces;
  if (q.error[q.encoding].worst_over_allowance > 1.0 && patch.level == 0) {
    if (box) pieces = bright_box_cut(patch);
    if (pieces.size() < 2 && regions) {
      pieces = split_by_charts(patch, *regions, 0);
      regions = nullptr;  // a chart's piece is cut no further
    }
  }
  if (pieces.size() < 2) {
    out.push_back(std::move(patch));
    quantized.push_back(std::move(q));
    return 1;
  }
  size_t added = 0;
  for (SourcePatch& piece : pieces)
    added += split_for_range(std::move(piece), regions, policy, out, quantized, false);
  return added;
}

}  // namespace

size_t split_for_range(SourcePatch patch, const std::vector<Region>* regions, EncodingPolicy policy,
                       std::vector<SourcePatch>& out, std::vector<QuantizedPatch>& quantized) {
  return split_for_range(std::move(patch), regions, policy, out, quantized, true);
}

}  // namespace lightpatch::cooker
