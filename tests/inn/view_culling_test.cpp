// The game's view culling (samples/inn/src/view_culling.h): conservative, so that culling can
// never remove a triangle the view shows, and not vacuous.
#include <gtest/gtest.h>

#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "view_culling.h"

namespace lightpatch::inn {
namespace {

bool inside_clip(const glm::mat4& vp, glm::vec3 p) {
  const glm::vec4 c = vp * glm::vec4(p, 1.0f);
  return c.w > 0.0f && std::fabs(c.x) <= c.w && std::fabs(c.y) <= c.w && std::fabs(c.z) <= c.w;
}

glm::mat4 random_view(std::mt19937& rng, float far) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const glm::vec3 eye(3.0f * u(rng), 1.0f + u(rng), 3.0f * u(rng));
  glm::vec3 dir(u(rng), 0.5f * u(rng), u(rng));
  if (glm::length(dir) < 0.1f) dir = glm::vec3(1.0f, 0.0f, 0.0f);
  const float fov = glm::radians(60.0f + 40.0f * (u(rng) + 1.0f) * 0.5f);
  return glm::perspective(fov, 1.0f + 0.8f * (u(rng) + 1.0f) * 0.5f, 0.05f, far) *
         glm::lookAt(eye, eye + dir, glm::vec3(0.0f, 1.0f, 0.0f));
}

TEST(ViewCulling, BoxesBeforeBehindAndBesideTheCamera) {
  // At the origin looking down -z, 90 degrees, out to 10 m.
  const glm::mat4 vp = glm::perspective(glm::radians(90.0f), 1.0f, 0.1f, 10.0f) *
                       glm::lookAt(glm::vec3(0.0f), glm::vec3(0, 0, -1), glm::vec3(0, 1, 0));
  EXPECT_TRUE(box_in_view(vp, {-0.5f, -0.5f, -3.0f}, {0.5f, 0.5f, -2.0f}));     // ahead
  EXPECT_FALSE(box_in_view(vp, {-0.5f, -0.5f, 2.0f}, {0.5f, 0.5f, 3.0f}));      // behind
  EXPECT_FALSE(box_in_view(vp, {4.0f, -0.5f, -3.0f}, {5.0f, 0.5f, -2.0f}));     // right of it
  EXPECT_FALSE(box_in_view(vp, {-0.5f, -0.5f, -13.0f}, {0.5f, 0.5f, -12.0f}));  // past far
  EXPECT_TRUE(box_in_view(vp, {-20.0f, -20.0f, -5.0f}, {20.0f, 20.0f, 5.0f}));  // around it
  EXPECT_TRUE(box_in_view(vp, {2.9f, -0.5f, -3.0f}, {3.5f, 0.5f, -2.0f}));      // across an edge
}

TEST(ViewCulling, NoBoxWithAPointInTheViewIsCulled) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  int culled = 0, shown = 0;
  for (int v = 0; v < 200; ++v) {
    const glm::mat4 vp = random_view(rng, 8.0f);
    for (int b = 0; b < 50; ++b) {
      const glm::vec3 lo(-8.0f + 16.0f * u(rng), -2.0f + 6.0f * u(rng), -8.0f + 16.0f * u(rng));
      const glm::vec3 hi =
          lo + glm::vec3(0.05f + 2.0f * u(rng), 0.05f + 2.0f * u(rng), 0.05f + 2.0f * u(rng));
      bool seen = false;
      for (int s = 0; s < 400 && !seen; ++s)
        seen = inside_clip(vp, lo + (hi - lo) * glm::vec3(u(rng), u(rng), u(rng)));
      const bool kept = box_in_view(vp, lo, hi);
      if (seen) {
        EXPECT_TRUE(kept) << "view " << v << " box " << b;
      }
      culled += kept ? 0 : 1;
      shown += seen ? 1 : 0;
    }
  }
  // Not vacuous: most boxes outside a view are culled.
  EXPECT_GT(culled, (10000 - shown) / 2);
  EXPECT_GT(shown, 500);
}

TEST(ViewCulling, ViewsThatShareAPointMeet) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  int apart = 0, sharing = 0;
  for (int k = 0; k < 2000; ++k) {
    const glm::mat4 a = random_view(rng, 6.0f), b = random_view(rng, 6.0f);
    const glm::mat4 inverse = glm::inverse(a);
    bool shared = false;
    for (int s = 0; s < 300 && !shared; ++s) {
      const glm::vec4 c = inverse * glm::vec4(u(rng), u(rng), u(rng), 1.0f);
      shared = inside_clip(b, glm::vec3(c) / c.w);
    }
    const bool meet = views_meet(a, b);
    if (shared) {
      EXPECT_TRUE(meet) << "pair " << k;
    }
    EXPECT_EQ(meet, views_meet(b, a));
    apart += meet ? 0 : 1;
    sharing += shared ? 1 : 0;
  }
  EXPECT_GT(apart, 100);
  EXPECT_GT(sharing, 100);
}

TEST(ViewCulling, TheCubeFaceBehindTheCameraIsNotLookedUp) {
  // A lantern 30 cm left of and below the eye; the camera looks down -z. The cube face looking
  // +z from the lantern (behind the camera) misses the camera's view; the face looking -z meets
  // it.
  const glm::vec3 eye(0.0f, 1.6f, 0.0f), lantern(-0.3f, 1.3f, -0.1f);
  const glm::mat4 camera = glm::perspective(glm::radians(70.0f), 16.0f / 9.0f, 0.05f, 100.0f) *
                           glm::lookAt(eye, eye + glm::vec3(0, 0, -1), glm::vec3(0, 1, 0));
  const glm::mat4 face = glm::perspective(2.0f * std::atan(1.03125f), 1.0f, 0.05f, 1000.0f);
  EXPECT_FALSE(views_meet(
      camera, face * glm::lookAt(lantern, lantern + glm::vec3(0, 0, 1), glm::vec3(0, -1, 0))));
  EXPECT_TRUE(views_meet(
      camera, face * glm::lookAt(lantern, lantern + glm::vec3(0, 0, -1), glm::vec3(0, -1, 0))));
}

}  // namespace
}  // namespace lightpatch::inn
