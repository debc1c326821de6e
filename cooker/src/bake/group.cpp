#include "bake/group.h"

#include <algorithm>
#include <chrono>
#include <memory>

#include "bake/direct_pass.h"
#include "bake/plan.h"
#include "indirect/integrator.h"
#include "lightpatch/cooker/progress.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {

// A map is kept when its peak exceeds this fraction of its group's significance threshold (half
// an 8-bit step at the authored exposure): below, it would round away.
constexpr float kKeepFraction = 0.5f;
// A bounce-only object is solved when the first bounce of its change could reach this fraction
// of half an output step; the solved change is then kept or dropped by its own peak.
constexpr float kBounceOnlyFraction = 0.5f;

// The first channel of a map whose three are equal (a light's grey transport).
FloatImage first_channel(FloatImage m) {
  if (m.channels == 1) return m;
  FloatImage out(m.width, m.height, 1);
  for (size_t i = 0; i < out.data.size(); ++i) out.data[i] = m.data[i * size_t(m.channels)];
  return out;
}

std::string keep_reason(float peak, float keep_at, const std::string& what) {
  if (peak > keep_at)
    return what + " peak " + std::to_string(peak) + " above half an output step (" +
           std::to_string(keep_at) + ")";
  if (peak > 0.0f)
    return what + " peak " + std::to_string(peak) + " below half an output step (" +
           std::to_string(keep_at) + ")";
  return "changes none of the group's light at any texel";
}

}  // namespace

namespace {

// One light group's bake in progress (bake_light_groups): its direct pass, its bounce light, its
// objects' changes and its maps, stage by stage, so that the stages that solve bounce light can
// take several groups at once.
struct GroupWork {
  GroupWork(const BakeContext& b, const BakePlan& plan, size_t group)
      : lg(plan.groups.at(group)),
        planned(b.options.plan_effects),
        is_static(lg.light < 0),
        cand(b.scene.objects.size()) {
    out.group = group;
    for (int o : lg.candidates) cand.add(o);
  }
  void decide(DecisionKind kind, DecisionStage stage, int object, int object_b, bool taken,
              std::string reason, double value = std::nan(""), double bound = std::nan(""),
              double seconds = std::nan("")) {
    Decision d;
    d.kind = kind;
    d.stage = stage;
    d.light = lg.light;
    d.object = object;
    d.object_b = object_b;
    d.taken = taken;
    d.forced = !planned;
    d.reason = planned ? std::move(reason) : std::string(kForced) + ": " + reason;
    d.value = value;
    d.bound = bound;
    d.seconds = seconds;
    out.decisions.push_back(std::move(d));
  }
  // A map's direct part (ShadowMap::direct): grey for a light (one channel), the static lights'
  // colours for the base map.
  FloatImage direct_part(const FloatImage& m) const { return is_static ? m : first_channel(m); }

  const LightGroup& lg;
  const bool planned, is_static;
  GroupBake out;
  Candidates cand;
  DirectPass dp;
  GroupBounce gb;
  bool bounce = false;
  std::vector<BounceMap> change, only;  // per slot; per bounce-only object
  std::vector<std::string> only_reason;
  std::vector<double> seconds;  // per slot, then per bounce-only object: its change's solve
  double own_s = 0.0;           // wall time of its own stages and its share of shared ones
  // Overlaps kept and their slots, in dp.pairs order.
  std::vector<PairCorrectionMap> corrections;
  std::vector<std::pair<int, int>> kept_pairs;
};

// `wall` split by `work` (each >= 0; evenly where all are 0).
std::vector<double> shares(double wall, const std::vector<double>& work) {
  double total = 0.0;
  for (double w : work) total += w;
  std::vector<double> out(work.size());
  for (size_t i = 0; i < work.size(); ++i)
    out[i] = total > 0.0 ? wall * work[i] / total : wall / double(work.size());
  return out;
}

// Whether each map's direct part (ShadowMap::direct) is kept apart from its bounce light: with
// bounce light and no indirect map, where the pack may store the two apart.
bool keeps_direct(const BakeContext& b) {
  return b.indirect && b.layout.align == 1;
}

// Solves `requests` (request k changes group work[group_of[k]]) in one
// IndirectIntegrator::changes() under a progress line naming the groups; `seconds` receives each
// request's share of the solve and `by_group` each group's sum of them.
std::vector<BounceMap> solve_requests(const BakeContext& b, const std::vector<GroupWork*>& work,
                                      const std::vector<size_t>& group_of,
                                      const std::vector<ChangeRequest>& requests,
                                      const std::string& what, Progress& progress,
                                      std::vector<double>& seconds, std::vector<double>& by_group) {
  by_group.assign(work.size(), 0.0);
  seconds.clear();
  if (requests.empty()) return {};
  std::vector<uint8_t> named(work.size(), 0);
  for (size_t i : group_of) named[i] = 1;
  std::string names;
  for (size_t i = 0; i < work.size(); ++i)
    if (named[i]) names += (names.empty() ? "" : ", ") + work[i]->lg.name;
  progress.begin(what + ": " + names, requests.size());
  std::vector<BounceMap> solved = b.indirect->changes(requests, b.threads, &seconds, &progress);
  progress.end();
  for (size_t k = 0; k < requests.size(); ++k) by_group[group_of[k]] += seconds[k];
  return solved;
}

// The direct pass of one group.
void trace_group(const BakeContext& b, GroupWork& g, Progress& progress, Report& report) {
  const auto t0 = std::chrono::steady_clock::now();
  const int channels = g.is_static || b.indirect ? 3 : 1;
  progress.begin(g.is_static ? "base map" : "light " + g.lg.name,
                 static_cast<uint64_t>(b.texels.height));
  g.dp = trace_direct(b, g.lg.light, g.cand, channels, progress);
  report.stage_time(g.is_static ? "bake.base" : "bake.contribution", progress.end());
  g.change.resize(g.cand.sets.size());
  g.only.resize(g.lg.bounce_only.size());
  g.only_reason.assign(g.lg.bounce_only.size(), "the group's bounce light is off");
  g.seconds.assign(g.cand.sets.size() + g.lg.bounce_only.size(), 0.0);
  g.own_s += seconds_since(t0);
}

// Every group's bounce light, then every object's change to it: one solve each for all groups,
// so that the lights of one room share each pass over the integrator's rays, and one object's
// changes to several lights (the same rays changed) are neighbours.
void bounce_groups(const BakeContext& b, std::vector<GroupWork*>& work, Progress& progress,
                   Report& report) {
  const IndirectIntegrator* ind = b.indirect.get();
  const Scene& scene = b.scene;
  const auto tb = std::chrono::steady_clock::now();
  std::vector<GroupLight> lights;
  for (GroupWork* g : work) {
    const DirectPass* points = g->dp.points.get();
    lights.push_back({&g->dp.map, points ? &points->map : nullptr, g->lg.threshold});
  }
  std::vector<GroupBounce> prepared = ind->prepare(lights, b.threads);
  std::vector<double> gathers;
  for (const GroupBounce& gb : prepared) gathers.push_back(double(gb.gathers));
  const std::vector<double> prepare_s = shares(seconds_since(tb), gathers);
  std::vector<double> bounce_s(work.size(), 0.0);

  struct Job {
    size_t work, slot;  // slot: cand.sets index, then cand.sets.size() + bounce-only index
    int object;         // the first object present, for the order
  };
  std::vector<Job> jobs;
  for (size_t i = 0; i < work.size(); ++i) {
    GroupWork& g = *work[i];
    g.gb = std::move(prepared[i]);
    bounce_s[i] += prepare_s[i];
    const float at = 0.5f * g.lg.threshold;
    g.bounce = !g.planned || g.gb.peak >= at;
    g.decide(DecisionKind::kGroupBounce, DecisionStage::kTraced, -1, -1, g.bounce,
             "bounce peak " + std::to_string(g.gb.peak) + (g.gb.peak >= at ? " above" : " below") +
                 " half an output step (" + std::to_string(at) + "); " +
                 std::to_string(g.gb.bounces) + " bounces",
             g.gb.peak, at, prepare_s[i]);
    if (!g.bounce) continue;
    // An object that blocks no direct light is solved only if the cheap bound of its change's
    // first bounce says it may matter.
    const auto tf = std::chrono::steady_clock::now();
    const size_t slots = g.cand.sets.size(), n_only = g.lg.bounce_only.size();
    std::vector<float> first(n_only, 0.0f);
    parallel_for(int(n_only), b.threads, [&](int q) {
      const auto tq = std::chrono::steady_clock::now();
      std::vector<uint8_t> present(scene.objects.size(), 0);
      present[size_t(g.lg.bounce_only[size_t(q)])] = 1;
      first[size_t(q)] = ind->first_change(g.gb, present);
      g.seconds[slots + size_t(q)] = seconds_since(tq);
    });
    bounce_s[i] += seconds_since(tf);
    for (size_t j = 0; j < slots; ++j) jobs.push_back({i, j, g.cand.sets[j].front()});
    for (size_t q = 0; q < n_only; ++q) {
      const float bar = kBounceOnlyFraction * at;
      if (g.planned && first[q] < bar) {
        g.only_reason[q] = "first bounce of its change " + std::to_string(first[q]) +
                           " below a quarter output step (" + std::to_string(bar) + ")";
        continue;
      }
      g.only_reason[q] = "first bounce of its change " + std::to_string(first[q]);
      jobs.push_back({i, slots + q, g.lg.bounce_only[q]});
    }
  }
  // One object's changes to every group side by side: they read the same changed rays.
  std::stable_sort(jobs.begin(), jobs.end(),
                   [](const Job& a, const Job& c) { return a.object < c.object; });
  std::vector<ChangeRequest> requests;
  std::vector<size_t> group_of;
  for (const Job& job : jobs) {
    group_of.push_back(job.work);
    GroupWork& g = *work[job.work];
    const DirectPass* points = g.dp.points.get();
    ChangeRequest r;
    r.group = &g.gb;
    r.threshold = g.lg.threshold;
    r.present.assign(scene.objects.size(), 0);
    if (job.slot < g.cand.sets.size()) {
      for (int o : g.cand.sets[job.slot]) r.present[size_t(o)] = 1;
      r.blocked.sparse.push_back({&g.dp.shadow[job.slot], 1.0f});
      if (points) r.blocked_points.sparse.push_back({&points->shadow[job.slot], 1.0f});
    } else {
      r.present[size_t(job.object)] = 1;
    }
    requests.push_back(std::move(r));
  }
  const auto tc = std::chrono::steady_clock::now();
  std::vector<double> solve_s, by_group;
  std::vector<BounceMap> solved =
      solve_requests(b, work, group_of, requests, "bounce of objects", progress, solve_s, by_group);
  const std::vector<double> change_s = shares(seconds_since(tc), by_group);
  for (size_t i = 0; i < work.size(); ++i) bounce_s[i] += change_s[i];
  for (size_t k = 0; k < jobs.size(); ++k) {
    GroupWork& g = *work[jobs[k].work];
    const size_t slots = g.cand.sets.size();
    g.seconds[jobs[k].slot] += solve_s[k];
    if (jobs[k].slot < slots)
      g.change[jobs[k].slot] = std::move(solved[k]);
    else
      g.only[jobs[k].slot - slots] = std::move(solved[k]);
  }
  for (size_t i = 0; i < work.size(); ++i) {
    GroupWork& g = *work[i];
    if (g.bounce) {
      const auto ta = std::chrono::steady_clock::now();
      const size_t slots = g.cand.sets.size();
      for (size_t j = 0; j < slots; ++j)
        g.decide(DecisionKind::kObjectBounce, DecisionStage::kTraced, g.cand.objects[j], -1, true,
                 "blocks direct light: its change to the bounce light is solved", std::nan(""),
                 std::nan(""), g.seconds[j]);
      for (size_t q = 0; q < g.lg.bounce_only.size(); ++q)
        g.decide(DecisionKind::kObjectBounce, DecisionStage::kBounce, g.lg.bounce_only[q], -1,
                 !g.only[q].empty(), g.only_reason[q], std::nan(""), std::nan(""),
                 g.seconds[slots + q]);
      if (keeps_direct(b)) g.out.direct = g.direct_part(g.dp.map);
      ind->add(g.gb.indirect, g.dp.map, &g.out.indirect);
      bounce_s[i] += seconds_since(ta);
    }
    report.stage_time(g.is_static ? "bake.base_bounce" : "bake.contribution_bounce", bounce_s[i]);
    g.own_s += bounce_s[i];
  }
}

// Each slot's map (its direct shadow and its bounce change), kept above half a step, and the
// overlaps kept.
void keep_maps(const BakeContext& b, GroupWork& g) {
  const auto t0 = std::chrono::steady_clock::now();
  const IndirectIntegrator* ind = b.indirect.get();
  const TexelSet& texels = b.texels;
  const LightGroup& lg = g.lg;
  const bool planned = g.planned, is_static = g.is_static, bounce = g.bounce;
  const bool keep_direct = keeps_direct(b);
  const int w = texels.width, h = texels.height;
  // Without bounce light a light's transport is grey: one channel.
  const bool grey = !is_static && !bounce;
  g.out.map = grey ? first_channel(std::move(g.dp.map)) : std::move(g.dp.map);

  const float keep_at = kKeepFraction * lg.threshold;
  const DecisionKind kind = is_static ? DecisionKind::kStaticShadow : DecisionKind::kPair;
  const int light_index = int(g.out.group) - 1;  // BakedMaps::lights index of a light group
  const Candidates& cand = g.cand;
  std::vector<uint8_t> kept(cand.sets.size(), 0);
  // Made in parallel (the bounce changes denoised and magnified), a map below the bar freed at
  // once (all held until decided took the full inn's peak from 2.57 to 2.81 GB); decided and
  // stored in order.
  struct Made {
    FloatImage map, blocks, direct;
    float peak = 0.0f;
    bool solved = false;
  };
  const size_t slots = cand.sets.size(), n_only = lg.bounce_only.size();
  std::vector<Made> made(slots + n_only);
  parallel_for(int(slots + n_only), b.threads, [&](int i) {
    const size_t j = size_t(i);
    Made& m = made[j];
    if (j < slots) {
      m.map = g.dp.shadow[j].dense();
      if (bounce) {
        if (keep_direct) m.direct = g.direct_part(m.map);
        ind->add(g.change[j], m.map, &m.blocks);
      }
    } else if (!g.only[j - slots].empty()) {
      m.map = FloatImage(w, h, 3);
      if (keep_direct) m.direct = FloatImage(w, h, is_static ? 3 : 1);  // bounce light alone
      ind->add(std::move(g.only[j - slots]), m.map, &m.blocks);
    } else {
      return;
    }
    m.solved = true;
    if (grey) m.map = first_channel(std::move(m.map));
    m.peak = peak_of(m.map, texels);
    if (planned && !(m.peak > keep_at))
      m = Made{FloatImage(), FloatImage(), FloatImage(), m.peak, true};
  });
  auto keep_map = [&](int object, Made& m, DecisionStage stage, const std::string& what) {
    const bool keep = !planned || m.peak > keep_at;
    g.decide(kind, stage, object, -1, keep, keep_reason(m.peak, keep_at, what), m.peak, keep_at);
    if (!keep) return false;
    if (is_static)
      g.out.static_shadows.push_back(
          {object, std::move(m.map), std::move(m.blocks), std::move(m.direct)});
    else
      g.out.shadows.push_back(
          {light_index, object, std::move(m.map), std::move(m.blocks), std::move(m.direct)});
    return true;
  };
  for (size_t j = 0; j < slots; ++j)
    kept[j] =
        keep_map(cand.objects[j], made[j], DecisionStage::kTraced, is_static ? "change" : "shadow")
            ? 1
            : 0;
  for (size_t q = 0; q < n_only; ++q) {
    if (!made[slots + q].solved) {
      g.decide(kind, DecisionStage::kPlan, lg.bounce_only[q], -1, false,
               lg.bounce_only_why[q] + "; bounce: " + g.only_reason[q]);
      continue;
    }
    keep_map(lg.bounce_only[q], made[slots + q], DecisionStage::kBounce, "bounce change");
  }

  // Overlaps: where two objects block the same rays, S_a + S_b removes that light twice; the
  // pair's correction adds it back while both are visible (inclusion-exclusion, DESIGN.md).
  g.corrections.reserve(g.dp.pairs.size());  // change requests point at their maps
  for (auto& [key, img] : g.dp.pairs) {
    const int oa = cand.objects[size_t(key.first)], ob = cand.objects[size_t(key.second)];
    const float peak = peak_of(img, texels);
    if (is_static) {
      // The pack has no static pair corrections: overlapping static shadows stay the paper's
      // approximation, reported with their size.
      if (peak > keep_at)
        g.decide(DecisionKind::kStaticOverlap, DecisionStage::kTraced, std::min(oa, ob),
                 std::max(oa, ob), false,
                 "peak " + std::to_string(peak) +
                     ": static lights have no pair corrections in the pack; where both are "
                     "visible their overlap is darkened twice",
                 peak, keep_at);
      continue;
    }
    const bool keep =
        (!planned || peak > keep_at) && kept[size_t(key.first)] && kept[size_t(key.second)];
    g.decide(DecisionKind::kOverlap, DecisionStage::kTraced, std::min(oa, ob), std::max(oa, ob),
             keep, keep_reason(peak, keep_at, "overlap"), peak, keep_at);
    if (!keep) continue;
    PairCorrectionMap pc;
    pc.light = light_index;
    pc.object_a = std::min(oa, ob);
    pc.object_b = std::max(oa, ob);
    pc.map = std::move(img);
    if (grey) pc.map = first_channel(std::move(pc.map));
    g.corrections.push_back(std::move(pc));
    g.kept_pairs.push_back(key);
  }
  g.own_s += seconds_since(t0);
}

// Each kept overlap's joint change to its group's bounce light, from the same rays, for every
// group in one solve: the bounce part of a correction is change_a + change_b - change_ab (one
// object hides the other's bounce).
void bounce_overlaps(const BakeContext& b, std::vector<GroupWork*>& work, Progress& progress) {
  const IndirectIntegrator* ind = b.indirect.get();
  const auto t0 = std::chrono::steady_clock::now();
  struct Job {
    size_t work, pair;
    std::pair<int, int> objects;  // for the order
  };
  std::vector<Job> jobs;
  for (size_t i = 0; i < work.size(); ++i) {
    const GroupWork& g = *work[i];
    if (!g.bounce) continue;
    for (size_t k = 0; k < g.corrections.size(); ++k)
      jobs.push_back({i, k, {g.corrections[k].object_a, g.corrections[k].object_b}});
  }
  if (jobs.empty()) return;
  // One pair's joint changes to every group side by side, as bounce_groups' changes.
  std::stable_sort(jobs.begin(), jobs.end(),
                   [](const Job& a, const Job& c) { return a.objects < c.objects; });
  std::vector<ChangeRequest> requests;
  std::vector<size_t> group_of;
  for (const Job& job : jobs) {
    GroupWork& g = *work[job.work];
    const PairCorrectionMap& pc = g.corrections[job.pair];
    const auto [sa, sb] = g.kept_pairs[job.pair];
    ChangeRequest r;
    r.group = &g.gb;
    r.threshold = g.lg.threshold;
    r.present.assign(b.scene.objects.size(), 0);
    r.present[size_t(pc.object_a)] = r.present[size_t(pc.object_b)] = 1;
    r.blocked.sparse = {{&g.dp.shadow[size_t(sa)], 1.0f}, {&g.dp.shadow[size_t(sb)], 1.0f}};
    r.blocked.dense = {{&pc.map, -1.0f}};
    if (const DirectPass* points = g.dp.points.get()) {
      r.blocked_points.sparse = {{&points->shadow[size_t(sa)], 1.0f},
                                 {&points->shadow[size_t(sb)], 1.0f}};
      auto it = points->pairs.find({sa, sb});
      if (it != points->pairs.end()) r.blocked_points.dense = {{&it->second, -1.0f}};
    }
    requests.push_back(std::move(r));
    group_of.push_back(job.work);
  }
  std::vector<double> solve_s, by_group;
  const std::vector<BounceMap> joint = solve_requests(
      b, work, group_of, requests, "bounce of overlaps", progress, solve_s, by_group);
  parallel_for(int(jobs.size()), b.threads, [&](int kk) {
    const size_t k = size_t(kk);
    GroupWork& g = *work[jobs[k].work];
    PairCorrectionMap& pc = g.corrections[jobs[k].pair];
    const auto [sa, sb] = g.kept_pairs[jobs[k].pair];
    const BounceMap& ab = joint[k];
    BounceMap p(ab.size());
    for (size_t c = 0; c < p.size(); ++c)
      p[c] = g.change[size_t(sa)][c] + g.change[size_t(sb)][c] - ab[c];
    if (keeps_direct(b)) pc.direct = g.direct_part(pc.map);
    ind->add(std::move(p), pc.map, &pc.indirect);
  });
  const std::vector<double> s = shares(seconds_since(t0), by_group);
  for (size_t i = 0; i < work.size(); ++i) work[i]->own_s += s[i];
}

// The group's maps, in the order assemble() expects.
void finish_group(GroupWork& g) {
  for (PairCorrectionMap& pc : g.corrections) g.out.pair_corrections.push_back(std::move(pc));
  g.corrections.clear();
  const DirectPass& dp = g.dp;
  // Triple overlaps (three objects blocking one ray) are not corrected: the decision says how
  // much light they carry next to the pair overlaps that are.
  if (dp.doubly_blocked > 0.0 || dp.triply_blocked > 0.0) {
    const double share = dp.triply_blocked / (dp.doubly_blocked + dp.triply_blocked);
    g.decide(DecisionKind::kTripleOverlap, DecisionStage::kTraced, -1, -1, false,
             std::to_string(100.0 * share) +
                 "% of the light blocked by several objects is blocked by three or more; only "
                 "pairs are corrected",
             share);
  }
  std::sort(g.out.shadows.begin(), g.out.shadows.end(),
            [](const ShadowMap& a, const ShadowMap& c) { return a.object < c.object; });
  std::sort(g.out.static_shadows.begin(), g.out.static_shadows.end(),
            [](const StaticShadowMap& a, const StaticShadowMap& c) { return a.object < c.object; });
  g.out.seconds = g.own_s;
}

}  // namespace

std::vector<GroupBake> bake_light_groups(const BakeContext& b, const BakePlan& plan,
                                         const std::vector<size_t>& groups, Progress& progress,
                                         Report& report) {
  std::vector<std::unique_ptr<GroupWork>> owned;
  std::vector<GroupWork*> work;
  for (size_t group : groups) {
    owned.push_back(std::make_unique<GroupWork>(b, plan, group));
    work.push_back(owned.back().get());
  }
  for (GroupWork* g : work) trace_group(b, *g, progress, report);
  if (b.indirect) bounce_groups(b, work, progress, report);
  for (GroupWork* g : work) keep_maps(b, *g);
  if (b.indirect) bounce_overlaps(b, work, progress);
  std::vector<GroupBake> out;
  for (GroupWork* g : work) {
    finish_group(*g);
    out.push_back(std::move(g->out));
  }
  return out;
}

}  // namespace lightpatch::cooker
