// Atlas packing rules (thesis §4.1.5): sort order, channel filling, growth vs a new atlas, no
// overlaps, gutters inside the atlas.
#include <gtest/gtest.h>

#include <vector>

#include "atlas_packer.h"
#include "lightpatch/cooker/error.h"

namespace lightpatch::cooker {
namespace {

std::vector<PackItem> same(int count, int w, int h, int channels) {
  return std::vector<PackItem>(size_t(count), PackItem{w, h, channels});
}

TEST(AtlasPacker, FillsAChannelBeforeOpeningTheNext) {
  // 6x6 patches are 8x8 with their gutter: four per channel of a 16x16 atlas. 16 patches need
  // all four channels; S_l = 16*64 is not more than 2*S_a = 2*1024, so the atlas does not grow.
  const AtlasLayout a = pack_atlases(same(16, 6, 6, 1), 64);
  ASSERT_EQ(a.atlases.size(), 1u);
  EXPECT_EQ(a.atlases[0].width, 16);
  EXPECT_EQ(a.atlases[0].height, 16);
  for (size_t i = 0; i < 16; ++i) EXPECT_EQ(a.placements[i].channel, int(i / 4)) << i;
}

TEST(AtlasPacker, OpensANewAtlasWhenTheRestIsSmall) {
  // The 17th patch does not fit; S_l = 64 < 2*S_a: a second atlas, not a 4x larger first one.
  const AtlasLayout a = pack_atlases(same(17, 6, 6, 1), 64);
  ASSERT_EQ(a.atlases.size(), 2u);
  EXPECT_EQ(a.atlases[0].width, 16);
  EXPECT_EQ(a.placements[16].atlas, 1);
  EXPECT_EQ(a.atlases[1].width, 16);
  EXPECT_EQ(a.atlases[1].height, 8);  // unused rows trimmed to a power of two
}

TEST(AtlasPacker, GrowsWhenTheRestIsLarge) {
  // 64 patches: when the 16x16 atlas is full, S_l = 48*64 > 2*S_a = 2048: it doubles to 32x32,
  // which holds all of them.
  const AtlasLayout a = pack_atlases(same(64, 6, 6, 1), 64);
  ASSERT_EQ(a.atlases.size(), 1u);
  EXPECT_EQ(a.atlases[0].width, 32);
  EXPECT_EQ(a.atlases[0].height, 32);
}

TEST(AtlasPacker, StopsGrowingAtTheMaximumSize) {
  const AtlasLayout a = pack_atlases(same(80, 6, 6, 1), 16);
  EXPECT_EQ(a.atlases.size(), 5u);
  for (const AtlasSize& s : a.atlases) EXPECT_LE(s.width, 16);
}

TEST(AtlasPacker, ThreeChannelPatchesComeFirstAndTakeRgb) {
  std::vector<PackItem> items = same(3, 6, 6, 1);
  items.push_back(PackItem{6, 6, 3});
  const AtlasLayout a = pack_atlases(items, 64);
  EXPECT_EQ(a.placements[3].channel, 0);
  EXPECT_EQ(a.placements[3].x, 1);  // placed first: the top-left corner
  EXPECT_EQ(a.placements[3].y, 1);
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(a.placements[size_t(i)].channel, 0);  // channel 0 still has room
}

TEST(AtlasPacker, SortsBySizeDescending) {
  std::vector<PackItem> items = {{2, 2, 1}, {10, 3, 1}, {5, 5, 1}};
  const AtlasLayout a = pack_atlases(items, 64);
  // The largest (max side 10) goes to the top-left corner.
  EXPECT_EQ(a.placements[1].x, 1);
  EXPECT_EQ(a.placements[1].y, 1);
}

TEST(AtlasPacker, RandomItemsNeverOverlapAndStayInside) {
  uint64_t s = 12345;
  auto next = [&](int n) {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return int((s >> 33) % uint64_t(n));
  };
  std::vector<PackItem> items;
  for (int i = 0; i < 300; ++i)
    items.push_back(PackItem{1 + next(40), 1 + next(40), next(3) == 0 ? 3 : 1});
  const AtlasLayout a = pack_atlases(items, 128);
  std::vector<std::vector<uint8_t>> used;  // per atlas, per texel: channel bits
  for (const AtlasSize& sz : a.atlases) used.emplace_back(size_t(sz.width) * sz.height, 0);
  for (size_t i = 0; i < items.size(); ++i) {
    const Placement& p = a.placements[i];
    const AtlasSize& sz = a.atlases[size_t(p.atlas)];
    ASSERT_GE(p.x - 1, 0);
    ASSERT_GE(p.y - 1, 0);
    ASSERT_LE(p.x + items[i].width + 1, sz.width);
    ASSERT_LE(p.y + items[i].height + 1, sz.height);
    ASSERT_LE(p.channel + items[i].channels, 4);
    const uint8_t bits = uint8_t(((1u << items[i].channels) - 1u) << p.channel);
    for (int y = p.y - 1; y < p.y + items[i].height + 1; ++y) {
      for (int x = p.x - 1; x < p.x + items[i].width + 1; ++x) {
        uint8_t& u = used[size_t(p.atlas)][size_t(y) * sz.width + x];
        ASSERT_EQ(u & bits, 0) << "item " << i << " overlaps at (" << x << "," << y << ")";
        u |= bits;
      }
    }
  }
}

TEST(AtlasPacker, RejectsPatchesLargerThanTheMaximum) {
  EXPECT_THROW(pack_atlases(same(1, 15, 15, 1), 16), CookError);
  EXPECT_THROW(pack_atlases(same(1, 4, 4, 1), 12), CookError);
}

}  // namespace
}  // namespace lightpatch::cooker
