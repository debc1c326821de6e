#include "lightpatch/cpu_sink.h"

#include <cstring>

#include "lightpatch/half_float.h"
#include "lightpatch/patch_accumulate.h"

namespace lightpatch {

void CpuSink::bind(const PackView* pack, double* accumulator, float* rgb, uint16_t* half_rgba,
                   float scale) {
  pack_ = pack;
  accumulator_ = accumulator;
  rgb_ = rgb;
  half_rgba_ = half_rgba;
  scale_ = scale;
  clear_dirty();
}

void CpuSink::clear_dirty() {
  for (int t = 0; t < 2; ++t) dirty_begin_[t] = dirty_end_[t] = 0;
}

void CpuSink::clear() {
  std::memset(accumulator_, 0, sizeof(double) * 3 * size_t(pack_->map_texels()));
}

void CpuSink::draw(uint32_t, uint32_t first, uint32_t count, const float factor[3]) {
  const double f[3] = {factor[0], factor[1], factor[2]};
  add_patches(*pack_, first, count, f, accumulator_);
}

void CpuSink::present_rect(uint8_t target, uint32_t x0, uint32_t y0, uint32_t width,
                           uint32_t height) {
  const uint32_t w = pack_->map_width(target);
  const size_t base = size_t(pack_->map_offset(target));  // the target's first texel
  const bool keep_sign = pack_->presents_signed();
  for (uint32_t y = y0; y < y0 + height; ++y) {
    const size_t row = base + size_t(y) * w + x0;
    const double* src = accumulator_ + row * 3;
    for (uint32_t x = 0; x < width; ++x) {
      for (uint32_t c = 0; c < 3; ++c) {
        const double a = src[x * 3 + c];
        const double v = keep_sign || a > 0.0 ? a * scale_ : 0.0;
        if (rgb_) {
          rgb_[(row + x) * 3 + c] = float(v);
        } else {
          half_rgba_[(row + x) * 4 + c] = float_to_half(float(v));
        }
      }
      if (half_rgba_) half_rgba_[(row + x) * 4 + 3] = 0x3C00u;  // alpha 1
    }
  }
  uint32_t& begin = dirty_begin_[target];
  uint32_t& end = dirty_end_[target];
  if (begin == end) {
    begin = y0;
    end = y0 + height;
  } else {
    if (y0 < begin) begin = y0;
    if (y0 + height > end) end = y0 + height;
  }
}

void CpuSink::present(uint32_t first, uint32_t count) {
  for (uint32_t p = first; p < first + count; ++p) {
    const pack::PatchRecord& pr = pack_->patch(p);
    present_rect(pr.target, pr.dest_x, pr.dest_y, pr.width, pr.height);
  }
}

void CpuSink::present_all() {
  present_rect(pack::kTargetLightMap, 0, 0, pack_->lightmap_width(), pack_->lightmap_height());
  if (pack_->has_indirect_map()) {
    present_rect(pack::kTargetIndirectMap, 0, 0, pack_->indirect_width(), pack_->indirect_height());
  }
}

}  // namespace lightpatch
