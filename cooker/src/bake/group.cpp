#include "bake/group.h"

#include <algorithm>
#include <chrono>

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

GroupBake bake_light_group(const BakeContext& b, const BakePlan& plan, size_t group,
                           Progress& progress, Report& report) {
  const auto t0 = std::chrono::steady_clock::now();
  const LightGroup& lg = plan.groups.at(group);
  const Scene& scene = b.scene;
  const TexelSet& texels = b.texels;
  const bool planned = b.options.plan_effects;
  const bool is_static = lg.light < 0;
  const IndirectIntegrator* ind = b.indirect.get();
  const int w = texels.width, h = texels.height;
  GroupBake out;
  out.group = group;
  auto decide = [&](DecisionKind kind, DecisionStage stage, int object, int object_b, bool taken,
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
  };

  Candidates cand(scene.objects.size());
  for (int o : lg.candidates) cand.add(o);
  const int channels = is_static || ind ? 3 : 1;
  progress.begin(is_static ? "base map" : "light " + lg.name, static_cast<uint64_t>(h));
  DirectPass dp = trace_direct(b, lg.light, cand, channels, progress);
  report.stage_time(is_static ? "bake.base" : "bake.contribution", progress.end());

  // Each map's direct part (ShadowMap::direct), kept where the pack may store it apart from the
  // bounce light: grey for a light (one channel), the static lights' colours for the base map.
  const bool keep_direct = ind && b.layout.align == 1;
  auto direct_part = [&](const FloatImage& m) { return is_static ? m : first_channel(m); };

  // Bounce light: the group's own, then every object's change to it.
  GroupBounce gb;
  bool bounce = false;
  std::vector<BounceMap> change(cand.sets.size()), only(lg.bounce_only.size());
  std::vector<std::string> only_reason(lg.bounce_only.size(), "the group's bounce light is off");
  if (ind) {
    const auto tb = std::chrono::steady_clock::now();
    DirectPass* points = dp.points.get();
    gb = ind->prepare(dp.map, points ? &points->map : nullptr, lg.threshold);
    const float at = 0.5f * lg.threshold;
    bounce = !planned || gb.peak >= at;
    decide(DecisionKind::kGroupBounce, DecisionStage::kTraced, -1, -1, bounce,
           "bounce peak " + std::to_string(gb.peak) + (gb.peak >= at ? " above" : " below") +
               " half an output step (" + std::to_string(at) + "); " + std::to_string(gb.bounces) +
               " bounces",
           gb.peak, at, seconds_since(tb));
    if (bounce) {
      const size_t jobs = cand.sets.size() + lg.bounce_only.size();
      std::vector<double> seconds(jobs, 0.0);
      // An object that blocks no direct light is solved only if the cheap bound of its change's
      // first bounce says it may matter.
      std::vector<float> first(lg.bounce_only.size(), 0.0f);
      parallel_for(int(lg.bounce_only.size()), b.threads, [&](int q) {
        const auto tq = std::chrono::steady_clock::now();
        std::vector<uint8_t> present(scene.objects.size(), 0);
        present[size_t(lg.bounce_only[size_t(q)])] = 1;
        first[size_t(q)] = ind->first_change(gb, present);
        seconds[cand.sets.size() + size_t(q)] = seconds_since(tq);
      });
      std::vector<ChangeRequest> requests;
      std::vector<size_t> job_of;  // request -> job (a slot, then cand.sets.size() + q)
      for (size_t j = 0; j < cand.sets.size(); ++j) {
        ChangeRequest r;
        r.present.assign(scene.objects.size(), 0);
        for (int o : cand.sets[j]) r.present[size_t(o)] = 1;
        r.blocked.sparse.push_back({&dp.shadow[j], 1.0f});
        if (points) r.blocked_points.sparse.push_back({&points->shadow[j], 1.0f});
        requests.push_back(std::move(r));
        job_of.push_back(j);
      }
      for (size_t q = 0; q < lg.bounce_only.size(); ++q) {
        const float bar = kBounceOnlyFraction * at;
        if (planned && first[q] < bar) {
          only_reason[q] = "first bounce of its change " + std::to_string(first[q]) +
                           " below a quarter output step (" + std::to_string(bar) + ")";
          continue;
        }
        only_reason[q] = "first bounce of its change " + std::to_string(first[q]);
        ChangeRequest r;
        r.present.assign(scene.objects.size(), 0);
        r.present[size_t(lg.bounce_only[q])] = 1;
        requests.push_back(std::move(r));
        job_of.push_back(cand.sets.size() + q);
      }
      progress.begin("bounce of objects: " + lg.name, requests.size());
      std::vector<double> solve_s;
      std::vector<BounceMap> solved =
          ind->changes(gb, requests, lg.threshold, b.threads, &solve_s, &progress);
      progress.end();
      for (size_t i = 0; i < requests.size(); ++i) {
        const size_t j = job_of[i];
        seconds[j] += solve_s[i];
        if (j < cand.sets.size())
          change[j] = std::move(solved[i]);
        else
          only[j - cand.sets.size()] = std::move(solved[i]);
      }
      for (size_t j = 0; j < cand.sets.size(); ++j)
        decide(DecisionKind::kObjectBounce, DecisionStage::kTraced, cand.objects[j], -1, true,
               "blocks direct light: its change to the bounce light is solved", std::nan(""),
               std::nan(""), seconds[j]);
      for (size_t q = 0; q < lg.bounce_only.size(); ++q)
        decide(DecisionKind::kObjectBounce, DecisionStage::kBounce, lg.bounce_only[q], -1,
               !only[q].empty(), only_reason[q], std::nan(""), std::nan(""),
               seconds[cand.sets.size() + q]);
      if (keep_direct) out.direct = direct_part(dp.map);
      ind->add(gb.indirect, dp.map, &out.indirect);
    }
    report.stage_time(is_static ? "bake.base_bounce" : "bake.contribution_bounce",
                      seconds_since(tb));
  }
  // Without bounce light a light's transport is grey: one channel.
  const bool grey = !is_static && !bounce;
  out.map = grey ? first_channel(std::move(dp.map)) : std::move(dp.map);

  // Each slot's map: its direct shadow and its bounce change; kept above half a step.
  const float keep_at = kKeepFraction * lg.threshold;
  const DecisionKind kind = is_static ? DecisionKind::kStaticShadow : DecisionKind::kPair;
  const int light_index = int(group) - 1;  // BakedMaps::lights index of a light group
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
      m.map = dp.shadow[j].dense();
      if (bounce) {
        if (keep_direct) m.direct = direct_part(m.map);
        ind->add(change[j], m.map, &m.blocks);
      }
    } else if (!only[j - slots].empty()) {
      m.map = FloatImage(w, h, 3);
      if (keep_direct) m.direct = FloatImage(w, h, is_static ? 3 : 1);  // bounce light alone
      ind->add(std::move(only[j - slots]), m.map, &m.blocks);
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
    decide(kind, stage, object, -1, keep, keep_reason(m.peak, keep_at, what), m.peak, keep_at);
    if (!keep) return false;
    if (is_static)
      out.static_shadows.push_back(
          {object, std::move(m.map), std::move(m.blocks), std::move(m.direct)});
    else
      out.shadows.push_back(
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
      decide(kind, DecisionStage::kPlan, lg.bounce_only[q], -1, false,
             lg.bounce_only_why[q] + "; bounce: " + only_reason[q]);
      continue;
    }
    keep_map(lg.bounce_only[q], made[slots + q], DecisionStage::kBounce, "bounce change");
  }

  // Overlaps: where two objects block the same rays, S_a + S_b removes that light twice; the
  // pair's correction adds it back while both are visible (inclusion-exclusion, DESIGN.md).
  std::vector<std::pair<int, int>> kept_pairs;  // slots of each correction kept, in dp.pairs order
  std::vector<PairCorrectionMap> corrections;
  corrections.reserve(dp.pairs.size());  // the requests below point at their maps
  for (auto& [key, img] : dp.pairs) {
    const int oa = cand.objects[size_t(key.first)], ob = cand.objects[size_t(key.second)];
    const float peak = peak_of(img, texels);
    if (is_static) {
      // The pack has no static pair corrections: overlapping static shadows stay the paper's
      // approximation, reported with their size.
      if (peak > keep_at)
        decide(DecisionKind::kStaticOverlap, DecisionStage::kTraced, std::min(oa, ob),
               std::max(oa, ob), false,
               "peak " + std::to_string(peak) +
                   ": static lights have no pair corrections in the pack; where both are "
                   "visible their overlap is darkened twice",
               peak, keep_at);
      continue;
    }
    const bool keep =
        (!planned || peak > keep_at) && kept[size_t(key.first)] && kept[size_t(key.second)];
    decide(DecisionKind::kOverlap, DecisionStage::kTraced, std::min(oa, ob), std::max(oa, ob), keep,
           keep_reason(peak, keep_at, "overlap"), peak, keep_at);
    if (!keep) continue;
    PairCorrectionMap pc;
    pc.light = light_index;
    pc.object_a = std::min(oa, ob);
    pc.object_b = std::max(oa, ob);
    pc.map = std::move(img);
    if (grey) pc.map = first_channel(std::move(pc.map));
    corrections.push_back(std::move(pc));
    kept_pairs.push_back(key);
  }
  if (bounce && !corrections.empty()) {
    // Each pair's joint change to the bounce light, from the same rays: the bounce part of the
    // correction is change_a + change_b - change_ab (one object hides the other's bounce).
    std::vector<ChangeRequest> requests(corrections.size());
    for (size_t i = 0; i < corrections.size(); ++i) {
      const auto [sa, sb] = kept_pairs[i];
      ChangeRequest& r = requests[i];
      r.present.assign(scene.objects.size(), 0);
      r.present[size_t(corrections[i].object_a)] = r.present[size_t(corrections[i].object_b)] = 1;
      r.blocked.sparse = {{&dp.shadow[size_t(sa)], 1.0f}, {&dp.shadow[size_t(sb)], 1.0f}};
      r.blocked.dense = {{&corrections[i].map, -1.0f}};
      if (const DirectPass* points = dp.points.get()) {
        r.blocked_points.sparse = {{&points->shadow[size_t(sa)], 1.0f},
                                   {&points->shadow[size_t(sb)], 1.0f}};
        auto it = points->pairs.find({sa, sb});
        if (it != points->pairs.end()) r.blocked_points.dense = {{&it->second, -1.0f}};
      }
    }
    progress.begin("bounce of overlaps: " + lg.name, requests.size());
    const std::vector<BounceMap> joint =
        ind->changes(gb, requests, lg.threshold, b.threads, nullptr, &progress);
    progress.end();
    parallel_for(int(corrections.size()), b.threads, [&](int ii) {
      const size_t i = size_t(ii);
      const auto [sa, sb] = kept_pairs[i];
      const BounceMap& ab = joint[i];
      BounceMap p(ab.size());
      for (size_t c = 0; c < p.size(); ++c)
        p[c] = change[size_t(sa)][c] + change[size_t(sb)][c] - ab[c];
      if (keep_direct) corrections[i].direct = direct_part(corrections[i].map);
      ind->add(std::move(p), corrections[i].map, &corrections[i].indirect);
    });
  }
  for (PairCorrectionMap& pc : corrections) out.pair_corrections.push_back(std::move(pc));
  // Triple overlaps (three objects blocking one ray) are not corrected: the decision says how
  // much light they carry next to the pair overlaps that are.
  if (dp.doubly_blocked > 0.0 || dp.triply_blocked > 0.0) {
    const double share = dp.triply_blocked / (dp.doubly_blocked + dp.triply_blocked);
    decide(DecisionKind::kTripleOverlap, DecisionStage::kTraced, -1, -1, false,
           std::to_string(100.0 * share) +
               "% of the light blocked by several objects is blocked by three or more; only "
               "pairs are corrected",
           share);
  }
  std::sort(out.shadows.begin(), out.shadows.end(),
            [](const ShadowMap& a, const ShadowMap& c) { return a.object < c.object; });
  std::sort(out.static_shadows.begin(), out.static_shadows.end(),
            [](const StaticShadowMap& a, const StaticShadowMap& c) { return a.object < c.object; });
  out.seconds = seconds_since(t0);
  return out;
}

}  // namespace lightpatch::cooker
