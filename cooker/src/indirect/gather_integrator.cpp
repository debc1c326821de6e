// The final-gathering integrator (gather.h, solve.h) behind IndirectIntegrator.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>

#include "indirect/gather.h"
#include "indirect/integrator.h"
#include "indirect/solve.h"
#include "lightpatch/cooker/progress.h"
#include "worker_pool.h"

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

// The near hits as DirectPoints, in the order of a Morton curve over their bounds (10 bits an
// axis).
DirectPoints direct_points_of(const GatherOperator& op, const TexelSet& texels) {
  DirectPoints pts;
  const size_t n = op.near.size();
  pts.height = int((n + size_t(pts.width) - 1) / size_t(pts.width));
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const NearHit& h : op.near) {
    lo = glm::min(lo, h.point);
    hi = glm::max(hi, h.point);
  }
  const glm::vec3 scale = 1023.0f / glm::max(hi - lo, glm::vec3(1e-6f));
  auto spread = [](uint64_t v) {  // 10 bits to every third of 30
    v = (v | (v << 16)) & 0x030000FFull;
    v = (v | (v << 8)) & 0x0300F00Full;
    v = (v | (v << 4)) & 0x030C30C3ull;
    v = (v | (v << 2)) & 0x09249249ull;
    return v;
  };
  std::vector<std::pair<uint64_t, uint32_t>> keyed(n);
  for (size_t i = 0; i < n; ++i) {
    const glm::uvec3 q(glm::clamp((op.near[i].point - lo) * scale, 0.0f, 1023.0f));
    keyed[i] = {(spread(q.x) << 2) | (spread(q.y) << 1) | spread(q.z), uint32_t(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  pts.position.resize(n);
  pts.normal.resize(n);
  pts.index.resize(n);
  pts.texel.resize(n);
  for (size_t p = 0; p < n; ++p) {
    const NearHit& h = op.near[keyed[p].second];
    pts.index[p] = keyed[p].second;
    pts.texel[p] = h.fine;
    pts.position[p] = h.point;
    pts.normal[p] = texels.normal[h.fine];  // the shading normal where it lands
  }
  return pts;
}

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
      go.split_contacts = preset_.contact_texels;
      if (!b.footprints.empty()) go.footprints = &b.footprints;
      op_ = build_gather(b.scene, b.layout, b.texels, b.tracer, preset_.level, go);
      report.stage_time("bake.gather_rays", progress.end());
      if (store) store->save(op_, progress);
    }
    const std::vector<float> near = near_field(op_);
    denoise_ = denoise_weights(op_.grid, preset_.denoise, &near, near_field_sigma(op_.rays));
    points_ = direct_points_of(op_, b.texels);
    near_ = near_index(op_);
  }

  const DirectPoints* direct_points() const override { return &points_; }

  std::vector<GroupBounce> prepare(const std::vector<GroupLight>& groups,
                                   int threads) const override {
    const size_t n = groups.size();
    std::vector<CoarseMap> sources(n);
    std::vector<NearSource> near(n);
    std::vector<const NearSource*> near_of(n, nullptr);
    std::vector<float> tolerance(n);
    parallel_for(int(n), threads, [&](int jj) {
      const size_t j = size_t(jj);
      const GroupLight& g = groups[j];
      sources[j] = coarse_source(op_, b_.texels, *g.direct);
      tolerance[j] = options(g.threshold, threads).tolerance;
      if (g.points) {
        near[j] = near_source(*g.points);
        near_of[j] = &near[j];
      }
    });
    return solve_groups(sources, near_of, tolerance, threads, /*sends=*/true);
  }

  std::vector<GroupBounce> prepare_many(std::vector<FloatImage> direct,
                                        const std::vector<SparsePointLight>& points,
                                        float threshold, int threads) const override {
    const size_t n = direct.size();
    std::vector<CoarseMap> sources(n);
    std::vector<NearSource> near(n);
    std::vector<const NearSource*> near_of(n, nullptr);
    parallel_for(int(n), threads, [&](int jj) {
      const size_t j = size_t(jj);
      sources[j] = coarse_source(op_, b_.texels, direct[j]);
      direct[j] = FloatImage();
      if (j < points.size()) {
        near[j] = near_source(points[j]);
        near_of[j] = &near[j];
      }
    });
    const std::vector<float> tolerance(n, options(threshold, threads).tolerance);
    return solve_groups(sources, near_of, tolerance, threads, /*sends=*/false);
  }

  std::vector<BounceMap> changes(const std::vector<ChangeRequest>& requests, int threads,
                                 std::vector<double>* seconds, Progress* progress) const override {
    const auto t0 = std::chrono::steady_clock::now();
    const size_t n = requests.size();
    // Each group's sends as the solve reads them, once per group.
    std::map<const GroupBounce*, EmptyRadiance> empties;
    for (const ChangeRequest& r : requests) empties.try_emplace(r.group, empty(*r.group));
    std::vector<ChangeJob> jobs(n);
    std::vector<NearSource> near(n);
    parallel_for(int(n), threads, [&](int jj) {
      const size_t j = size_t(jj);
      const ChangeRequest& r = requests[j];
      jobs[j].present = &r.present;
      jobs[j].empty = &empties.at(r.group);
      jobs[j].tolerance = options(r.threshold, threads).tolerance;
      jobs[j].direct_change =
          r.blocked.sparse.empty() && r.blocked.dense.empty()
              ? CoarseMap(op_.grid.size(), glm::vec3(0.0f))
              : coarse_source_of(op_, b_.texels, [&](size_t t) { return r.blocked.at(t); });
      if (!r.blocked_points.sparse.empty() || !r.blocked_points.dense.empty()) {
        near[j] = near_source(r.blocked_points);
        jobs[j].near_change = &near[j];
      }
    });
    std::vector<SolveStats> st;
    std::vector<BounceMap> out =
        solve_changes(op_, jobs, options(0.0f, threads), &st, [&](size_t k) {
          if (progress) progress->advance(k);
        });
    uint64_t total = 0;
    for (const SolveStats& s : st) {
      count(s, changes_);
      total += s.gathers;
    }
    if (seconds) {
      const double spent = seconds_since(t0) * double(std::max(1, std::min(threads, int(n))));
      seconds->resize(n);
      for (size_t j = 0; j < n; ++j)
        (*seconds)[j] =
            total > 0 ? spent * double(st[j].gathers) / double(total) : spent / double(n);
    }
    return out;
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

  float add_blocks(BounceMap map, FloatImage& blocks) const override {
    denoise(op_.grid, denoise_, map);
    blocks = block_image(op_.grid, b_.texels, b_.layout.align, map);
    return magnified_peak(op_.grid, b_.texels, map);
  }

  void add_state(const FloatImage& direct, const PointLight* points,
                 const std::vector<uint8_t>& present, float threshold,
                 FloatImage& fine) const override {
    const CoarseMap source = coarse_source(op_, b_.texels, direct);
    const NearSource near = points ? near_source(*points) : NearSource{};
    SolveStats st;
    add(solve_indirect(op_, present, source, options(threshold, b_.threads), &st,
                       points ? &near : nullptr)
            .total(),
        fine, nullptr);
    count(st, states_);
  }

  std::vector<uint8_t> read_texels() const override {
    auto buried = [&](size_t t) { return t < op_.buried.size() && op_.buried[t] != 0; };
    // hit: some ray lands on the coarse texel; sees: some ray of its own lands on a surface (the
    // outside of a closed room sees nothing, though a grazing ray from a floor texel whose sample
    // point lies on the room's outer edge may land on it).
    const size_t nc = op_.grid.size(), rays = size_t(op_.rays);
    std::vector<uint8_t> hit(nc, 0), sees(nc, 0);
    for (size_t c = 0; c < nc; ++c)
      for (size_t k = 0; k < rays; ++k) {
        const uint32_t h = op_.hit[c * rays + k];
        if (h == kNoTexel) continue;
        hit[h] = 1;
        sees[c] = 1;
      }
    std::vector<uint8_t> read(b_.texels.valid.size(), 0);
    for (size_t t = 0; t < read.size(); ++t) {
      const uint32_t c = op_.grid.coarse_of[t];
      if (c != kNoTexel && hit[c] && sees[c] && !buried(t)) read[t] = 1;
    }
    for (const NearHit& h : op_.near)
      if (h.fine < read.size() && !buried(h.fine)) read[h.fine] = 1;
    return read;
  }

  nlohmann::json describe() const override {
    return {
        {"integrator", "gather"},
        {"level", preset_.level},
        {"rays_per_coarse_texel", preset_.rays},
        {"rays_per_bounce", {op_.level_rays[0], op_.level_rays[1], op_.level_rays[2]}},
        {"denoise_passes", preset_.denoise},
        {"contact_texels_option", preset_.contact_texels},
        {"indirect_map_scale", b_.layout.align},
        {"coarse_texels", op_.grid.size()},
        {"contact_texels", size_t(std::count(op_.grid.fine.begin(), op_.grid.fine.end(), 1))},
        {"buried_texels", op_.buried_texels},
        {"gather_rays", op_.rays_traced},
        {"crossings", op_.crossings.size()},
        {"near_hits", op_.near.size()},
        {"mean_albedo", op_.mean_albedo},
        {"solves",
         {{"groups", groups_.json()}, {"changes", changes_.json()}, {"states", states_.json()}}}};
  }

 private:
  static EmptyRadiance empty(const GroupBounce& g) { return {g.sends[0], g.sends[1], g.sends[2]}; }

  // The near hits' first-bounce source (solve.h NearSource) of `count` lit points, item(k) the
  // k-th as (point p, its light), p ascending, each once: the albedo where each lands times it.
  template <typename Item>
  NearSource near_source_of(size_t count, const Item& item) const {
    NearSource out;
    out.reserve(count);
    for (size_t k = 0; k < count; ++k) {
      const auto [p, v] = item(k);
      if (v == glm::vec3(0.0f)) continue;
      const uint32_t i = points_.index[p];
      out.push_back({i, b_.texels.albedo[op_.near[i].fine] * v});
    }
    return out;
  }
  // From a point image (3 channels, or 1 for grey).
  NearSource near_source(const PointLight& d) const {
    const size_t ch = size_t(d.channels);
    return near_source_of(points_.size(), [&](size_t p) {
      const float* v = d.data.data() + p * ch;
      return std::pair(uint32_t(p), ch == 3 ? glm::vec3(v[0], v[1], v[2]) : glm::vec3(v[0]));
    });
  }
  // From the lit points alone: the same list as near_source(PointLight) of the image they fill.
  NearSource near_source(const SparsePointLight& lit) const {
    return near_source_of(lit.size(), [&](size_t k) { return lit[k]; });
  }
  // From a sum of the passes' point maps: only the points its sparse maps wrote (an object's
  // shadow covers few), every point of its dense ones.
  NearSource near_source(const FineSum& sum) const {
    std::vector<uint32_t> listed;
    const uint32_t n = uint32_t(points_.size());
    if (!sum.dense.empty()) {
      listed.resize(n);
      std::iota(listed.begin(), listed.end(), 0u);
    } else {
      for (const auto& [m, k] : sum.sparse)
        for (int y = 0; y < m->height(); ++y) {
          if (!m->row_written(y)) continue;
          const uint32_t p0 = uint32_t(y) * uint32_t(m->width());
          for (uint32_t p = p0; p < std::min(n, p0 + uint32_t(m->width())); ++p)
            listed.push_back(p);
        }
      std::sort(listed.begin(), listed.end());
      listed.erase(std::unique(listed.begin(), listed.end()), listed.end());
    }
    return near_source_of(listed.size(),
                          [&](size_t k) { return std::pair(listed[k], sum.at(listed[k])); });
  }

  // The bounce light of each source (prepare(), prepare_many()), solved side by side, with what
  // its changes start from where `sends`.
  std::vector<GroupBounce> solve_groups(const std::vector<CoarseMap>& sources,
                                        const std::vector<const NearSource*>& near_of,
                                        const std::vector<float>& tolerance, int threads,
                                        bool sends) const {
    const size_t n = sources.size();
    std::vector<SolveStats> st;
    std::vector<Bounces> bounces =
        solve_indirect_many(op_, sources, near_of, options(0.0f, threads), &st, tolerance);
    std::vector<GroupBounce> out(n);
    parallel_for(int(n), threads, [&](int jj) {
      const size_t j = size_t(jj);
      GroupBounce& g = out[j];
      g.indirect = bounces[j].total();
      if (sends) {
        EmptyRadiance e = empty_radiance(op_, sources[j], bounces[j]);
        g.sends = {std::move(e.direct), std::move(e.first), std::move(e.later)};
      }
      bounces[j] = Bounces{};
      g.peak = peak(g.indirect);
      g.bounces = st[j].bounces;
      g.gathers = st[j].gathers;
    });
    for (size_t j = 0; j < n; ++j) count(st[j], groups_);
    return out;
  }

  SolveOptions options(float threshold, int threads) const {
    SolveOptions so;
    so.tolerance = kBounceTolerance * threshold * (1.0f - op_.mean_albedo);
    so.max_bounces = 1024;
    so.threads = threads;
    so.reach = reach();
    so.near = &near_;
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
  DirectPoints points_;     // op_.near's points
  NearIndex near_;          // near_index(op_)
  mutable Tally groups_, changes_, states_;
};

}  // namespace

std::unique_ptr<IndirectIntegrator> make_gather_integrator(const BakeContext& b, GatherStore* store,
                                                           Progress& progress, Report& report) {
  return std::make_unique<GatherIntegrator>(b, store, progress, report);
}

}  // namespace lightpatch::cooker
