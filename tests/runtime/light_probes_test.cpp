// LightProbes (light_probes.h): incremental updates against rebuilds and against an independent
// double-precision sum of pack_format.h's formula; a light switched off or an object hidden
// changes exactly the probes its sets reach; the grid query against closed forms (a field linear
// in position, a corner behind a short reach, the fallbacks); no allocation per update or query.
#include "lightpatch/light_probes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <set>
#include <vector>

#include "lightpatch/planner.h"
#include "lightpatch/scene_state.h"
#include "runtime/map_reference.h"
#include "runtime/synthetic_pack.h"
#include "support/counters.h"

namespace lightpatch {
namespace {

using testing::make_synthetic_pack;
using testing::SyntheticOptions;
using testing::SyntheticPack;

SyntheticOptions probe_options(uint32_t seed = 1) {
  SyntheticOptions o;
  o.lights = 4;
  return testing::with_probe_grid(o, 4, 3, 3, seed);
}

// Every probe's SH for `st` written from pack_format.h's sum (not group_rules.h), in double, and
// per coefficient the sum of the magnitudes of its terms (the scale of its rounding).
void reference(const PackView& v, const SceneState& st, std::vector<double>* value,
               std::vector<double>* magnitude) {
  value->assign(size_t(v.probe_count()) * kProbeShFloats, 0.0);
  magnitude->assign(value->size(), 0.0);
  for (uint32_t s = 0; s < v.probe_set_count(); ++s) {
    const pack::ProbeSetRecord& set = v.probe_set(s);
    double f[3] = {0, 0, 0};
    auto light = [&](double sign) {
      const LightState& l = st.light(set.light);
      for (int c = 0; c < 3; ++c) f[c] = l.on ? sign * double(l.color[c]) * l.intensity : 0.0;
    };
    switch (set.kind) {
      case pack::kGroupBase:
        f[0] = f[1] = f[2] = 1.0;
        break;
      case pack::kGroupContribution:
        light(1.0);
        break;
      case pack::kGroupShadow:
        if (st.object_visible(set.object_a)) light(-1.0);
        break;
      case pack::kGroupStaticShadow:
        if (st.object_visible(set.object_a)) f[0] = f[1] = f[2] = -1.0;
        break;
      default:
        ADD_FAILURE() << "unexpected set kind " << set.kind;
    }
    for (uint32_t e = set.first_entry; e < set.first_entry + set.entry_count; ++e) {
      const pack::ProbeEntry& pe = v.probe_entry(e);
      for (uint32_t i = 0; i < kProbeShFloats; ++i) {
        const double term = f[i % 3] * double(pe.sh[i]);
        (*value)[size_t(pe.probe) * kProbeShFloats + i] += term;
        (*magnitude)[size_t(pe.probe) * kProbeShFloats + i] += std::fabs(term);
      }
    }
  }
}

// A random change of one light (on, colour, intensity) or one object's visibility.
void random_change(std::mt19937& rng, SceneState* st) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const uint32_t pick = rng() % 4;
  if (pick == 0 && st->object_count() > 0) {
    const uint32_t o = rng() % st->object_count();
    ASSERT_EQ(st->set_object_visible(o, !st->object_visible(o)), Status::kOk);
    return;
  }
  const uint32_t l = rng() % st->light_count();
  if (pick == 1) {
    ASSERT_EQ(st->set_light_on(l, !st->light(l).on), Status::kOk);
  } else if (pick == 2) {
    const float rgb[3] = {u(rng), u(rng), u(rng)};
    ASSERT_EQ(st->set_light_color(l, rgb), Status::kOk);
  } else {
    ASSERT_EQ(st->set_light_intensity(l, 4.0f * u(rng)), Status::kOk);
  }
}

TEST(LightProbes, IncrementalUpdatesEqualRebuildsAndTheReferenceSum) {
  for (uint32_t seed : {1u, 2u}) {
    const SyntheticPack bytes = make_synthetic_pack(probe_options(seed));
    PackView v;
    ASSERT_TRUE(bytes.open(&v, nullptr));
    SceneState st;
    ASSERT_EQ(st.init(v, nullptr), Status::kOk);
    LightProbes incremental, rebuilt;
    ASSERT_EQ(incremental.init(v, nullptr), Status::kOk);
    ASSERT_EQ(rebuilt.init(v, nullptr), Status::kOk);
    ASSERT_GT(incremental.probe_count(), 30u);
    std::mt19937 rng(seed);
    std::vector<double> want, magnitude;
    uint64_t total = 0;
    for (int step = 0; step < 300; ++step) {
      if (step > 0) random_change(rng, &st);
      ASSERT_EQ(incremental.update(st), Status::kOk);
      total += incremental.stats().entries_last_update;
      ASSERT_EQ(rebuilt.rebuild(st), Status::kOk);
      reference(v, st, &want, &magnitude);
      for (uint32_t p = 0; p < v.probe_count(); ++p) {
        float a[kProbeShFloats], b[kProbeShFloats];
        incremental.probe_sh(p, a);
        rebuilt.probe_sh(p, b);
        for (uint32_t i = 0; i < kProbeShFloats; ++i) {
          const double w = want[size_t(p) * kProbeShFloats + i];
          const double tol = 1e-6 * magnitude[size_t(p) * kProbeShFloats + i] + 1e-30;
          ASSERT_NEAR(a[i], w, tol) << "seed " << seed << " step " << step << " probe " << p;
          ASSERT_NEAR(b[i], w, tol) << "seed " << seed << " step " << step << " probe " << p;
        }
      }
    }
    EXPECT_EQ(incremental.stats().entries_total, total);
    // The state has not changed since: nothing to do.
    ASSERT_EQ(incremental.update(st), Status::kOk);
    EXPECT_EQ(incremental.stats().entries_last_update, 0u);
    EXPECT_EQ(incremental.stats().sets_changed_last_update, 0u);
    // A rebuild touches at most every entry; the per-probe costs add up to the entries.
    EXPECT_LE(rebuilt.stats().entries_last_update, rebuilt.stats().rebuild_entries);
    EXPECT_EQ(rebuilt.stats().rebuild_entries, v.probe_entry_count());
    uint64_t per_probe = 0;
    uint32_t most = 0;
    for (uint32_t p = 0; p < v.probe_count(); ++p) {
      per_probe += incremental.probe_entries(p);
      most = std::max(most, incremental.probe_entries(p));
    }
    EXPECT_EQ(per_probe, v.probe_entry_count());
    EXPECT_EQ(incremental.stats().max_entries_per_probe, most);
  }
}

// A game with a Runtime updates the probes from its planner: they follow the presented state
// (what the light map shows), not the wanted one, so a lit thing changes in the frame its room
// does, however many frames the change takes.
TEST(LightProbes, FollowThePlannersPresentedStateNotTheWanted) {
  const SyntheticPack bytes = make_synthetic_pack(probe_options(5));
  PackView v;
  Error error;
  ASSERT_TRUE(bytes.open(&v, &error)) << error.message;
  Planner planner;
  ASSERT_EQ(planner.init(v, PlannerLimits(), &error), Status::kOk) << error.message;
  testing::CpuMapSink sink(v, testing::Rounding::kNone);
  LightProbes probes;
  SceneState shown;
  ASSERT_EQ(probes.init(v, &error), Status::kOk) << error.message;
  ASSERT_EQ(shown.init(v, &error), Status::kOk) << error.message;
  ASSERT_EQ(probes.update(planner), Status::kOk);  // nothing presented yet: nothing applied
  EXPECT_EQ(probes.stats().entries_last_update, 0u);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<double> value, magnitude;
  int lagging = 0, checked = 0;
  for (int frame = 0; frame < 300; ++frame) {
    if (rng() % 3 == 0) {
      if (rng() % 3 == 0) {
        const uint32_t o = rng() % v.object_count();
        ASSERT_EQ(planner.set_object_visible(o, !planner.object_visible(o)), Status::kOk);
      } else {
        const float c[3] = {u(rng), u(rng), u(rng)};
        ASSERT_EQ(planner.set_light(rng() % v.light_count(), u(rng) < 0.7f, c, 4.0f * u(rng)),
                  Status::kOk);
      }
    }
    planner.update(200, sink);
    ASSERT_EQ(probes.update(planner), Status::kOk);
    if (!planner.map_ready()) continue;
    // The presented state as a SceneState: each light at its shown factor.
    for (uint32_t l = 0; l < v.light_count(); ++l) {
      LightState ls{true, {0, 0, 0}, 1.0f};
      planner.shown_factor(l, ls.color);
      ASSERT_EQ(shown.set_light(l, ls), Status::kOk);
    }
    for (uint32_t o = 0; o < v.object_count(); ++o)
      ASSERT_EQ(shown.set_object_visible(o, planner.shown_visible(o)), Status::kOk);
    reference(v, shown, &value, &magnitude);
    for (uint32_t p = 0; p < v.probe_count(); ++p) {
      float sh[kProbeShFloats];
      probes.probe_sh(p, sh);
      for (uint32_t i = 0; i < kProbeShFloats; ++i) {
        const size_t k = size_t(p) * kProbeShFloats + i;
        ASSERT_NEAR(sh[i], value[k], 1e-5 * magnitude[k] + 1e-7) << "frame " << frame;
      }
    }
    ++checked;
    lagging += planner.stats().pending_changes > 0 ? 1 : 0;
  }
  EXPECT_GT(checked, 200);
  EXPECT_GT(lagging, 20) << "no change took more than a frame: the test shows nothing";
}

// The probes whose SH differs bit for bit between two snapshots.
std::set<uint32_t> changed(const LightProbes& probes, const std::vector<float>& before) {
  std::set<uint32_t> out;
  for (uint32_t p = 0; p < probes.probe_count(); ++p) {
    float sh[kProbeShFloats];
    probes.probe_sh(p, sh);
    if (std::memcmp(sh, before.data() + size_t(p) * kProbeShFloats, sizeof sh) != 0) out.insert(p);
  }
  return out;
}
std::vector<float> snapshot(const LightProbes& probes) {
  std::vector<float> out(size_t(probes.probe_count()) * kProbeShFloats);
  for (uint32_t p = 0; p < probes.probe_count(); ++p)
    probes.probe_sh(p, out.data() + size_t(p) * kProbeShFloats);
  return out;
}

TEST(LightProbes, ALightSwitchedOffChangesTheProbesItReachedAndNoOthers) {
  SyntheticOptions o = probe_options(5);
  o.probe_reach_probability = 0.3f;  // lights that reach some probes, not all
  const SyntheticPack bytes = make_synthetic_pack(o);
  PackView v;
  ASSERT_TRUE(bytes.open(&v, nullptr));
  SceneState st;
  ASSERT_EQ(st.init(v, nullptr), Status::kOk);
  ASSERT_EQ(st.set_object_visible(1, false), Status::kOk);
  LightProbes probes;
  ASSERT_EQ(probes.init(v, nullptr), Status::kOk);
  ASSERT_EQ(probes.update(st), Status::kOk);
  for (uint32_t l = 0; l < v.light_count(); ++l) {
    // The probes of l's contribution and of its shadows of visible objects.
    std::set<uint32_t> reached;
    uint64_t entries = 0;
    for (uint32_t s = 0; s < v.probe_set_count(); ++s) {
      const pack::ProbeSetRecord& set = v.probe_set(s);
      const bool counts =
          set.light == l && (set.kind == pack::kGroupContribution ||
                             (set.kind == pack::kGroupShadow && st.object_visible(set.object_a)));
      if (!counts) continue;
      entries += set.entry_count;
      for (uint32_t e = set.first_entry; e < set.first_entry + set.entry_count; ++e)
        reached.insert(v.probe_entry(e).probe);
    }
    ASSERT_FALSE(reached.empty());
    ASSERT_LT(reached.size(), v.probe_count()) << "light " << l << " reaches every probe";
    const std::vector<float> before = snapshot(probes);
    ASSERT_EQ(st.set_light_on(l, false), Status::kOk);
    ASSERT_EQ(probes.update(st), Status::kOk);
    EXPECT_EQ(changed(probes, before), reached) << "light " << l;
    EXPECT_EQ(probes.stats().entries_last_update, entries);
    ASSERT_EQ(st.set_light_on(l, true), Status::kOk);
    ASSERT_EQ(probes.update(st), Status::kOk);
  }
  // Hiding object 0 changes the probes of its shadow and static-shadow sets (lights on).
  std::set<uint32_t> shadowed;
  for (uint32_t s = 0; s < v.probe_set_count(); ++s) {
    const pack::ProbeSetRecord& set = v.probe_set(s);
    if ((set.kind == pack::kGroupShadow || set.kind == pack::kGroupStaticShadow) &&
        set.object_a == 0) {
      for (uint32_t e = set.first_entry; e < set.first_entry + set.entry_count; ++e)
        shadowed.insert(v.probe_entry(e).probe);
    }
  }
  ASSERT_FALSE(shadowed.empty());
  const std::vector<float> before = snapshot(probes);
  ASSERT_EQ(st.set_object_visible(0, false), Status::kOk);
  ASSERT_EQ(probes.update(st), Status::kOk);
  EXPECT_EQ(changed(probes, before), shadowed);
}

// A field linear in position in the base set's entries, nothing in the others.
void linear_field(const float p[3], float sh[kProbeShFloats]) {
  for (uint32_t i = 0; i < kProbeShFloats; ++i)
    sh[i] = 0.3f * float(i) - 2.0f + (0.5f + 0.1f * float(i)) * p[0] - 0.7f * p[1] +
            (1.0f - 0.05f * float(i)) * p[2];
}

SyntheticOptions linear_options() {
  SyntheticOptions o = probe_options(9);
  o.probe_hole_probability = 0.0f;
  o.named_probes = 0;
  o.probe_reach = 2.0f * o.probe_spacing;
  o.probe_sh = [](const pack::ProbeRecord& probe, const pack::ProbeSetRecord& set, float* sh) {
    if (set.kind == pack::kGroupBase)
      linear_field(probe.position, sh);
    else
      for (uint32_t i = 0; i < kProbeShFloats; ++i) sh[i] = 0.0f;
  };
  return o;
}

struct Loaded {
  SyntheticPack bytes;
  PackView view;
  SceneState state;
  LightProbes probes;
  explicit Loaded(const SyntheticOptions& o) : bytes(make_synthetic_pack(o)) {
    EXPECT_TRUE(bytes.open(&view, nullptr));
    EXPECT_EQ(state.init(view, nullptr), Status::kOk);
    EXPECT_EQ(probes.init(view, nullptr), Status::kOk);
    EXPECT_EQ(probes.update(state), Status::kOk);
  }
};

void expect_field(const float got[kProbeShFloats], const float at[3], const char* what) {
  float want[kProbeShFloats];
  linear_field(at, want);
  for (uint32_t i = 0; i < kProbeShFloats; ++i)
    EXPECT_NEAR(got[i], want[i], 1e-5f * (1.0f + std::fabs(want[i])))
        << what << " at " << at[0] << "," << at[1] << "," << at[2] << " coefficient " << i;
}

TEST(LightProbes, SampleReproducesALinearFieldInsideAndClampsOutside) {
  Loaded l(linear_options());
  const pack::ProbeGridRecord& g = l.view.probe_grid();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int n = 0; n < 200; ++n) {
    float pos[3], sh[kProbeShFloats];
    for (int a = 0; a < 3; ++a) pos[a] = g.origin[a] + u(rng) * g.spacing * float(g.size[a] - 1);
    ASSERT_TRUE(l.probes.sample(pos, sh));
    expect_field(sh, pos, "inside");
  }
  // Beyond the last face along x (within the probes' reach): the field on that face.
  const float out[3] = {g.origin[0] + g.spacing * (float(g.size[0] - 1) + 0.6f), 0.4f, -1.3f};
  const float face[3] = {g.origin[0] + g.spacing * float(g.size[0] - 1), 0.4f, -1.3f};
  float sh[kProbeShFloats];
  ASSERT_TRUE(l.probes.sample(out, sh));
  expect_field(sh, face, "clamped");
  float rgb[3];
  const float up[3] = {0.0f, 1.0f, 0.0f};
  LightProbes::irradiance(sh, up, rgb);
  for (float c : rgb) EXPECT_GE(c, 0.0f);
}

// Grid probe (i, j, k) of the linear pack (no holes: its index is its grid point's).
uint32_t grid_probe(const pack::ProbeGridRecord& g, uint32_t i, uint32_t j, uint32_t k) {
  return i + g.size[0] * (j + g.size[1] * k);
}

TEST(LightProbes, ACornerBehindAShortReachIsLeftOut) {
  SyntheticOptions o = linear_options();
  // Probe (2, 1, 1) sees only 0.1 m towards -X (a wall between it and cell (1, 1, 1)'s middle).
  o.mutate_probes = [](auto& probes, auto& grid, auto&, auto&, auto&) {
    probes[grid_probe(grid, 2, 1, 1)].reach[1] = 0.1f;
  };
  Loaded l(o);
  const pack::ProbeGridRecord& g = l.view.probe_grid();
  auto corner = [&](uint32_t k, float out[3]) {
    const uint32_t ijk[3] = {1 + (k & 1), 1 + ((k >> 1) & 1), 1 + ((k >> 2) & 1)};
    for (int a = 0; a < 3; ++a) out[a] = g.origin[a] + g.spacing * float(ijk[a]);
  };
  // The cell's middle: 0.25 m from the probe along -X, beyond its reach. The 7 other corners,
  // each weighted 1/8, renormalised: their mean.
  float mid[3], sh[kProbeShFloats];
  for (int a = 0; a < 3; ++a) mid[a] = g.origin[a] + g.spacing * 1.5f;
  ASSERT_TRUE(l.probes.sample(mid, sh));
  double want[kProbeShFloats] = {};
  for (uint32_t k = 0; k < 8; ++k) {
    if (k == 1) continue;  // corner (2, 1, 1)
    float c[3], f[kProbeShFloats];
    corner(k, c);
    linear_field(c, f);
    for (uint32_t i = 0; i < kProbeShFloats; ++i) want[i] += f[i] / 7.0;
  }
  for (uint32_t i = 0; i < kProbeShFloats; ++i)
    EXPECT_NEAR(sh[i], want[i], 1e-5 * (1.0 + std::fabs(want[i]))) << i;
  // 0.05 m from it: within its reach, all 8 corners, the field itself.
  const float near[3] = {g.origin[0] + g.spacing * 2.0f - 0.05f, mid[1], mid[2]};
  ASSERT_TRUE(l.probes.sample(near, sh));
  expect_field(sh, near, "within reach");
}

TEST(LightProbes, WithNoCornerLeftTheNearestReachableThenTheNearestCornerAnswers) {
  SyntheticOptions o = linear_options();
  o.probe_reach = 0.0f;  // every probe walled in
  // Except probe (2, 1, 1), which sees 1 m towards -X.
  o.mutate_probes = [](auto& probes, auto& grid, auto&, auto&, auto&) {
    for (float& r : probes[grid_probe(grid, 2, 1, 1)].reach) r = 1.0f;
  };
  Loaded l(o);
  const pack::ProbeGridRecord& g = l.view.probe_grid();
  float want[kProbeShFloats], sh[kProbeShFloats];
  // On cell (1, 1, 1)'s -X face: the +X corners weigh 0, the -X ones are walled in; (2, 1, 1)
  // is the one reachable corner, though (1, 1, 1) is nearer.
  const float face[3] = {g.origin[0] + g.spacing * 1.0f, g.origin[1] + g.spacing * 1.2f,
                         g.origin[2] + g.spacing * 1.3f};
  ASSERT_TRUE(l.probes.sample(face, sh));
  l.probes.probe_sh(grid_probe(g, 2, 1, 1), want);
  EXPECT_EQ(std::memcmp(sh, want, sizeof sh), 0);
  // In cell (0, 0, 0) nothing is reachable: the nearest corner, (0, 1, 0).
  const float inside[3] = {g.origin[0] + g.spacing * 0.2f, g.origin[1] + g.spacing * 0.7f,
                           g.origin[2] + g.spacing * 0.4f};
  ASSERT_TRUE(l.probes.sample(inside, sh));
  l.probes.probe_sh(grid_probe(g, 0, 1, 0), want);
  EXPECT_EQ(std::memcmp(sh, want, sizeof sh), 0);
}

TEST(LightProbes, WithoutAGridThereIsNothingToSample) {
  Loaded plain{SyntheticOptions()};
  float sh[kProbeShFloats] = {};
  const float pos[3] = {0, 0, 0};
  EXPECT_EQ(plain.probes.probe_count(), 0u);
  EXPECT_FALSE(plain.probes.sample(pos, sh));
  EXPECT_EQ(plain.probes.find_probe("probe_0"), -1);
  // A grid whose cell has no probe at all.
  SyntheticOptions o = probe_options();
  o.probe_hole_probability = 1.0f;  // only the two named probes, off the grid
  Loaded holes(o);
  EXPECT_EQ(holes.probes.probe_count(), 2u);
  EXPECT_FALSE(holes.probes.sample(pos, sh));
  EXPECT_EQ(holes.probes.find_probe("probe_1"), 1);
  // A state of another pack is refused.
  EXPECT_EQ(holes.probes.update(plain.state), Status::kInvalidArgument);
}

TEST(LightProbes, UpdatesAndQueriesAllocateNothing) {
  Loaded l(probe_options(4));
  testing::Counters& c = testing::counters();
  // Positive control: init allocates, and the counters see it.
  c.news = c.mallocs = 0;
  c.on = true;
  {
    LightProbes other;
    SceneState st;
    ASSERT_EQ(other.init(l.view, nullptr), Status::kOk);
    ASSERT_EQ(st.init(l.view, nullptr), Status::kOk);
  }
  c.on = false;
  EXPECT_GT(c.news + (testing::malloc_counted() ? c.mallocs.load() : 0), 0u);
  if (testing::malloc_counted()) {
    EXPECT_GT(c.mallocs, 0u);
  }

  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(-2.0f, 3.0f);
  c.news = c.mallocs = 0;
  c.on = true;
  uint64_t touched = 0;
  for (int n = 0; n < 500; ++n) {
    random_change(rng, &l.state);
    l.probes.update(l.state);
    touched += l.probes.stats().entries_last_update;
    const float pos[3] = {u(rng), u(rng), u(rng)};
    float sh[kProbeShFloats] = {}, rgb[3];
    l.probes.sample(pos, sh);
    LightProbes::irradiance(sh, pos, rgb);
    l.probes.find_probe("probe_1");
  }
  l.probes.rebuild(l.state);
  c.on = false;
  EXPECT_GT(touched, 0u);
  EXPECT_EQ(c.news, 0u);
  if (testing::malloc_counted()) {
    EXPECT_EQ(c.mallocs, 0u);
  }
}

}  // namespace
}  // namespace lightpatch
