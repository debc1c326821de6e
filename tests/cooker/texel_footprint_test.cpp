// What a texel stands for (texel_footprint.h): its patch less the cells behind static geometry
// standing on the surface, sampled the same way by the cook and the reference path tracer.
#include <gtest/gtest.h>

#include <bit>

#include "lightpatch/cooker/tracer.h"
#include "test_scenes.h"
#include "texel_footprint.h"

namespace lightpatch::cooker {
namespace {

// A 2 x 2 m floor of 10 x 10 texels (0.2 m) whose column 7 is centred 5 cm before a wall standing
// on the floor at x = 0.5: a quarter of that texel's patch is under the wall.
struct FloorBesideAWall {
  Scene scene;
  TexelSet texels = test::grid_texels(10, 10, {-1.05f, 0, -1}, {2, 0, 0}, {0, 0, 2}, {0, 1, 0});
  explicit FloorBesideAWall(bool wall_is_an_object) {
    test::add_quad(scene, {-1.05f, 0, -1}, {-1.05f, 0, 1}, {0.95f, 0, 1}, {0.95f, 0, -1}, "floor");
    if (wall_is_an_object)
      test::add_object_box(scene, {0.5f, 0, -1}, {0.6f, 1, 1}, "wall");
    else
      test::add_box(scene, {0.5f, 0, -1}, {0.6f, 1, 1}, "wall");
    test::finish(scene);
  }
};

TEST(TexelFootprint, CellsBehindAStaticWallAreNeverSampled) {
  const FloorBesideAWall f(false);
  auto tracer = make_embree_tracer(f.scene);
  const std::vector<TexelFootprint> fp = texel_footprints(f.texels, tracer.get(), 2);
  const size_t beside = f.texels.index(7, 5), open = f.texels.index(3, 5);
  // Cell columns (along x) centred at 0.375, 0.425, 0.475 and 0.525 m: the last is under the wall.
  EXPECT_EQ(std::popcount(unsigned(fp[beside].open)), 12);
  EXPECT_EQ(fp[open].open, 0xFFFF);
  for (int k = 0; k < 256; ++k) {
    const glm::vec3 p = footprint_point(fp[beside], f.texels.position[beside], k, 42);
    EXPECT_LT(p.x, 0.5f) << "point " << k;
    EXPECT_GE(p.x, 0.35f - 1e-5f) << "point " << k;
  }
  // Without the cells, the same points reach under the wall.
  TexelFootprint whole = fp[beside];
  whole.open = 0xFFFF;
  int under = 0;
  for (int k = 0; k < 256; ++k)
    under += footprint_point(whole, f.texels.position[beside], k, 42).x > 0.5f ? 1 : 0;
  EXPECT_GT(under, 40);
}

// A semi-dynamic object closes no cell: the points a texel stands for are the same in every
// state (when the object is hidden, the floor under it is seen).
TEST(TexelFootprint, ObjectsCloseNoCell) {
  const FloorBesideAWall f(true);
  auto tracer = make_embree_tracer(f.scene);
  const std::vector<TexelFootprint> fp = texel_footprints(f.texels, tracer.get(), 1);
  EXPECT_EQ(fp[f.texels.index(7, 5)].open, 0xFFFF);
}

// A texel whose every cell runs into geometry (here a floor texel in a 2 cm slot between two
// walls; in the small inn, corner texels of small props' charts) is its sample point alone: with
// all its cells kept, most of its points lay inside the walls, where the cook's gather rays met
// only back faces and the path tracer's paths were black.
TEST(TexelFootprint, ATexelWithNoOpenCellIsItsSamplePoint) {
  const FloorBesideAWall f(false);
  Scene scene = f.scene;
  test::add_box(scene, {0.34f, 0, -1}, {0.44f, 1, 1}, "other wall");
  test::add_box(scene, {0.46f, 0, -1}, {0.56f, 1, 1}, "slot wall");
  test::finish(scene);
  auto tracer = make_embree_tracer(scene);
  const std::vector<TexelFootprint> fp = texel_footprints(f.texels, tracer.get(), 2);
  const size_t slot = f.texels.index(7, 5), open = f.texels.index(3, 5);
  EXPECT_EQ(fp[slot].a0, 0.0f);
  EXPECT_EQ(fp[slot].a1, 0.0f);
  EXPECT_EQ(fp[slot].b0, 0.0f);
  EXPECT_EQ(fp[slot].b1, 0.0f);
  for (int k = 0; k < 256; ++k) {
    const glm::vec3 p = footprint_point(fp[slot], f.texels.position[slot], k, 42);
    EXPECT_NEAR(p.x, 0.45f, 1e-5f) << "point " << k;
  }
  EXPECT_EQ(fp[open].open, 0xFFFF);
  EXPECT_EQ(fp[open].a0, -0.5f);
  EXPECT_EQ(fp[open].a1, 0.5f);
}

}  // namespace
}  // namespace lightpatch::cooker
