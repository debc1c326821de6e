// Magnified patches (pack_format.h, "Magnified patches"): what PackView::open accepts and refuses
// (the atlas rectangle is checked with the atlas sides, the destination with width and height),
// and add_patches (patch_accumulate.h) against a direct evaluation of the rule in double, written
// here independently, including that a patch never reads its atlas neighbours.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "lightpatch/group_rules.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/patch_accumulate.h"
#include "runtime/pack_checks.h"
#include "runtime/synthetic_pack.h"

namespace lightpatch {
namespace {

using testing::make_synthetic_pack;
using testing::open_message;
using testing::SyntheticOptions;
using testing::SyntheticPack;

// A 48x40 light map, 16x16 atlases: a level-1 patch may be wider than its atlas.
SyntheticOptions small_atlas_options() {
  SyntheticOptions o;
  o.atlas_size = 16;
  o.max_patch = 6;
  return o;
}

TEST(MagnifiedPatches, TheAtlasRectangleIsCheckedWithTheAtlasSides) {
  using Patches = std::vector<pack::PatchRecord>;
  auto with_patch0 = [](uint32_t level, uint16_t atlas_x, uint16_t width) {
    SyntheticOptions o = small_atlas_options();
    o.mutate = [=](pack::Header&, Patches& p) {
      p[0].atlas = 0;
      p[0].atlas_x = atlas_x;
      p[0].atlas_y = 0;
      p[0].width = width;
      p[0].height = 20;  // 10 atlas rows at level 1
      p[0].dest_x = p[0].dest_y = 0;
      p[0].flags = uint8_t((p[0].flags & ~pack::kFlagLevelMask) | (level << pack::kFlagLevelShift));
    };
    return make_synthetic_pack(o);
  };
  ASSERT_EQ(open_message(make_synthetic_pack(small_atlas_options())), "");
  // 31 destination texels from 16 atlas texels: fits the 16-texel atlas at x = 0.
  const testing::SyntheticPack wide = with_patch0(1, 0, 31);  // outlives the view
  PackView view;
  EXPECT_EQ(open_message(wide, &view), "");
  EXPECT_EQ(pack::patch_level(view.patch(0).flags), 1u);
  EXPECT_EQ(open_message(with_patch0(2, 0, 48)), "");  // 12 atlas texels
  // The same at x = 1 (17 > 16), or at level 0, is refused, naming the patch.
  for (const std::string& m :
       {open_message(with_patch0(1, 1, 31)), open_message(with_patch0(0, 0, 31)),
        open_message(with_patch0(1, 0xFFFF, 31))}) {
    EXPECT_NE(m.find("patch 0: atlas rectangle"), std::string::npos) << m;
    EXPECT_NE(m.find("exceeds atlas 0 (16x16)"), std::string::npos) << m;
  }
  EXPECT_NE(open_message(with_patch0(1, 1, 31)).find("1+16 x 0+10 (level 1, destination 31x20)"),
            std::string::npos)
      << open_message(with_patch0(1, 1, 31));
  // The destination is still checked with the destination sides.
  const std::string dest = open_message(with_patch0(3, 0, 49));
  EXPECT_NE(dest.find("patch 0: destination rectangle 0+49 exceeds light-map width 48"),
            std::string::npos)
      << dest;
  // Flags beyond the level stay unknown.
  SyntheticOptions o = small_atlas_options();
  o.mutate = [](pack::Header&, Patches& p) { p[0].flags = uint8_t(p[0].flags | 0x20u); };
  EXPECT_NE(open_message(make_synthetic_pack(o)).find("patch 0: unknown flags"), std::string::npos);
  // The bytes after the second tint are reserved.
  o.mutate = [](pack::Header&, Patches& p) { p[1].reserved = 1; };
  EXPECT_NE(open_message(make_synthetic_pack(o)).find("patch 1: reserved field not zero"),
            std::string::npos);
  // A second tint only on a 2-channel patch; a 2-channel patch's channels within RGBA.
  o.mutate = [](pack::Header&, Patches& p) {
    p[0].channel_count = 1;
    p[0].tint_b[1] = 7;
  };
  EXPECT_NE(open_message(make_synthetic_pack(o)).find("patch 0: a second tint on a 1-channel"),
            std::string::npos);
  o.mutate = [](pack::Header&, Patches& p) {
    p[0].channel_count = 2;
    p[0].channel = 3;
    p[0].flags = uint8_t(p[0].flags & ~pack::kFlagDestinationMask);
  };
  EXPECT_NE(open_message(make_synthetic_pack(o)).find("patch 0: channels 3+2 exceed RGBA"),
            std::string::npos);
}

// Many magnified patches of every kind, shelf-packed against each other in the atlases.
SyntheticOptions magnified_options(uint32_t seed) {
  SyntheticOptions o;
  o.seed = seed;
  o.lights = 4;
  o.objects = 3;
  o.max_patch = 13;
  o.patches_per_group = 6;
  o.indirect_scale = 2;
  o.magnified_probability = 0.6f;
  o.tinted_probability = 0.4f;
  o.two_channel_probability = 0.5f;
  return o;
}

// The rule evaluated directly in double: decode each of the four taps, clamped explicitly to the
// patch's atlas rectangle, and weight them. `clamp_right`: false reads past the right and bottom
// edges (a wrong implementation, for the controls).
double rule_at(const PackView& pack, const pack::PatchRecord& p, uint32_t x, uint32_t y, int c,
               bool clamp_right = true, bool nearest = false) {
  const uint32_t level = (p.flags >> 3) & 3u;
  const double side = double(1u << level);
  const int aw = int((p.width + (1u << level) - 1) >> level);
  const int ah = int((p.height + (1u << level) - 1) >> level);
  const double sx = (x + 0.5) / side - 0.5, sy = (y + 0.5) / side - 0.5;
  const double ix = std::floor(sx), iy = std::floor(sy);
  const double fx = sx - ix, fy = sy - iy;
  auto clamp = [&](int i, int n) {
    if (i < 0) return 0;
    if (clamp_right && i > n - 1) return n - 1;
    return i;
  };
  const int x0 = clamp(int(ix), aw), x1 = clamp(int(ix) + 1, aw);
  const int y0 = clamp(int(iy), ah), y1 = clamp(int(iy) + 1, ah);
  // c: the map channel of a 3-channel patch, or a 2-channel patch's channel (0 or 1).
  const int channel = p.channel + (p.channel_count >= 2 ? c : 0);
  const uint8_t* pixels = pack.atlas_pixels(p.atlas);
  const uint32_t stride = pack.atlas(p.atlas).width;
  auto value = [&](int tx, int ty) {
    const uint8_t q = pixels[((size_t(p.atlas_y) + ty) * stride + p.atlas_x + tx) * 4 + channel];
    double v = q / 255.0;
    if (p.encoding == pack::kEncodingSquare) v *= v;
    const bool subtracts = pack::group_subtracts(pack.group(p.group).kind);
    const bool negative = (p.flags & pack::kFlagNegative) != 0;
    return (subtracts != negative ? -1.0 : 1.0) * double(p.scale) * v;
  };
  if (nearest) return value(int(x >> level), int(y >> level));
  return (1 - fx) * (1 - fy) * value(x0, y0) + fx * (1 - fy) * value(x1, y0) +
         (1 - fx) * fy * value(x0, y1) + fx * fy * value(x1, y1);
}

// The expected map set after drawing patch i alone with `factor`, from rule_at.
std::vector<double> rule_map(const PackView& pack, uint32_t i, const double factor[3],
                             bool clamp_right = true, bool nearest = false) {
  std::vector<double> map(size_t(pack.map_texels()) * 3, 0.0);
  const pack::PatchRecord& p = pack.patch(i);
  const int destination = pack::patch_destination(p.flags);
  const uint32_t w = pack.map_width(p.target);
  for (uint32_t y = 0; y < p.height; ++y) {
    for (uint32_t x = 0; x < p.width; ++x) {
      double* t =
          map.data() + (pack.map_offset(p.target) + (size_t(p.dest_y) + y) * w + p.dest_x + x) * 3;
      for (int c = 0; c < 3; ++c) {
        if (destination >= 0 && c != destination) continue;
        if (p.channel_count == 2)  // two tints: each channel's value times its own
          t[c] +=
              factor[c] * ((p.tint[c] / 255.0) * rule_at(pack, p, x, y, 0, clamp_right, nearest) +
                           (p.tint_b[c] / 255.0) * rule_at(pack, p, x, y, 1, clamp_right, nearest));
        else
          t[c] += factor[c] * (p.tint[c] / 255.0) * rule_at(pack, p, x, y, c, clamp_right, nearest);
      }
    }
  }
  return map;
}

double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0.0;
  for (size_t k = 0; k < a.size(); ++k) m = std::max(m, std::fabs(a[k] - b[k]));
  return m;
}

TEST(MagnifiedPatches, TheSyntheticPackHasMagnifiedPatchesOfEveryKind) {
  const SyntheticPack bytes = make_synthetic_pack(magnified_options(3));
  PackView pack;
  ASSERT_EQ(open_message(bytes, &pack), "");
  uint32_t level[4] = {}, odd = 0, even = 0, rgb = 0, grey = 0, single = 0, square = 0, linear = 0,
           negative = 0, subtracted = 0, indirect = 0, light_map = 0, tinted = 0, two[2] = {};
  for (uint32_t i = 0; i < pack.patch_count(); ++i) {
    const pack::PatchRecord& p = pack.patch(i);
    const uint32_t l = pack::patch_level(p.flags);
    ++level[l];
    tinted += pack::patch_has_tint(p);
    if (p.channel_count == 2) ++two[l > 0];
    if (l == 0) continue;
    ++((p.width % 2) ? odd : even);
    ++((p.height % 2) ? odd : even);
    ++(p.channel_count == 3 ? rgb : pack::patch_destination(p.flags) >= 0 ? single : grey);
    ++(p.encoding == pack::kEncodingSquare ? square : linear);
    negative += (p.flags & pack::kFlagNegative) != 0;
    subtracted += pack::group_subtracts(pack.group(p.group).kind);
    ++(p.target == pack::kTargetIndirectMap ? indirect : light_map);
  }
  EXPECT_GT(level[0], 0u);
  EXPECT_GT(level[1], 0u);
  EXPECT_GT(level[2], 0u);
  for (uint32_t n : {odd, even, rgb, grey, single, square, linear, negative, subtracted, indirect,
                     light_map, tinted, two[0], two[1]})
    EXPECT_GT(n, 0u);
}

// add_patches of each magnified patch alone equals the rule to float rounding (in float and in
// double: the decoded values are floats, as for level 0), and so does its magnitude bound
// (`absolute`) on the absolute values. The controls: the data tells the rule from nearest-neighbour
// magnification and from unclamped taps.
TEST(MagnifiedPatches, AddPatchesFollowsTheRule) {
  for (uint32_t seed : {3u, 4u}) {
    const SyntheticPack bytes = make_synthetic_pack(magnified_options(seed));
    PackView pack;
    ASSERT_EQ(open_message(bytes, &pack), "");
    const double factor[3] = {0.75, -1.5, 2.25};
    const float factor_f[3] = {0.75f, -1.5f, 2.25f};
    const double one[3] = {1, 1, 1};
    double nearest_gap = 0.0;
    uint32_t checked = 0;
    for (uint32_t i = 0; i < pack.patch_count(); ++i) {
      if (pack::patch_level(pack.patch(i).flags) == 0) continue;
      ++checked;
      const std::vector<double> want = rule_map(pack, i, factor);
      std::vector<double> got(want.size(), 0.0);
      add_patches(pack, i, 1, factor, got.data());
      std::vector<float> got_f(want.size(), 0.0f);
      add_patches(pack, i, 1, factor_f, got_f.data());
      double scale = 0.0;
      for (double v : want) scale = std::max(scale, std::fabs(v));
      for (size_t k = 0; k < want.size(); ++k) {
        ASSERT_NEAR(got[k], want[k], 1e-6 * (1.0 + scale)) << "patch " << i << " value " << k;
        ASSERT_NEAR(got_f[k], want[k], 1e-6 * (1.0 + scale)) << "patch " << i << " value " << k;
      }
      // The magnitude bound: interpolated |values|, >= |value| (one sign within a patch: equal).
      std::vector<double> bound(want.size(), 0.0);
      add_patches(pack, i, 1, one, bound.data(), /*absolute=*/true);
      const std::vector<double> unit = rule_map(pack, i, one);
      for (size_t k = 0; k < want.size(); ++k)
        ASSERT_NEAR(bound[k], std::fabs(unit[k]), 1e-6 * (1.0 + scale)) << "patch " << i;
      nearest_gap = std::max(nearest_gap, max_abs_difference(want, rule_map(pack, i, factor, true,
                                                                            /*nearest=*/true)));
    }
    EXPECT_GT(checked, 10u);
    EXPECT_GT(nearest_gap, 0.05) << "the data does not tell bilinear from nearest";
  }
}

// Tinted patches (PatchRecord::tint), at level 0 and magnified: add_patches multiplies the value
// added to each map channel by tint / 255, as the rule written out above does. Control: the same
// rule without the tint is far from it.
TEST(PatchTint, AddPatchesMultipliesEachMapChannelByItsTint) {
  const SyntheticPack bytes = make_synthetic_pack(magnified_options(3));
  PackView pack;
  ASSERT_EQ(open_message(bytes, &pack), "");
  const double factor[3] = {0.75, 1.5, 2.25};
  uint32_t checked[2] = {0, 0};  // level 0, magnified
  double untinted_gap = 0.0;
  for (uint32_t i = 0; i < pack.patch_count(); ++i) {
    const pack::PatchRecord& p = pack.patch(i);
    if (!pack::patch_has_tint(p)) continue;
    ++checked[pack::patch_level(p.flags) > 0 ? 1 : 0];
    const std::vector<double> want = rule_map(pack, i, factor);
    std::vector<double> got(want.size(), 0.0);
    add_patches(pack, i, 1, factor, got.data());
    double scale = 0.0;
    for (double v : want) scale = std::max(scale, std::fabs(v));
    for (size_t k = 0; k < want.size(); ++k)
      ASSERT_NEAR(got[k], want[k], 1e-6 * (1.0 + scale)) << "patch " << i << " value " << k;
    // The rule without the tint: each channel's factor divided by its tint (where not zero).
    double untinted[3];
    for (int c = 0; c < 3; ++c) untinted[c] = p.tint[c] ? factor[c] * 255.0 / p.tint[c] : 0.0;
    untinted_gap = std::max(untinted_gap, max_abs_difference(want, rule_map(pack, i, untinted)));
  }
  EXPECT_GT(checked[0], 5u);
  EXPECT_GT(checked[1], 5u);
  EXPECT_GT(untinted_gap, 0.05) << "the tints do not show";
}

// Every texel of the atlas outside a magnified patch's rectangle set to 255 (then 0): the patch
// draws the same, bit for bit. Control: a reading that does not clamp at the right and bottom
// edges would see the change.
TEST(MagnifiedPatches, AMagnifiedPatchNeverReadsItsAtlasNeighbours) {
  const SyntheticPack bytes = make_synthetic_pack(magnified_options(4));
  PackView pack;
  ASSERT_EQ(open_message(bytes, &pack), "");
  const double factor[3] = {1.0, 0.5, 2.0};
  double unclamped_gap = 0.0;
  uint32_t checked = 0;
  for (uint32_t i = 0; i < pack.patch_count(); ++i) {
    const pack::PatchRecord& p = pack.patch(i);
    const uint32_t level = pack::patch_level(p.flags);
    if (level == 0) continue;
    std::vector<double> base(size_t(pack.map_texels()) * 3, 0.0);
    add_patches(pack, i, 1, factor, base.data());
    const uint32_t aw = pack::patch_atlas_side(p.width, level);
    const uint32_t ah = pack::patch_atlas_side(p.height, level);
    for (const uint8_t fill : {uint8_t(255), uint8_t(0)}) {
      // The atlas data is outside the table checksum: edit a copy of the bytes in place.
      SyntheticPack edited = bytes;
      const size_t at =
          size_t(pack.atlas_pixels(p.atlas) - static_cast<const uint8_t*>(bytes.data()));
      uint8_t* pixels = reinterpret_cast<uint8_t*>(edited.storage.data()) + at;
      const pack::AtlasRecord& a = pack.atlas(p.atlas);
      for (uint32_t y = 0; y < a.height; ++y) {
        for (uint32_t x = 0; x < a.width; ++x) {
          const bool inside =
              x >= p.atlas_x && x < p.atlas_x + aw && y >= p.atlas_y && y < p.atlas_y + ah;
          if (!inside) std::memset(pixels + (size_t(y) * a.width + x) * 4, fill, 4);
        }
      }
      PackView other;
      ASSERT_EQ(open_message(edited, &other), "");
      std::vector<double> got(base.size(), 0.0);
      add_patches(other, i, 1, factor, got.data());
      ASSERT_EQ(std::memcmp(got.data(), base.data(), got.size() * sizeof(double)), 0)
          << "patch " << i << " fill " << int(fill);
      unclamped_gap = std::max(
          unclamped_gap,
          max_abs_difference(rule_map(pack, i, factor, false), rule_map(other, i, factor, false)));
    }
    ++checked;
  }
  EXPECT_GT(checked, 10u);
  EXPECT_GT(unclamped_gap, 0.05) << "no patch's unclamped taps reach a neighbour";
}

// Golden values of magnified.lpk (format version 7 with patches at levels 1 and 2 and tints; a
// pack_load fuzz seed too: tests/fuzz/corpus/pack_load/).
constexpr uint64_t kMagnifiedSize = 37376;
constexpr uint32_t kMagnifiedCrc = 0x09c97d4fu;

TEST(MagnifiedPatches, GoldenBytesAndEveryTruncationRefused) {
  const SyntheticPack built = make_synthetic_pack(magnified_options(3));
  const uint8_t* b = reinterpret_cast<const uint8_t*>(built.data());
  testing::expect_committed_pack(b, built.size, "magnified.lpk", kMagnifiedSize, kMagnifiedCrc);
  testing::expect_truncations_refused(built.data(), built.size);
}

}  // namespace
}  // namespace lightpatch
