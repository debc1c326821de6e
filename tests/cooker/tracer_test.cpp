// The Embree tracer: masks select static geometry and semi-dynamic objects per query, blocking
// objects are found in one traversal, occluders are double-sided, epsilon scales with the scene.
#include <gtest/gtest.h>

#include "lightpatch/cooker/tracer.h"
#include "test_scenes.h"

namespace lightpatch::cooker {
namespace {

// A static wall at x = 5 and two objects on the +x axis at x = 1 and x = 3.
Scene line_scene() {
  Scene s;
  test::add_box(s, {5, -1, -1}, {6, 1, 1}, "wall");
  test::add_object_box(s, {0.5f, -0.5f, -0.5f}, {1.5f, 0.5f, 0.5f}, "first");
  test::add_object_box(s, {2.5f, -0.5f, -0.5f}, {3.5f, 0.5f, 0.5f}, "second");
  test::finish(s);
  return s;
}

TEST(Tracer, MasksSelectStaticAndObjects) {
  const Scene s = line_scene();
  auto tr = make_embree_tracer(s);
  const glm::vec3 o(0, 0, 0), d(1, 0, 0);
  const Hit with = tr->intersect(o, d, 0.0f, 100.0f, true);
  ASSERT_TRUE(with.hit);
  EXPECT_NEAR(with.t, 0.5f, 1e-5f);
  EXPECT_EQ(with.mesh, 1);
  const Hit without = tr->intersect(o, d, 0.0f, 100.0f, false);
  ASSERT_TRUE(without.hit);
  EXPECT_NEAR(without.t, 5.0f, 1e-5f);
  EXPECT_EQ(without.mesh, 0);
  EXPECT_NEAR(std::fabs(without.geometric_normal.x), 1.0f, 1e-5f);
  EXPECT_TRUE(tr->occluded_static(o, d, 0.0f, 100.0f));
  EXPECT_FALSE(tr->occluded_static(o, d, 0.0f, 4.9f));  // objects never occlude statically
}

TEST(Tracer, BlockingObjectsFindsEveryObjectOnce) {
  const Scene s = line_scene();
  auto tr = make_embree_tracer(s);
  int out[4] = {-1, -1, -1, -1};
  const int n = tr->blocking_objects({0, 0, 0}, {1, 0, 0}, 0.0f, 100.0f, out, 4);
  ASSERT_EQ(n, 2);
  EXPECT_TRUE((out[0] == 0 && out[1] == 1) || (out[0] == 1 && out[1] == 0));
  EXPECT_EQ(tr->blocking_objects({0, 0, 0}, {1, 0, 0}, 0.0f, 2.0f, out, 4), 1);
  EXPECT_EQ(out[0], 0);
  EXPECT_EQ(tr->blocking_objects({0, 0, 0}, {1, 0, 0}, 0.0f, 100.0f, out, 1), 1);
  EXPECT_EQ(tr->blocking_objects({0, 2, 0}, {1, 0, 0}, 0.0f, 100.0f, out, 4), 0);
  // One traversal: static blocker -> -1, else the objects.
  EXPECT_EQ(tr->shadow_query({0, 0, 0}, {1, 0, 0}, 0.0f, 100.0f, out, 4), -1);
  EXPECT_EQ(tr->shadow_query({0, 0, 0}, {1, 0, 0}, 0.0f, 4.0f, out, 4), 2);
  EXPECT_EQ(tr->shadow_query({-3, 0, 0}, {-1, 0, 0}, 0.0f, 4.0f, out, 4), 0);
  EXPECT_GT(tr->rays_traced(), 0u);
}

TEST(Tracer, OccludersAreDoubleSided) {
  Scene s;
  // A quad facing +y; rays from above and from below both hit it.
  test::add_quad(s, {-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}, "sheet");
  test::finish(s);
  auto tr = make_embree_tracer(s);
  EXPECT_TRUE(tr->occluded_static({0, 1, 0}, {0, -1, 0}, 0.0f, 2.0f));
  EXPECT_TRUE(tr->occluded_static({0, -1, 0}, {0, 1, 0}, 0.0f, 2.0f));
}

TEST(Tracer, EpsilonScalesWithTheScene) {
  Scene tiny, huge;
  test::add_box(tiny, {0, 0, 0}, {1e-3f, 1e-3f, 1e-3f}, "tiny");
  test::add_box(huge, {0, 0, 0}, {1e4f, 1e2f, 1e4f}, "terrain");
  test::finish(tiny);
  test::finish(huge);
  auto a = make_embree_tracer(tiny);
  auto b = make_embree_tracer(huge);
  EXPECT_GT(a->epsilon(), 0.0f);
  EXPECT_LT(a->epsilon(), 1e-6f);
  EXPECT_GT(b->epsilon(), 1e-2f);
  EXPECT_LT(b->epsilon(), 1.0f);
  // A ray leaving each box's top face by epsilon does not hit its own face.
  EXPECT_FALSE(a->occluded_static({5e-4f, 1e-3f + a->epsilon(), 5e-4f}, {0, 1, 0}, 0.0f, 1.0f));
  EXPECT_FALSE(b->occluded_static({5e3f, 1e2f + b->epsilon(), 5e3f}, {0, 1, 0}, 0.0f, 1e4f));
  EXPECT_TRUE(b->occluded_static({5e3f, 1e2f + b->epsilon(), 5e3f}, {0, -1, 0}, 0.0f, 1e4f));
}

}  // namespace
}  // namespace lightpatch::cooker
