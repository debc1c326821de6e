// Atlas packing rules: sort order, channel filling (the alpha plane under 3-channel patches),
// atlas sides that are multiples of 4 and at most the maximum, full atlases then a last one sized
// to what is left, no overlaps, the texels wasted against the lower bound, and a layout that does
// not depend on the threads that searched for it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "atlas_packer.h"
#include "lightpatch/cooker/error.h"

namespace lightpatch::cooker {
namespace {

std::vector<PackItem> same(int count, int w, int h, int channels) {
  return std::vector<PackItem>(size_t(count), PackItem{w, h, channels});
}

int64_t atlas_texels(const AtlasLayout& a) {
  int64_t t = 0;
  for (const AtlasSize& s : a.atlases) t += int64_t(s.width) * s.height;
  return t;
}

// Checks that every patch lies inside its atlas, in channels 0..3, and that no two patches share
// a channel-texel; returns the channel-texels the patches cover.
int64_t expect_disjoint(const std::vector<PackItem>& items, const AtlasLayout& a, int max_size) {
  std::vector<std::vector<uint8_t>> used;  // per atlas, per texel: channel bits
  for (const AtlasSize& sz : a.atlases) {
    EXPECT_EQ(sz.width % 4, 0);
    EXPECT_EQ(sz.height % 4, 0);
    EXPECT_LE(sz.width, max_size);
    EXPECT_LE(sz.height, max_size);
    used.emplace_back(size_t(sz.width) * sz.height, 0);
  }
  int64_t covered = 0;
  for (size_t i = 0; i < items.size(); ++i) {
    const Placement& p = a.placements[i];
    EXPECT_GE(p.atlas, 0);
    EXPECT_LT(p.atlas, int(a.atlases.size()));
    if (p.atlas < 0 || p.atlas >= int(a.atlases.size())) return covered;
    const AtlasSize& sz = a.atlases[size_t(p.atlas)];
    EXPECT_GE(p.x, 0);
    EXPECT_GE(p.y, 0);
    EXPECT_LE(p.x + items[i].width, sz.width);
    EXPECT_LE(p.y + items[i].height, sz.height);
    EXPECT_LE(p.channel + items[i].channels, 4);
    if (p.x < 0 || p.y < 0 || p.x + items[i].width > sz.width ||
        p.y + items[i].height > sz.height || p.channel + items[i].channels > 4) {
      return covered;
    }
    const uint8_t bits = uint8_t(((1u << items[i].channels) - 1u) << p.channel);
    for (int y = p.y; y < p.y + items[i].height; ++y) {
      for (int x = p.x; x < p.x + items[i].width; ++x) {
        uint8_t& u = used[size_t(p.atlas)][size_t(y) * sz.width + x];
        EXPECT_EQ(u & bits, 0) << "item " << i << " overlaps at (" << x << "," << y << ")";
        u |= bits;
      }
    }
    covered += int64_t(items[i].width) * items[i].height * items[i].channels;
  }
  return covered;
}

TEST(AtlasPacker, PatchesTouchAndFillEveryChannel) {
  // Sixteen 4x4 grey patches: 256 channel-texels, exactly one 8x8 RGBA atlas's worth (or any
  // other 64-texel shape); no gutter between them.
  const std::vector<PackItem> items = same(16, 4, 4, 1);
  const AtlasLayout a = pack_atlases(items, 64);
  ASSERT_EQ(a.atlases.size(), 1u);
  EXPECT_EQ(atlas_texels(a), 64);
  EXPECT_EQ(expect_disjoint(items, a, 64), 4 * atlas_texels(a));
}

TEST(AtlasPacker, GreyPatchesFillTheAlphaPlaneUnderRgbPatches) {
  // Four 8x8 tinted patches take channels 0-2 of 256 texels; four 8x8 grey ones fit channel 3 of
  // the same texels: no waste.
  std::vector<PackItem> items = same(4, 8, 8, 1);
  for (const PackItem& it : same(4, 8, 8, 3)) items.push_back(it);
  const AtlasLayout a = pack_atlases(items, 64);
  ASSERT_EQ(a.atlases.size(), 1u);
  EXPECT_EQ(atlas_texels(a), 256);
  EXPECT_EQ(expect_disjoint(items, a, 64), 4 * atlas_texels(a));
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(a.placements[i].channel, 3) << i;
  for (size_t i = 4; i < 8; ++i) EXPECT_EQ(a.placements[i].channel, 0) << i;
}

TEST(AtlasPacker, TwoChannelPatchesPairUpAndLeaveTheAlphaPlaneToGreyOnes) {
  // Four 8x8 patches of each channel count: the 2-channel ones pair up in channels 0-1 and 2-3
  // of two rectangles, the 3-channel ones take channels 0-2 of four more, whose alpha plane the
  // grey ones fill: 384 texels, no waste.
  std::vector<PackItem> items = same(4, 8, 8, 1);
  for (const PackItem& it : same(4, 8, 8, 2)) items.push_back(it);
  for (const PackItem& it : same(4, 8, 8, 3)) items.push_back(it);
  const AtlasLayout a = pack_atlases(items, 64);
  ASSERT_EQ(a.atlases.size(), 1u);
  EXPECT_EQ(atlas_texels(a), 384);
  EXPECT_EQ(expect_disjoint(items, a, 64), 4 * atlas_texels(a));
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(a.placements[i].channel, 3) << i;
  for (size_t i = 4; i < 8; ++i) EXPECT_EQ(a.placements[i].channel % 2, 0) << i;
  for (size_t i = 8; i < 12; ++i) EXPECT_EQ(a.placements[i].channel, 0) << i;
}

TEST(AtlasPacker, TallestPatchGoesFirst) {
  const std::vector<PackItem> items = {{2, 2, 1}, {10, 3, 1}, {5, 5, 1}, {4, 4, 3}};
  const AtlasLayout a = pack_atlases(items, 64);
  // Tinted patches first (they need three channels of one rectangle), then the grey ones by
  // height: the 5x5 patch takes the lowest, leftmost place of the alpha plane.
  EXPECT_EQ(a.placements[3].x, 0);
  EXPECT_EQ(a.placements[3].y, 0);
  EXPECT_EQ(a.placements[3].channel, 0);
  EXPECT_EQ(a.placements[2].y, 0);
  expect_disjoint(items, a, 64);
}

TEST(AtlasPacker, FullAtlasesThenOneSizedToTheRest) {
  // 100 grey 6x6 patches at a maximum of 16: a 16x16 atlas holds 4 per channel (12x12 used),
  // so 16 per atlas: six full atlases (trimmed to 12x12) and a smaller seventh for the last 4.
  const std::vector<PackItem> items = same(100, 6, 6, 1);
  const AtlasLayout a = pack_atlases(items, 16);
  ASSERT_EQ(a.atlases.size(), 7u);
  for (size_t i = 0; i + 1 < a.atlases.size(); ++i) {
    EXPECT_EQ(a.atlases[i].width, 12) << i;
    EXPECT_EQ(a.atlases[i].height, 12) << i;
  }
  EXPECT_LT(int64_t(a.atlases.back().width) * a.atlases.back().height, 12 * 12);
  expect_disjoint(items, a, 16);
}

TEST(AtlasPacker, RandomItemsNeverOverlapAndWasteLittle) {
  uint64_t s = 12345;
  auto next = [&](int n) {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return int((s >> 33) % uint64_t(n));
  };
  for (int max_size : {128, 2048}) {
    std::vector<PackItem> items;
    int64_t rgb = 0, channel_texels = 0;
    for (int i = 0; i < 300; ++i) {
      const int kind = next(4);  // a quarter 3-channel, a quarter 2-channel, half grey
      const PackItem it{1 + next(32), 1 + next(32), kind == 0 ? 3 : kind == 1 ? 2 : 1};
      items.push_back(it);
      channel_texels += int64_t(it.width) * it.height * it.channels;
      if (it.channels == 3) rgb += int64_t(it.width) * it.height;
    }
    const AtlasLayout a = pack_atlases(items, max_size);
    EXPECT_EQ(expect_disjoint(items, a, max_size), channel_texels);
    // Against the lower bound (every channel-texel used, or every RGB rectangle apart).
    const int64_t bound = std::max(rgb, (channel_texels + 3) / 4);
    const double over = double(atlas_texels(a)) / double(bound) - 1.0;
    std::printf("max %d: %zu atlases, %.1f %% above the lower bound\n", max_size, a.atlases.size(),
                100.0 * over);
    EXPECT_LE(over, 0.08) << "max " << max_size;
  }
}

TEST(AtlasPacker, SmallPacksTryEveryWidthAndOrder) {
  // The 103 patches of room_soft cooked on a 128 page (`write_test_scene room_soft`, `cook
  // --lightmap-size 128`, preview): the candidate widths in height order alone left 10.7 % of the
  // atlas empty (32x116); trying every width in four orders finds 112x32, 7.5 %. Issue 12's bar
  // for packing waste is 10 %.
  const std::vector<PackItem> items = {
      {6, 11, 1},  {32, 32, 1}, {32, 32, 1}, {6, 25, 1},  {17, 8, 1},  {16, 9, 1},  {16, 16, 1},
      {28, 10, 1}, {8, 8, 1},   {8, 8, 1},   {8, 8, 1},   {8, 8, 1},   {16, 16, 1}, {8, 8, 1},
      {8, 8, 1},   {4, 8, 1},   {8, 4, 1},   {6, 4, 1},   {16, 16, 1}, {16, 16, 1}, {11, 7, 1},
      {16, 16, 1}, {12, 5, 1},  {6, 6, 1},   {4, 4, 1},   {4, 4, 1},   {4, 4, 1},   {4, 4, 1},
      {4, 4, 1},   {11, 5, 1},  {11, 5, 1},  {6, 3, 1},   {2, 2, 1},   {3, 4, 1},   {3, 1, 1},
      {2, 1, 1},   {32, 32, 1}, {15, 32, 1}, {32, 32, 1}, {32, 32, 1}, {15, 16, 1}, {32, 15, 1},
      {16, 15, 1}, {28, 32, 1}, {21, 10, 1}, {8, 10, 1},  {16, 16, 1}, {8, 8, 1},   {2, 1, 1},
      {6, 5, 1},   {8, 8, 1},   {8, 8, 1},   {11, 5, 1},  {1, 5, 1},   {6, 2, 1},   {3, 3, 1},
      {3, 2, 1},   {3, 1, 1},   {16, 16, 1}, {8, 8, 1},   {8, 6, 1},   {16, 5, 1},  {12, 5, 1},
      {12, 9, 1},  {4, 4, 2},   {6, 5, 1},   {2, 2, 1},   {8, 8, 1},   {6, 8, 1},   {2, 2, 1},
      {3, 4, 1},   {2, 4, 1},   {4, 2, 1},   {2, 2, 1},   {3, 1, 1},   {1, 4, 1},   {18, 18, 1},
      {14, 10, 2}, {8, 8, 1},   {8, 8, 1},   {3, 8, 1},   {14, 5, 2},  {6, 6, 2},   {4, 4, 1},
      {4, 4, 1},   {4, 4, 1},   {6, 7, 1},   {8, 5, 1},   {3, 3, 1},   {4, 4, 1},   {1, 2, 1},
      {1, 2, 1},   {3, 1, 1},   {2, 2, 1},   {3, 4, 1},   {2, 3, 1},   {2, 2, 1},   {3, 4, 1},
      {3, 1, 1},   {1, 1, 1},   {1, 1, 1},   {1, 1, 1},   {1, 1, 1}};
  const AtlasLayout a = pack_atlases(items, 2048);
  ASSERT_EQ(a.atlases.size(), 1u);
  const int64_t covered = expect_disjoint(items, a, 2048);
  const double waste = 1.0 - double(covered) / double(4 * atlas_texels(a));
  std::printf("%dx%d, %.1f %% of the atlas empty\n", a.atlases[0].width, a.atlases[0].height,
              100.0 * waste);
  EXPECT_LE(waste, 0.10);
}

TEST(AtlasPacker, LayoutDoesNotDependOnTheThreadCount) {
  uint64_t s = 777;
  auto next = [&](int n) {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return int((s >> 33) % uint64_t(n));
  };
  std::vector<PackItem> items;
  for (int i = 0; i < 200; ++i) items.push_back(PackItem{1 + next(24), 1 + next(24), 1 + next(3)});
  const AtlasLayout one = pack_atlases(items, 256, 1);
  for (int threads : {2, 3}) {
    const AtlasLayout more = pack_atlases(items, 256, threads);
    ASSERT_EQ(more.atlases.size(), one.atlases.size());
    for (size_t k = 0; k < one.atlases.size(); ++k) {
      EXPECT_EQ(more.atlases[k].width, one.atlases[k].width);
      EXPECT_EQ(more.atlases[k].height, one.atlases[k].height);
    }
    for (size_t i = 0; i < items.size(); ++i) {
      EXPECT_EQ(more.placements[i].atlas, one.placements[i].atlas) << i;
      EXPECT_EQ(more.placements[i].x, one.placements[i].x) << i;
      EXPECT_EQ(more.placements[i].y, one.placements[i].y) << i;
      EXPECT_EQ(more.placements[i].channel, one.placements[i].channel) << i;
    }
  }
  expect_disjoint(items, one, 256);
}

TEST(AtlasPacker, RejectsPatchesLargerThanTheMaximumAndBadMaxima) {
  EXPECT_NO_THROW(pack_atlases(same(1, 16, 16, 1), 16));
  EXPECT_THROW(pack_atlases(same(1, 17, 4, 1), 16), CookError);
  EXPECT_THROW(pack_atlases(same(1, 0, 4, 1), 16), CookError);
  EXPECT_NO_THROW(pack_atlases(same(1, 4, 4, 2), 16));
  EXPECT_THROW(pack_atlases(same(1, 4, 4, 4), 16), CookError);
  EXPECT_THROW(pack_atlases(same(1, 4, 4, 1), 12), CookError);  // below the minimum
  EXPECT_THROW(pack_atlases(same(1, 4, 4, 1), 18), CookError);  // not a multiple of 4
}

}  // namespace
}  // namespace lightpatch::cooker
