// What the GLES runtime presents, read back for comparisons with the CPU recomposer: the pack's
// map set (pack_view.h: the light map, then the indirect map where the pack has one), and what a
// game samples, L + the indirect map magnified (indirect_map.h), as the CPU recomposer's rgb().
// RGB floats (alpha dropped), row 0 at the top. A read stalls the pipeline: tests only.
#pragma once

#include <gtest/gtest.h>
#include <algorithm>

#include <cstddef>
#include <vector>

#include "lightpatch/indirect_map.h"
#include "lightpatch/runtime.h"

namespace lightpatch::testing {

// The map set as RGB: map_texels() * 3 values (CpuRecomposer::presented_maps()'s layout).
inline std::vector<float> read_map_set(const Runtime& runtime, const PackView& pack) {
  const size_t light = size_t(runtime.width()) * runtime.height();
  std::vector<float> rgba(size_t(pack.map_texels()) * 4);
  Error error;
  EXPECT_EQ(runtime.read_light_map(rgba.data(), &error), Status::kOk) << error.message;
  if (pack.has_indirect_map()) {
    EXPECT_EQ(runtime.read_indirect_map(rgba.data() + light * 4, &error), Status::kOk)
        << error.message;
  }
  std::vector<float> rgb(rgba.size() / 4 * 3);
  for (size_t i = 0; i < rgba.size() / 4; ++i) {
    for (size_t c = 0; c < 3; ++c) rgb[i * 3 + c] = rgba[i * 4 + c];
  }
  return rgb;
}

// max(L + magnified I, 0) from a map set: width * height * 3 values (CpuRecomposer::rgb()'s
// layout).
inline std::vector<float> sampled_from(const std::vector<float>& maps, const PackView& pack) {
  const size_t light = size_t(pack.lightmap_width()) * pack.lightmap_height() * 3;
  std::vector<float> out(maps.begin(), maps.begin() + std::ptrdiff_t(light));
  if (pack.has_indirect_map()) {
    add_magnified_indirect(maps.data() + light, 3, pack.indirect_width(), pack.indirect_height(),
                           pack.indirect_scale(), out.data(), 3);
    for (float& v : out) v = std::max(v, 0.0f);  // the game clamps L + I
  }
  return out;
}

inline std::vector<float> read_sampled(const Runtime& runtime, const PackView& pack) {
  return sampled_from(read_map_set(runtime, pack), pack);
}

}  // namespace lightpatch::testing
