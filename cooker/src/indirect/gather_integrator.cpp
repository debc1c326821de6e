// The final-gathering integrator (gather.h, solve.h) behind IndirectIntegrator.
#include <atomic>
#include <chrono>
#include <mutex>

#include "indirect/gather.h"
#include "indirect/integrator.h"
#include "indirect/solve.h"

namespace lightpatch::cooker {

glm::vec3 FineSum::at(size_t texel) const {
  glm::vec3 v(0.0f);
  for (const auto& [m, k] : sparse) {
    if (m->channels() == 3)
      v += k * glm::vec3(m->at(texel, 0), m->at(texel, 1), m->at(texel, 2));
    else
      v += k * glm::vec3(m->at(texel, 0));
  }
  for (const auto& [m, k] : dense) {
    const float* p = m->data.data() + texel * size_t(m->channels);
    v += k * (m->channels == 3 ? glm::vec3(p[0], p[1], p[2]) : glm::vec3(p[0]));
  }
  return v;
}

namespace {

// Bounce terms below this fraction of a group's significance threshold are dropped (the series
// stops when a bounce adds less anywhere), scaled by 1 - the mean albedo: a series cut at a term
// t leaves a tail of about t * albedo / (1 - albedo), which is what the decomposition and
// bake_state may differ by.
constexpr float kBounceTolerance = 0.02f;

class GatherIntegrator final : public IndirectIntegrator {
 public:
  GatherIntegrator(const BakeContext& b, GatherStore* store, Progress& progress, Report& report)
      : b_(b), preset_(gather_preset(b.options)) {
    progress.begin("load gather rays", 1);
    const bool loaded = store && store->load(op_, progress);
    const double load_s = progress.end();
    if (loaded) {
      report.stage_time("bake.gather_load", load_s);
    } else {
      progress.begin("gather rays", 1);
      GatherOptions go;
      go.rays = preset_.rays;
      go.seed = b.options.seed;
      go.threads = b.threads;
      if (!b.footprints.empty()) go.footprints = &b.footprints;
      op_ = build_gather(b.scene, b.layout, b.texels, b.tracer, preset_.level, go);
      report.stage_time("bake.gather_rays", progress.end());
      if (store) store->save(op_, progress);
    }
    const std::vector<float> near = near_field(op_);
    denoise_ = denoise_weights(op_.grid, preset_.denoise, &near, near_field_sigma(op_.rays));
  }

  GroupBounce prepare(const FloatImage& direct, float threshold) const override {
    GroupBounce g;
    const CoarseMap source = coarse_source(op_, b_.texels, direct);
    SolveStats st;
    const Bounces bounces = solve_indirect(op_, {}, source, options(threshold, b_.threads), &st);
    count(st, groups_);
    g.indirect = bounces.total();
    EmptyRadiance e = empty_radiance(op_, source, bounces);
    g.sends = {std::move(e.direct), std::move(e.first), std::move(e.later)};
    g.peak = peak(g.indirect);
    g.bounces = st.bounces;
    return g;
  }

  BounceMap change(const GroupBounce& group, const std::vector<uint8_t>& present,
                   const FineSum& blocked, float threshold) const override {
    const CoarseMap src =
        blocked.sparse.empty() && blocked.dense.empty()
            ? CoarseMap(op_.grid.size(), glm::vec3(0.0f))
            : coarse_source_of(op_, b_.texels, [&](size_t t) { return blocked.at(t); });
    SolveStats st;
    BounceMap change = solve_change(op_, present, empty(group), src, options(threshold, 1), &st);
    count(st, changes_);
    return change;
  }

  float first_change(const GroupBounce& group, const std::vector<uint8_t>& present) const override {
    return first_change_peak(op_, present, empty(group));
  }

  void add(BounceMap map, FloatImage& fine, FloatImage* blocks) const override {
    denoise(op_.grid, denoise_, map);
    add_magnified(op_.grid, b_.texels, map, fine);
    const int s = b_.layout.align;
    if (s > 1 && blocks) *blocks = block_image(op_.grid, b_.texels, s, map);
  }

  void add_state(const FloatImage& direct, const std::vector<uint8_t>& present, float threshold,
                 FloatImage& fine) const override {
    const CoarseMap source = coarse_source(op_, b_.texels, direct);
    SolveStats st;
    add(solve_indirect(op_, present, source, options(threshold, b_.threads), &st).total(), fine,
        nullptr);
    count(st, states_);
  }

  nlohmann::json describe() const override {
    return {
        {"integrator", "gather"},
        {"level", preset_.level},
        {"rays_per_coarse_texel", preset_.rays},
        {"rays_per_bounce", {op_.level_rays[0], op_.level_rays[1], op_.level_rays[2]}},
        {"denoise_passes", preset_.denoise},
        {"indirect_map_scale", b_.layout.align},
        {"coarse_texels", op_.grid.size()},
        {"buried_texels", op_.buried_texels},
        {"gather_rays", op_.rays_traced},
        {"crossings", op_.crossings.size()},
        {"mean_albedo", op_.mean_albedo},
        {"solves",
         {{"groups", groups_.json()}, {"changes", changes_.json()}, {"states", states_.json()}}}};
  }

 private:
  static EmptyRadiance empty(const GroupBounce& g) { return {g.sends[0], g.sends[1], g.sends[2]}; }

  SolveOptions options(float threshold, int threads) const {
    SolveOptions so;
    so.tolerance = kBounceTolerance * threshold * (1.0f - op_.mean_albedo);
    so.max_bounces = 1024;
    so.threads = threads;
    so.reach = reach();
    return so;
  }

  // GatherReach spares reading rays whose sum is 0, but building it reads every stored ray
  // once: built when the solves have read kReachAfter times as many (a scene of one open room,
  // whose few solves see everything, never pays for it). Solves with and without it give the
  // same bits.
  static constexpr uint64_t kReachAfter = 4;
  const GatherReach* reach() const {
    if (reach_built_.load(std::memory_order_acquire)) return &reach_;
    const uint64_t read = groups_.gathers + changes_.gathers + states_.gathers;
    if (read < kReachAfter * uint64_t(op_.hit.size())) return nullptr;
    std::call_once(reach_once_, [&] {
      reach_ = gather_reach(op_, b_.threads);
      reach_built_.store(true, std::memory_order_release);
    });
    return &reach_;
  }

  // Work done by one kind of solve: how many, their bounces and the stored rays they read.
  struct Tally {
    std::atomic<uint64_t> solves{0}, bounces{0}, gathers{0};
    nlohmann::json json() const {
      return {{"solves", solves.load()}, {"bounces", bounces.load()}, {"gathers", gathers.load()}};
    }
  };
  static void count(const SolveStats& st, Tally& t) {
    t.solves += 1;
    t.bounces += uint64_t(st.bounces);
    t.gathers += st.gathers;
  }

  const BakeContext& b_;
  GatherPreset preset_;
  GatherOperator op_;
  mutable GatherReach reach_;
  mutable std::once_flag reach_once_;
  mutable std::atomic<bool> reach_built_{false};
  DenoiseWeights denoise_;  // guided by near_field(op_)
  mutable Tally groups_, changes_, states_;
};

}  // namespace

std::unique_ptr<IndirectIntegrator> make_gather_integrator(const BakeContext& b, GatherStore* store,
                                                           Progress& progress, Report& report) {
  return std::make_unique<GatherIntegrator>(b, store, progress, report);
}

}  // namespace lightpatch::cooker
