// The Embree tracer: masks select static geometry and semi-dynamic objects per query, blocking
// objects are found in one traversal, occluders are double-sided, epsilon scales with the scene.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <vector>

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

// Random segments through a room with a static pillar and two objects: the batch queries give
// what the single-ray queries give (occluded_many: what intersect with objects finds), ray by ray,
// for any batch length (partial packets included), and count each non-empty ray once.
TEST(Tracer, BatchQueriesMatchSingleRays) {
  Scene s;
  test::add_closed_room(s, {-2, 0, -2}, {2, 3, 2}, 0.1f, "room");
  test::add_box(s, {-0.3f, 0, -0.3f}, {0.3f, 2.5f, 0.3f}, "pillar");
  test::add_object_box(s, {0.8f, 0, 0.8f}, {1.4f, 0.6f, 1.4f}, "crate");
  test::add_object_box(s, {-1.5f, 0, 0.5f}, {-1.0f, 1.0f, 1.2f}, "chest");
  test::finish(s);
  auto tr = make_embree_tracer(s);
  ASSERT_GE(tr->batch_width(), 1);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(-1.9f, 1.9f), height(0.05f, 2.95f), len(0.0f, 6.0f);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  constexpr int kRays = 1003;  // not a multiple of any packet width
  std::vector<Ray> rays(kRays);
  for (int i = 0; i < kRays; ++i) {
    Ray& r = rays[size_t(i)];
    r.origin = glm::vec3(pos(rng), height(rng), pos(rng));
    r.dir = glm::normalize(glm::vec3(gauss(rng), gauss(rng), gauss(rng)));
    r.tmin = tr->epsilon();
    r.tmax = i % 97 == 0 ? 0.0f : len(rng);  // some empty segments
  }
  for (int n : {0, 1, 5, kRays}) {
    for (bool with_objects : {false, true}) {
      std::vector<Hit> hits(size_t(n) + 1);
      hits[size_t(n)].triangle = 12345;  // the batch writes no further than n
      const uint64_t before = tr->rays_traced();
      tr->intersect_many(rays.data(), n, hits.data(), with_objects);
      uint64_t live = 0;
      for (int i = 0; i < n; ++i) live += rays[size_t(i)].tmax > rays[size_t(i)].tmin ? 1 : 0;
      EXPECT_EQ(tr->rays_traced() - before, live);
      EXPECT_EQ(hits[size_t(n)].triangle, 12345);
      int hit_count = 0;
      for (int i = 0; i < n; ++i) {
        const Ray& r = rays[size_t(i)];
        const Hit one = tr->intersect(r.origin, r.dir, r.tmin, r.tmax, with_objects);
        const Hit& many = hits[size_t(i)];
        ASSERT_EQ(many.hit, one.hit) << "ray " << i;
        if (!one.hit) continue;
        ++hit_count;
        EXPECT_EQ(many.mesh, one.mesh) << "ray " << i;
        EXPECT_EQ(many.triangle, one.triangle) << "ray " << i;
        EXPECT_NEAR(many.t, one.t, 1e-5f * (1.0f + one.t)) << "ray " << i;
        EXPECT_NEAR(many.u, one.u, 1e-4f);
        EXPECT_NEAR(many.v, one.v, 1e-4f);
        EXPECT_EQ(many.geometric_normal, one.geometric_normal);
      }
      if (n == kRays) {
        EXPECT_GT(hit_count, kRays / 4);  // the comparison saw many hits
      }
    }
    std::vector<uint8_t> any(size_t(n) + 1, 7);
    tr->occluded_many(rays.data(), n, any.data());
    EXPECT_EQ(any[size_t(n)], 7);
    for (int i = 0; i < n; ++i) {
      const Ray& r = rays[size_t(i)];
      ASSERT_EQ(any[size_t(i)], tr->intersect(r.origin, r.dir, r.tmin, r.tmax, true).hit ? 1 : 0)
          << "ray " << i;
    }
    std::vector<uint8_t> blocked(size_t(n) + 1, 7);
    tr->occluded_static_many(rays.data(), n, blocked.data());
    EXPECT_EQ(blocked[size_t(n)], 7);
    int count = 0;
    for (int i = 0; i < n; ++i) {
      const Ray& r = rays[size_t(i)];
      const bool one = tr->occluded_static(r.origin, r.dir, r.tmin, r.tmax);
      ASSERT_EQ(blocked[size_t(i)], one ? 1 : 0) << "ray " << i;
      count += one ? 1 : 0;
    }
    if (n == kRays) {
      EXPECT_GT(count, kRays / 4);
      EXPECT_LT(count, kRays * 3 / 4);  // both answers occur
    }
    // shadow_query_many: shadow_query's answer and objects (in any order) per ray, counted alike.
    constexpr int kMax = 2;
    std::vector<int> counts(size_t(n) + 1, 7), objects(size_t(n) * kMax + 1, 7);
    const uint64_t before = tr->rays_traced();
    tr->shadow_query_many(rays.data(), n, counts.data(), objects.data(), kMax);
    const uint64_t counted = tr->rays_traced() - before;
    EXPECT_EQ(counts[size_t(n)], 7);
    EXPECT_EQ(objects[size_t(n) * kMax], 7);
    int crossing = 0;
    for (int i = 0; i < n; ++i) {
      const Ray& r = rays[size_t(i)];
      int one[kMax] = {-1, -1};
      const int k = tr->shadow_query(r.origin, r.dir, r.tmin, r.tmax, one, kMax);
      ASSERT_EQ(counts[size_t(i)], k) << "ray " << i;
      const int* many = objects.data() + size_t(i) * kMax;
      for (int j = 0; j < k; ++j)
        EXPECT_NE(std::find(many, many + k, one[j]), many + k) << "ray " << i;
      crossing += k > 0 ? 1 : 0;
    }
    EXPECT_EQ(counted, tr->rays_traced() - before - counted);  // as many as the singles counted
    if (n == kRays) {
      EXPECT_GT(crossing, 10);  // rays that cross objects were compared
    }
  }
}

// Shadow rays as the direct pass makes them: bundles leaving a texel's patch (5 cm) for a light
// sphere (30 cm). shadow_query_many bounds each bundle before it tests objects; the rays whose
// bundle's centre line misses an object by less than the bundle's spread must still find it.
TEST(Tracer, ShadowBundlesFindTheObjectsTheirRaysGraze) {
  Scene s;
  test::add_closed_room(s, {-2, 0, -2}, {2, 3, 2}, 0.1f, "room");
  test::add_object_box(s, {0.8f, 0, 0.8f}, {1.4f, 0.6f, 1.4f}, "crate");
  test::add_object_box(s, {-1.5f, 0, 0.5f}, {-1.0f, 1.0f, 1.2f}, "chest");
  test::add_object_box(s, {-0.2f, 1.0f, -0.2f}, {0.2f, 1.05f, 0.2f}, "plate");  // thin
  test::finish(s);
  auto tr = make_embree_tracer(s);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> pos(-1.9f, 1.9f), height(0.05f, 2.95f), unit(-1.0f, 1.0f);
  auto ball = [&](float r) {
    glm::vec3 v;
    do v = glm::vec3(unit(rng), unit(rng), unit(rng));
    while (glm::dot(v, v) > 1.0f);
    return v * r;
  };
  constexpr int kMax = 3, kBundle = 61;  // a chunk and a partial one
  int grazing = 0;  // bundles whose centre line misses every object while a ray crosses one
  for (int bundle = 0; bundle < 400; ++bundle) {
    const glm::vec3 a(pos(rng), height(rng), pos(rng)), b(pos(rng), height(rng), pos(rng));
    std::vector<Ray> rays(kBundle);
    for (Ray& r : rays) {
      const glm::vec3 o = a + ball(0.05f), e = b + ball(0.3f);
      r.origin = o;
      r.tmax = glm::length(e - o);
      r.dir = (e - o) / r.tmax;
      r.tmin = tr->epsilon();
    }
    if (bundle % 50 == 0) rays[3].tmax = std::numeric_limits<float>::infinity();  // a sun's
    if (bundle % 50 == 1) std::fill(rays.begin(), rays.end(), rays[0]);  // one point, one end
    std::vector<int> counts(kBundle), objects(size_t(kBundle) * kMax);
    tr->shadow_query_many(rays.data(), kBundle, counts.data(), objects.data(), kMax);
    bool crossing = false;
    for (int i = 0; i < kBundle; ++i) {
      const Ray& r = rays[size_t(i)];
      int one[kMax] = {-1, -1, -1};
      const int k = tr->shadow_query(r.origin, r.dir, r.tmin, r.tmax, one, kMax);
      ASSERT_EQ(counts[size_t(i)], k) << "bundle " << bundle << " ray " << i;
      const int* many = objects.data() + size_t(i) * kMax;
      for (int j = 0; j < k; ++j) EXPECT_NE(std::find(many, many + k, one[j]), many + k);
      crossing = crossing || k > 0;
    }
    int centre[kMax];
    const glm::vec3 ab = b - a;
    if (crossing &&
        tr->shadow_query(a, glm::normalize(ab), 0.0f, glm::length(ab), centre, kMax) == 0)
      ++grazing;
  }
  EXPECT_GT(grazing, 10);  // the bound's spread was needed, and checked
}

}  // namespace
}  // namespace lightpatch::cooker
