// Job names after an edit (cook_jobs.h): an edit changes the names, so re-runs the jobs, of the
// light groups it can change and no other; and a job that keeps its name bakes the same maps, bit
// for bit, in the edited scene, so reusing its old result is exact.
#include <gtest/gtest.h>

#include <bit>
#include <set>

#include "cooker/test_scenes.h"
#include "lightpatch/cooker/cook.h"
#include "lightpatch/cooker/cook_jobs.h"

namespace lightpatch::test {
namespace {

using namespace lightpatch::cooker;

// A 12 m hall: a floor and a back wall (big quads), lamp_a and a crate at the west end, lamp_b
// and a barrel at the east end, a static light over the middle, the brightest (it sets the
// output step). Ranges keep each light's reach to its part of the hall, as in a level whose
// lights each light one corner.
struct Edit {
  float ceiling = 40.0f;  // cd
  glm::vec3 lamp_b{10.0f, 1.5f, 0.5f};
  glm::vec3 static_colour{1.0f, 0.9f, 0.8f};
  glm::vec3 crate_offset{0.0f};
};

Scene hall(const Edit& e) {
  Scene s;
  add_quad(s, {0, 0, -2}, {0, 0, 2}, {12, 0, 2}, {12, 0, -2}, "floor");
  add_quad(s, {0, 0, -2}, {12, 0, -2}, {12, 3, -2}, {0, 3, -2}, "back_wall");
  add_object_box(s, glm::vec3(1.5f, 0.0f, -0.5f) + e.crate_offset,
                 glm::vec3(2.1f, 0.6f, 0.1f) + e.crate_offset, "crate");
  add_object_box(s, {9.7f, 0.0f, -0.6f}, {10.3f, 0.9f, 0.0f}, "barrel");
  Light a = point_light("lamp_a", {2.0f, 1.5f, 0.5f}, 4.0f, true);
  a.range = 3.0f;
  Light b = point_light("lamp_b", e.lamp_b, 4.0f, true);
  b.range = 3.0f;
  Light st = point_light("ceiling", {6.0f, 2.8f, 0.0f}, e.ceiling, false);
  st.range = 3.5f;
  st.color = e.static_colour;
  s.lights = {st, a, b};
  finish(s);
  return s;
}

BakeOptions options(bool indirect, float output_step = 0.0f) {
  BakeOptions o;
  o.quality = Quality::kDraft;
  o.indirect = indirect;
  o.seed = 7;
  o.output_step = output_step;
  return o;
}

struct Cook {
  std::unique_ptr<PreparedScene> p;
  std::unique_ptr<CookJobs> jobs;
};

Cook plan(const Edit& e, bool indirect, float output_step = 0.0f) {
  Progress progress(true);
  Report report;
  LayoutOptions lo;
  lo.lightmap_size = 64;
  Cook c;
  c.p = std::make_unique<PreparedScene>(prepare_scene(hall(e), lo, progress, report));
  c.jobs = std::make_unique<CookJobs>(*c.p, options(indirect, output_step), progress, report);
  return c;
}

// Groups (job indices) whose names differ between two plans of the same light groups.
std::set<size_t> renamed(const Cook& a, const Cook& b) {
  EXPECT_EQ(a.jobs->size(), b.jobs->size());
  std::set<size_t> out;
  for (size_t i = 0; i < a.jobs->size() && i < b.jobs->size(); ++i)
    if (a.jobs->jobs()[i].name != b.jobs->jobs()[i].name) out.insert(i);
  return out;
}

void expect_same_maps(const FloatImage& a, const FloatImage& b, const std::string& what) {
  ASSERT_EQ(a.data.size(), b.data.size()) << what;
  ASSERT_EQ(a.channels, b.channels) << what;
  size_t differ = 0;
  for (size_t i = 0; i < a.data.size(); ++i)
    differ += std::bit_cast<uint32_t>(a.data[i]) != std::bit_cast<uint32_t>(b.data[i]) ? 1 : 0;
  EXPECT_EQ(differ, 0u) << what;
}

// Every job that kept its name bakes the same maps and decisions in both plans.
void expect_kept_jobs_bake_the_same(const Cook& a, const Cook& b) {
  Progress progress(true);
  Report report;
  const std::set<size_t> changed = renamed(a, b);
  for (size_t i = 0; i < a.jobs->size(); ++i) {
    if (changed.count(i)) continue;
    const GroupBake x = a.jobs->run(i, progress, report);
    const GroupBake y = b.jobs->run(i, progress, report);
    const std::string what = "job " + a.jobs->jobs()[i].name;
    expect_same_maps(x.map, y.map, what);
    ASSERT_EQ(x.shadows.size(), y.shadows.size()) << what;
    for (size_t k = 0; k < x.shadows.size(); ++k)
      expect_same_maps(x.shadows[k].map, y.shadows[k].map, what + " shadow");
    ASSERT_EQ(x.static_shadows.size(), y.static_shadows.size()) << what;
    for (size_t k = 0; k < x.static_shadows.size(); ++k)
      expect_same_maps(x.static_shadows[k].map, y.static_shadows[k].map, what + " static shadow");
    ASSERT_EQ(x.pair_corrections.size(), y.pair_corrections.size()) << what;
    ASSERT_EQ(x.decisions.size(), y.decisions.size()) << what;
    for (size_t k = 0; k < x.decisions.size(); ++k) {
      EXPECT_EQ(x.decisions[k].reason, y.decisions[k].reason) << what;
      EXPECT_EQ(x.decisions[k].taken, y.decisions[k].taken) << what;
    }
  }
}

// Job 0: the static lights; 1: lamp_a; 2: lamp_b (scene order of the semi-dynamic lights).
TEST(JobHash, TheSamePlanTwiceGivesTheSameNames) {
  const Cook a = plan(Edit{}, true), b = plan(Edit{}, true);
  ASSERT_EQ(a.jobs->size(), 3u);
  EXPECT_TRUE(renamed(a, b).empty());
  EXPECT_EQ(a.jobs->jobs()[0].label, "static lights");
  EXPECT_EQ(a.jobs->jobs()[2].label, "lamp_b");
}

TEST(JobHash, MovingOneLightRerunsOnlyItsGroup) {
  for (bool indirect : {true, false}) {
    Edit moved;
    moved.lamp_b += glm::vec3(0.4f, -0.2f, 0.2f);
    const Cook a = plan(Edit{}, indirect), b = plan(moved, indirect);
    // The output step (every group's significance) stayed in its quarter octave.
    ASSERT_EQ(a.jobs->session().output_step(), b.jobs->session().output_step());
    EXPECT_EQ(renamed(a, b), (std::set<size_t>{2})) << "indirect " << indirect;
    if (indirect) expect_kept_jobs_bake_the_same(a, b);
  }
}

TEST(JobHash, APinnedOutputStepKeepsTheOtherJobsWhenTheStepWouldMove) {
  // With a dim static light the lamps set the output step; lowered towards the floor, lamp_b
  // moves the scene's 99th percentile into another quarter octave: the significance of every
  // group changes, and every job with it.
  Edit dim;
  dim.ceiling = 6.0f;
  Edit lowered = dim;
  lowered.lamp_b += glm::vec3(0.3f, -0.4f, 0.1f);
  const Cook a = plan(dim, true), b = plan(lowered, true);
  ASSERT_NE(a.jobs->session().output_step(), b.jobs->session().output_step());
  EXPECT_EQ(renamed(a, b), (std::set<size_t>{0, 1, 2}));
  // Pinned (--output-step), only lamp_b's group changes.
  const float step = a.jobs->session().output_step();
  const Cook c = plan(dim, true, step), d = plan(lowered, true, step);
  EXPECT_EQ(renamed(c, d), (std::set<size_t>{2}));
  expect_kept_jobs_bake_the_same(c, d);
}

TEST(JobHash, RecolouringAStaticLightRerunsOnlyTheStaticGroup) {
  Edit recoloured;
  recoloured.static_colour = {0.7f, 0.9f, 1.0f};
  const Cook a = plan(Edit{}, true), b = plan(recoloured, true);
  EXPECT_EQ(renamed(a, b), (std::set<size_t>{0}));
  expect_kept_jobs_bake_the_same(a, b);
}

TEST(JobHash, MovingAnObjectRerunsTheGroupsItInteractsWith) {
  Edit moved;
  moved.crate_offset = {0.25f, 0.0f, 0.1f};
  // Direct light only: the crate is within lamp_a's reach only.
  const Cook a = plan(Edit{}, false), b = plan(moved, false);
  EXPECT_EQ(renamed(a, b), (std::set<size_t>{1}));
  expect_kept_jobs_bake_the_same(a, b);
  // With bounce light every light's bounce reaches the crate and the crate changes every
  // light's bounce (the gather rays cross it): every group re-runs.
  const Cook c = plan(Edit{}, true), d = plan(moved, true);
  EXPECT_EQ(renamed(c, d), (std::set<size_t>{0, 1, 2}));
}

TEST(JobHash, OptionsThatChangeMapsRenameEveryJobAndThreadsDoNot) {
  const Cook a = plan(Edit{}, true);
  Progress progress(true);
  Report report;
  BakeOptions seed = options(true);
  seed.seed = 8;
  const CookJobs other_seed(*a.p, seed, progress, report);
  BakeOptions threads = options(true);
  threads.threads = 1;
  const CookJobs one_thread(*a.p, threads, progress, report);
  for (size_t i = 0; i < a.jobs->size(); ++i) {
    EXPECT_NE(other_seed.jobs()[i].name, a.jobs->jobs()[i].name);
    EXPECT_EQ(one_thread.jobs()[i].name, a.jobs->jobs()[i].name);
  }
}

}  // namespace
}  // namespace lightpatch::test
