// Magnified patches (pack_format.h, "Magnified patches"): what PackView::open accepts and refuses
// (the atlas rectangle is checked with the atlas sides, the destination with width and height).
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/pack_view.h"
#include "runtime/pack_checks.h"
#include "runtime/synthetic_pack.h"

namespace lightpatch {
namespace {

using testing::make_synthetic_pack;
using testing::open_message;
using testing::SyntheticOptions;

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
  PackView view;
  EXPECT_EQ(open_message(with_patch0(1, 0, 31), &view), "");
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
}

}  // namespace
}  // namespace lightpatch
