// Packs with an indirect map (pack_format.h, "Two target maps"): what PackView::open accepts and
// refuses (scale, rectangles in the indirect map's texels, targets and their order in a group),
// the golden bytes of a committed pack that has one, truncation at every byte, and the
// magnification of indirect_map.h against a direct evaluation of the contract's formula.
#include "lightpatch/indirect_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "lightpatch/pack_view.h"
#include "runtime/map_reference.h"
#include "runtime/pack_checks.h"
#include "runtime/synthetic_pack.h"

namespace lightpatch {
namespace {

using testing::make_synthetic_pack;
using testing::open_message;
using testing::SyntheticOptions;
using testing::SyntheticPack;

SyntheticOptions indirect_options(uint32_t scale, uint32_t seed = 1) {
  SyntheticOptions o;
  o.indirect_scale = scale;
  o.seed = seed;
  return o;
}

TEST(IndirectMap, PacksWithAnIndirectMapOpenAtEveryScale) {
  for (uint32_t scale : {2u, 4u, 8u}) {
    PackView v;
    const SyntheticPack bytes = make_synthetic_pack(indirect_options(scale));
    ASSERT_EQ(open_message(bytes, &v), "") << "scale " << scale;
    EXPECT_TRUE(v.has_indirect_map());
    EXPECT_EQ(v.indirect_scale(), scale);
    EXPECT_EQ(v.indirect_width(), 48u / scale);
    EXPECT_EQ(v.indirect_height(), 40u / scale);
    EXPECT_EQ(v.map_offset(pack::kTargetIndirectMap), 48u * 40u);
    EXPECT_EQ(v.map_texels(), 48u * 40u + (48u / scale) * (40u / scale));
    uint32_t indirect = 0;
    for (uint32_t g = 0; g < v.group_count(); ++g) {
      const pack::GroupRecord& gr = v.group(g);
      for (uint32_t p = gr.first_patch + 1; p < gr.first_patch + gr.patch_count; ++p)
        EXPECT_LE(v.patch(p - 1).target, v.patch(p).target);
    }
    for (uint32_t p = 0; p < v.patch_count(); ++p)
      indirect += v.patch(p).target == pack::kTargetIndirectMap;
    EXPECT_GT(indirect, 0u);
    EXPECT_LT(indirect, v.patch_count());
  }
  PackView plain;
  const SyntheticPack plain_bytes = make_synthetic_pack(SyntheticOptions{});  // outlives the view
  ASSERT_EQ(open_message(plain_bytes, &plain), "");
  EXPECT_FALSE(plain.has_indirect_map());
  EXPECT_EQ(plain.indirect_width(), 0u);
  EXPECT_EQ(plain.map_texels(), 48u * 40u);
}

// Each corruption is written before the table checksum, so only the record validation can see it.
TEST(IndirectMap, HostileFieldsAreRefusedByName) {
  struct Case {
    const char* expect;  // part of the message
    std::function<void(pack::Header&, std::vector<pack::PatchRecord>&)> mutate;
  };
  auto first_indirect = [](std::vector<pack::PatchRecord>& p) -> pack::PatchRecord& {
    for (pack::PatchRecord& r : p) {
      if (r.target == pack::kTargetIndirectMap) return r;
    }
    ADD_FAILURE() << "no indirect patch";
    return p[0];
  };
  const Case cases[] = {
      {"indirect scale 3", [](pack::Header& h, auto&) { h.indirect_scale = 3; }},
      {"indirect scale 1 ", [](pack::Header& h, auto&) { h.indirect_scale = 1; }},
      {"indirect scale 16", [](pack::Header& h, auto&) { h.indirect_scale = 16; }},
      {"indirect scale 4294967295", [](pack::Header& h, auto&) { h.indirect_scale = ~0u; }},
      {"does not divide", [](pack::Header& h, auto&) { h.lightmap_height = 44; }},  // 44 % 8
      {"does not divide", [](pack::Header& h, auto&) { h.lightmap_width = 44; }},
      {"unknown target 2", [&](auto&, auto& p) { first_indirect(p).target = 2; }},
      {"unknown target 255", [&](auto&, auto& p) { first_indirect(p).target = 255; }},
      {"of a pack that has none", [](pack::Header& h, auto&) { h.indirect_scale = 0; }},
      {"exceeds indirect-map width 6",
       [&](auto&, auto& p) {
         pack::PatchRecord& r = first_indirect(p);
         r.dest_x = uint16_t(6 - r.width + 1);
       }},
      {"exceeds indirect-map height 5",
       [&](auto&, auto& p) {
         pack::PatchRecord& r = first_indirect(p);
         r.dest_y = uint16_t(0xFFFF);  // 16-bit: the sum is taken in 32 bits
       }},
      {"light map after an indirect-map patch",
       [](auto&, std::vector<pack::PatchRecord>& p) {
         // The last patch of a group that has both kinds turns into a light-map patch.
         for (size_t i = 0; i + 1 < p.size(); ++i) {
           if (p[i].target == pack::kTargetIndirectMap && p[i + 1].group == p[i].group) {
             p[i + 1].target = pack::kTargetLightMap;
             return;
           }
         }
         ADD_FAILURE() << "no group with two indirect patches";
       }},
  };
  for (const Case& c : cases) {
    SyntheticOptions o = indirect_options(8, 4);  // 6x5 indirect map
    o.indirect_patches_per_group = 4;
    o.mutate = c.mutate;
    const std::string message = open_message(make_synthetic_pack(o));
    EXPECT_NE(message.find(c.expect), std::string::npos)
        << "expected \"" << c.expect << "\", got \"" << message << "\"";
  }
  // The unchanged pack opens (the cases above are refused for what they change).
  EXPECT_EQ(open_message(make_synthetic_pack(indirect_options(8, 4))), "");
}

// The committed pack with an indirect map (tests/data/packs/indirect.lpk, also a fuzz seed): a
// 16x8 light map, a 8x4 indirect map, one light, one object.
SyntheticPack build_indirect_pack() {
  SyntheticOptions o;
  o.width = 16;
  o.height = 8;
  o.lights = 1;
  o.objects = 1;
  o.atlas_size = 16;
  o.max_patch = 4;
  o.patches_per_group = 2;
  o.indirect_patches_per_group = 2;
  o.indirect_scale = 2;
  o.seed = 3;
  return make_synthetic_pack(o);
}

// Golden values of indirect.lpk (format version 7 with an indirect map).
constexpr uint64_t kIndirectSize = 3072;
constexpr uint32_t kIndirectCrc = 0xe9b16f75u;

// Keeps the committed pack byte-equal to what the builder writes (committed_pack.h).
TEST(IndirectMap, GoldenBytesOfAPackWithAnIndirectMap) {
  const SyntheticPack built = build_indirect_pack();
  const uint8_t* b = reinterpret_cast<const uint8_t*>(built.data());
  testing::expect_committed_pack(b, built.size, "indirect.lpk", kIndirectSize, kIndirectCrc);
  // The new fields at their pinned offsets: the header's scale, and a patch's target byte.
  uint32_t scale = 0;
  std::memcpy(&scale, b + 60, 4);
  EXPECT_EQ(scale, 2u);
  PackView v;
  ASSERT_EQ(open_message(built, &v), "");
  const uint8_t* patches = reinterpret_cast<const uint8_t*>(v.patches());
  uint32_t indirect = 0;
  for (uint32_t p = 0; p < v.patch_count(); ++p) {
    const uint8_t target = patches[p * sizeof(pack::PatchRecord) + 21];
    EXPECT_EQ(target, v.patch(p).target);
    indirect += target == pack::kTargetIndirectMap;
  }
  EXPECT_GT(indirect, 0u);
}

TEST(IndirectMap, TruncatedAtEveryByteIsRefused) {
  const SyntheticPack built = build_indirect_pack();
  testing::expect_truncations_refused(built.data(), built.size);
}

TEST(IndirectMap, MagnificationEqualsTheContractsFormula) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> value(0.0, 10.0);
  const uint32_t sizes[][2] = {{1, 1}, {3, 5}, {6, 5}, {12, 10}};
  for (uint32_t s : {2u, 4u, 8u}) {
    for (const auto& size : sizes) {
      const uint32_t w = size[0], h = size[1];
      std::vector<double> indirect(size_t(w) * h * 3);
      for (double& v : indirect) v = value(rng);
      std::vector<float> indirect_f(indirect.begin(), indirect.end());
      // Double: equal to rounding. Float: to a few ulps (the weights are exact).
      std::vector<double> base(size_t(w) * s * h * s * 3, 1.0);
      std::vector<float> base_f(base.size(), 1.0f);
      add_magnified_indirect(indirect.data(), 3, w, h, s, base.data(), 3);
      add_magnified_indirect(indirect_f.data(), 3, w, h, s, base_f.data(), 3);
      for (uint32_t y = 0; y < h * s; ++y) {
        for (uint32_t x = 0; x < w * s; ++x) {
          for (int c = 0; c < 3; ++c) {
            const double want =
                1.0 + testing::contract_indirect_at(indirect.data(), w, h, s, x, y, c);
            const size_t i = (size_t(y) * w * s + x) * 3 + size_t(c);
            ASSERT_NEAR(base[i], want, 1e-12) << "s " << s << " at " << x << "," << y;
            ASSERT_NEAR(base_f[i], want, 4e-6 * want) << "s " << s << " at " << x << "," << y;
          }
        }
      }
    }
  }
}

// Properties a bilinear magnification has: a constant stays constant; a ramp is reproduced
// exactly between the outer texel centres and flat beyond them; other channels of a wider
// stride are left alone.
TEST(IndirectMap, MagnificationKeepsConstantsAndRamps) {
  const uint32_t w = 5, h = 3, s = 4;
  std::vector<float> ramp(size_t(w) * h * 4, 0.0f), constant(ramp.size(), 0.25f);
  for (uint32_t j = 0; j < h; ++j) {
    for (uint32_t i = 0; i < w; ++i) {
      ramp[(j * w + i) * 4 + 0] = float(i);
      ramp[(j * w + i) * 4 + 1] = float(j);
    }
  }
  std::vector<float> out(size_t(w) * s * h * s * 4, 0.0f), flat(out.size(), 0.0f);
  for (size_t i = 3; i < out.size(); i += 4) out[i] = flat[i] = -7.0f;  // untouched
  add_magnified_indirect(ramp.data(), 4, w, h, s, out.data(), 4);
  add_magnified_indirect(constant.data(), 4, w, h, s, flat.data(), 4);
  for (uint32_t y = 0; y < h * s; ++y) {
    for (uint32_t x = 0; x < w * s; ++x) {
      const float* t = &out[(size_t(y) * w * s + x) * 4];
      const float u = (float(x) + 0.5f) / float(s) - 0.5f, v = (float(y) + 0.5f) / float(s) - 0.5f;
      EXPECT_EQ(t[0], std::min(std::max(u, 0.0f), float(w - 1)));
      EXPECT_EQ(t[1], std::min(std::max(v, 0.0f), float(h - 1)));
      EXPECT_EQ(t[2], 0.0f);
      EXPECT_EQ(t[3], -7.0f);
      const float* f = &flat[(size_t(y) * w * s + x) * 4];
      for (int c = 0; c < 3; ++c) EXPECT_EQ(f[c], 0.25f);
      EXPECT_EQ(f[3], -7.0f);
    }
  }
}

}  // namespace
}  // namespace lightpatch
