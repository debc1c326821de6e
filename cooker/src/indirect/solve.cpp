#include "indirect/solve.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>

#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {

constexpr uint32_t kChunk = 256;  // receivers per work item
// gather_k prefetches the rays of the receiver this far ahead.
constexpr size_t kPrefetchAhead = 8;

float max3(const glm::vec3& v) {
  return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
}

glm::vec3 at(const CoarseMap& m, uint32_t c) {
  return c == kNoTexel ? glm::vec3(0.0f) : m[c];
}

// The first object of a crossing that is present, as its hit; kNoTexel + false if none is.
bool present_hit(const GatherOperator& op, const Crossing& rec, const std::vector<uint8_t>& present,
                 uint32_t* coarse) {
  for (uint32_t j = rec.first; j < rec.first + rec.count; ++j) {
    const CrossingHit& h = op.crossing_hits[j];
    if (present[size_t(h.object)]) {
      *coarse = h.coarse;
      return true;
    }
  }
  return false;
}

// The rays that `present` changes, per receiver: each ray that now ends on a present object, and
// the coarse texel it ends on there (kNoTexel: the object's back), in ray order. Built once per
// solve from the receivers that cross a present object: every bounce reads it, and a bounce that
// walked every receiver's crossings (most of them through absent objects) spent half its time on
// them.
struct PresentCrossings {
  struct Ray {
    uint32_t ray;
    uint32_t coarse;
  };
  std::vector<uint32_t> offset;  // coarse -> [offset, next) into rays; empty: no object present
  std::vector<Ray> rays;
  std::vector<uint32_t> receivers;  // crossing_receivers(present), ascending
};

// Receivers whose rays can reach a non-zero source, in coarse order: by tiles, then (with
// `reach`) by each receiver's own rays of `level` where that costs less than the rays it spares.
std::vector<uint32_t> receivers_of(const GatherOperator& op, const CoarseMap& src,
                                   const GatherReach* reach, int level) {
  const size_t n_tiles = op.tile_coarse.size();
  std::vector<uint8_t> active(n_tiles, 0);
  for (uint32_t c = 0; c < src.size(); ++c)
    if (src[c] != glm::vec3(0.0f)) active[op.tile_of[c]] = 1;
  // The tiles with a ray into an active tile: from the active tiles where they hold few of the
  // (tile, source) pairs (a source on a few tiles), else by each tile's sources.
  std::vector<uint8_t> lit(n_tiles, 0);
  size_t from_active = 0;
  if (reach)
    for (size_t t = 0; t < n_tiles; ++t)
      if (active[t]) from_active += reach->target_offset[t + 1] - reach->target_offset[t];
  if (reach && 2 * from_active < reach->targets.size()) {
    for (size_t a = 0; a < n_tiles; ++a)
      if (active[a])
        for (uint32_t i = reach->target_offset[a]; i < reach->target_offset[a + 1]; ++i)
          lit[reach->targets[i]] = 1;
  } else {
    for (size_t t = 0; t < n_tiles; ++t)
      for (uint32_t s : op.sources[t])
        if (active[s]) {
          lit[t] = 1;
          break;
        }
  }
  std::vector<uint8_t> take(src.size(), 0);
  size_t taken = 0;
  for (size_t t = 0; t < n_tiles; ++t) {
    if (!lit[t]) continue;
    for (uint32_t c : op.tile_coarse[t]) take[c] = 1;
    taken += op.tile_coarse[t].size();
  }
  if (reach) {
    constexpr size_t kLevels = GatherOperator::kLevels;
    // Tile t's receivers of this level.
    auto first = [&](size_t t) { return reach->offset[t * kLevels]; };
    auto last = [&](size_t t) { return reach->offset[t * kLevels + kLevels - size_t(level)]; };
    size_t cost = 0;
    for (size_t t = 0; t < n_tiles; ++t)
      if (active[t]) cost += last(t) - first(t);
    // A source lit almost everywhere (a group's direct light) is reached by every receiver: the
    // marks would cost more than they spare.
    if (4 * cost < taken * size_t(op.level_rays[level])) {
      std::vector<uint8_t> marked(src.size(), 0);
      for (size_t t = 0; t < n_tiles; ++t)
        if (active[t])
          for (uint32_t i = first(t); i < last(t); ++i) marked[reach->receivers[i]] = 1;
      for (size_t c = 0; c < take.size(); ++c) take[c] &= marked[c];
    }
  }
  std::vector<uint32_t> out;
  for (uint32_t c = 0; c < take.size(); ++c)
    if (take[c]) out.push_back(c);
  return out;
}

// The receivers with a ray that now ends on a present object.
std::vector<uint32_t> crossing_receivers(const GatherOperator& op,
                                         const std::vector<uint8_t>& present) {
  std::vector<uint32_t> crossing;
  for (size_t o = 0; o < present.size(); ++o) {
    if (!present[o]) continue;
    crossing.insert(crossing.end(), op.coarse_crossing[o].begin(), op.coarse_crossing[o].end());
  }
  std::sort(crossing.begin(), crossing.end());
  crossing.erase(std::unique(crossing.begin(), crossing.end()), crossing.end());
  return crossing;
}

PresentCrossings present_crossings(const GatherOperator& op, const std::vector<uint8_t>& present) {
  PresentCrossings pc;
  if (std::none_of(present.begin(), present.end(), [](uint8_t p) { return p != 0; })) return pc;
  const size_t nc = op.grid.size();
  pc.offset.assign(nc + 1, 0);
  pc.receivers = crossing_receivers(op, present);
  for (uint32_t c : pc.receivers) {
    for (uint32_t r = op.crossing_offset[c]; r < op.crossing_offset[c + 1]; ++r) {
      const Crossing& rec = op.crossings[r];
      uint32_t oc = kNoTexel;
      if (!present_hit(op, rec, present, &oc)) continue;
      pc.rays.push_back({rec.ray, oc});
      ++pc.offset[c + 1];
    }
  }
  for (size_t c = 0; c < nc; ++c) pc.offset[c + 1] += pc.offset[c];
  return pc;
}

// Up to this many solves share each bounce's pass over the stored rays (solve_changes): a ray's
// hit reads all their sources from one or two cache lines, interleaved.
constexpr size_t kBatch = kChangeBatch;
static_assert(kBatch == 8, "gather_many has a gather_k for each batch size");

// One source of a batched gather: what it reads, the rays its present objects change, its
// receivers (ascending) and where its result goes.
struct GatherJob {
  const CoarseMap* src;
  const PresentCrossings* present;
  const std::vector<uint32_t>* receivers;
  CoarseMap* out;
};

// Floats per coarse texel in a gather's sources: K RGB sources, padded to whole 4-float vectors.
constexpr size_t stride_of(size_t k) {
  return (3 * k + 3) / 4 * 4;
}

// For K jobs, out[c] = mean over the first rays of `level` of c's rays of the job's source at what
// each ray hits with its present objects in place. Sources interleaved in `src` (coarse c's K at
// [stride_of(K) c, stride_of(K) (c+1))); visits the union of the jobs' receivers. A job's
// receivers are all those whose rays of this level reach a non-zero texel of its source (object
// hits included), so elsewhere its sum is exactly 0, what its own gather leaves there: each job
// gets its own gather's bits (each lane of a vector adds as the scalar sum did).
template <size_t K>
void gather_k(const GatherOperator& op, const float* src, const GatherJob* jobs,
              const std::vector<uint32_t>& receivers, int threads, int level) {
  using V4 = float __attribute__((vector_size(16)));
  constexpr size_t kStride = stride_of(K), kVectors = kStride / 4;
  const int n = op.level_rays[level];
  const std::vector<float>& weight = op.weight[level];
  const int items = int((receivers.size() + kChunk - 1) / kChunk);
  auto at = [&](uint32_t c, size_t j) {
    if (c == kNoTexel) return glm::vec3(0.0f);
    const float* v = src + size_t(c) * kStride + 3 * j;
    return glm::vec3(v[0], v[1], v[2]);
  };
  parallel_for(items, threads, [&](int item) {
    const size_t end = std::min(receivers.size(), size_t(item + 1) * kChunk);
    for (size_t i = size_t(item) * kChunk; i < end; ++i) {
      // Each receiver reads a row (or a prefix of it) far from the last one: the hardware
      // prefetcher does not see it coming, and waiting for it took half the gather's time.
      if (i + kPrefetchAhead < end) {
        const uint32_t* ahead = op.hit.data() + size_t(receivers[i + kPrefetchAhead]) * op.rays;
        for (int k = 0; k < n; k += 16) __builtin_prefetch(ahead + k);  // 16 rays a cache line
      }
      const uint32_t c = receivers[i];
      const uint32_t* hits = op.hit.data() + size_t(c) * size_t(op.rays);
      V4 acc[kVectors] = {};  // registers: the sum of every source at once
      const int rays = std::min(n, op.traced_rays(c));  // the rest are kNoTexel
      for (int k = 0; k < rays; ++k) {
        if (hits[k] == kNoTexel) continue;
        const float* v = src + size_t(hits[k]) * kStride;
#pragma GCC unroll 8
        for (size_t q = 0; q < kVectors; ++q) {
          V4 x;
          std::memcpy(&x, v + 4 * q, sizeof x);
          acc[q] += x;
        }
      }
      float sum[kStride];
      std::memcpy(sum, acc, sizeof acc);
      for (size_t j = 0; j < K; ++j) {
        glm::vec3 v(sum[3 * j], sum[3 * j + 1], sum[3 * j + 2]);
        const PresentCrossings& present = *jobs[j].present;
        if (!present.offset.empty()) {
          for (uint32_t r = present.offset[c]; r < present.offset[c + 1]; ++r) {
            const PresentCrossings::Ray x = present.rays[r];
            if (int(x.ray) >= n) break;  // in ray order
            v += at(x.coarse, j) - at(hits[x.ray], j);
          }
        }
        (*jobs[j].out)[c] = v * weight[c];
      }
    }
  });
}

// A pass grown job by job while sharing it costs less than a pass each: K jobs (at most kBatch)
// whose receivers number `visits` in all and `united` without repeats. A shared pass visits the
// union, each receiver at about 1 + (K - 1) / 3 of one job's cost (one read of its rays, wider
// sums); separate passes visit each job's own. Changes in one room share most receivers; in
// different rooms a shared pass would sum K sources where each has one.
class SharedPass {
 public:
  explicit SharedPass(size_t nc) : nc_(nc) {}
  void start(const std::vector<uint32_t>& receivers) {
    first_ = &receivers;
    marked_ = false;
    jobs_ = 1;
    visits_ = united_ = receivers.size();
  }
  // Adds a job's receivers if the pass is still worth sharing with them.
  bool add(const std::vector<uint32_t>& receivers) {
    if (!marked_) {  // marked only once a second job is asked about
      mark_.assign(nc_, 0);
      for (uint32_t c : *first_) mark_[c] = 1;
      marked_ = true;
    }
    size_t fresh = 0;
    for (uint32_t c : receivers) fresh += mark_[c] ? 0 : 1;
    const size_t k = jobs_ + 1, united = united_ + fresh, visits = visits_ + receivers.size();
    if (k > kBatch || united * (k + 2) > 3 * visits) return false;
    for (uint32_t c : receivers) mark_[c] = 1;
    jobs_ = k;
    united_ = united;
    visits_ = visits;
    return true;
  }
  // The union of the jobs' receivers, ascending.
  void receivers(std::vector<uint32_t>& out) const {
    out.clear();
    if (!marked_) {
      out = *first_;
      return;
    }
    for (uint32_t c = 0; c < nc_; ++c)
      if (mark_[c]) out.push_back(c);
  }

 private:
  size_t nc_;
  const std::vector<uint32_t>* first_ = nullptr;
  std::vector<uint8_t> mark_;
  bool marked_ = false;
  size_t jobs_ = 0, visits_ = 0, united_ = 0;
};

// Every job's gather of `level` (gather_k), outputs untouched beyond their receivers (the caller
// zeroes them). Jobs in order share a pass while SharedPass says so.
void gather_many(const GatherOperator& op, const std::vector<GatherJob>& jobs, int threads,
                 int level) {
  const size_t nc = op.grid.size();
  std::vector<float> mixed;
  std::vector<uint32_t> all;
  SharedPass pass(nc);
  for (size_t first = 0, end = 0; first < jobs.size(); first = end) {
    pass.start(*jobs[first].receivers);
    end = first + 1;
    while (end < jobs.size() && pass.add(*jobs[end].receivers)) ++end;
    const size_t k = end - first;
    const GatherJob* batch = jobs.data() + first;
    const std::vector<uint32_t>* receivers = batch[0].receivers;
    if (k > 1) {
      pass.receivers(all);
      receivers = &all;
    }
    // Sources interleaved and padded, so that a ray's hit reads them in whole vectors.
    const size_t stride = stride_of(k);
    mixed.assign(nc * stride, 0.0f);
    for (size_t j = 0; j < k; ++j) {
      const CoarseMap& m = *batch[j].src;
      for (size_t c = 0; c < nc; ++c) {
        float* v = mixed.data() + c * stride + 3 * j;
        v[0] = m[c].x;
        v[1] = m[c].y;
        v[2] = m[c].z;
      }
    }
    const float* src = mixed.data();
    using Gather = void (*)(const GatherOperator&, const float*, const GatherJob*,
                            const std::vector<uint32_t>&, int, int);
    static constexpr Gather kGather[kBatch] = {gather_k<1>, gather_k<2>, gather_k<3>, gather_k<4>,
                                               gather_k<5>, gather_k<6>, gather_k<7>, gather_k<8>};
    kGather[k - 1](op, src, batch, *receivers, threads, level);
  }
}

// The near hits' first bounce: each reads `near` (its own point's source) instead of `src` at the
// texel it lands on. Near rays cross no object, so `present` moves none of them.
void add_near(const GatherOperator& op, const NearIndex& index, const CoarseMap& src,
              const NearSource& near, CoarseMap& first) {
  const std::vector<float>& weight = op.weight[0];
  for (const auto& [i, v] : near) {
    const uint32_t c = index.receiver[i];
    first[c] += (weight[c] * float(op.near[i].count)) * v;
  }
  for (uint32_t h = 0; h + 1 < index.by_hit_offset.size(); ++h) {
    if (src[h] == glm::vec3(0.0f)) continue;
    for (uint32_t k = index.by_hit_offset[h]; k < index.by_hit_offset[h + 1]; ++k) {
      const uint32_t i = index.by_hit[k], c = index.receiver[i];
      first[c] -= (weight[c] * float(op.near[i].count)) * src[h];
    }
  }
}

// Drops terms below the tolerance; returns whether any is left.
bool prune(CoarseMap& delta, float tolerance) {
  bool any = false;
  for (glm::vec3& v : delta) {
    if (max3(v) < tolerance)
      v = glm::vec3(0.0f);
    else
      any = true;
  }
  return any;
}

// For receiver c and the series term of `level`: what c's rays of that level that now end on a
// present object no longer see (the static hit's `radiance`) against what they see instead.
glm::vec3 crossing_change(const GatherOperator& op, const PresentCrossings& present,
                          const CoarseMap& radiance, int level, uint32_t c) {
  glm::vec3 sum(0.0f);
  for (uint32_t r = present.offset[c]; r < present.offset[c + 1]; ++r) {
    const PresentCrossings::Ray x = present.rays[r];
    if (int(x.ray) >= op.level_rays[level]) break;
    sum += at(radiance, op.hit[size_t(c) * size_t(op.rays) + x.ray]) - at(radiance, x.coarse);
  }
  return sum * op.weight[level][c];
}

// One Neumann series for run_series: bounce b gathers albedo * term b-1 through the rays of its
// level, plus `extra[b]` (a change's crossing terms) where not empty. Each map is freed once read:
// eight changes side by side, two batches at once, hold sixteen series.
struct Series {
  const PresentCrossings* present = nullptr;
  float tolerance = 0.0f;  // SolveOptions::tolerance for this series
  CoarseMap first;         // the first bounce
  CoarseMap extra_second, extra_rest;
  SolveStats* stats = nullptr;
  Bounces out;  // its terms: the first, the second and the rest summed
};

// Runs the series side by side, bounce by bounce, each bounce's gathers in one gather_many; a
// series stops when its term is pruned to nothing and no extra is left.
void run_series(const GatherOperator& op, std::vector<Series>& series,
                const SolveOptions& options) {
  const CoarseGrid& g = op.grid;
  const size_t nc = g.size(), n = series.size();
  std::vector<CoarseMap> delta(n), next(n);
  std::vector<std::vector<uint32_t>> receivers(n);
  std::vector<uint8_t> running(n, 1), gathers(n, 0);
  for (size_t j = 0; j < n; ++j) {
    Series& s = series[j];
    s.out.second.assign(nc, glm::vec3(0.0f));
    s.out.rest.assign(nc, glm::vec3(0.0f));
    delta[j] = s.first;
    s.out.first = std::move(s.first);
    if (s.stats) s.stats->bounces = 1;
  }
  const int jobs_threads = std::min(options.threads, int(n));
  for (int b = 1; b < options.max_bounces; ++b) {
    const int level = GatherOperator::level_of(b);
    auto extra_of = [&](Series& s) -> CoarseMap* {
      CoarseMap* e = b == 1 ? &s.extra_second : b == 2 ? &s.extra_rest : nullptr;
      return e && !e->empty() ? e : nullptr;
    };
    parallel_for(int(n), jobs_threads, [&](int jj) {
      const size_t j = size_t(jj);
      gathers[j] = 0;
      if (!running[j]) return;
      const bool any = prune(delta[j], series[j].tolerance);
      if (!any && !extra_of(series[j])) {
        running[j] = 0;
        CoarseMap().swap(delta[j]);
        CoarseMap().swap(next[j]);
        return;
      }
      for (size_t c = 0; c < nc; ++c) delta[j][c] *= g.albedo[c];
      next[j].assign(nc, glm::vec3(0.0f));
      if (any) {
        receivers[j] = receivers_of(op, delta[j], options.reach, level);
        gathers[j] = 1;
        if (series[j].stats)
          series[j].stats->gathers +=
              uint64_t(receivers[j].size()) * uint64_t(op.level_rays[level]);
      }
    });
    if (std::find(running.begin(), running.end(), uint8_t(1)) == running.end()) break;
    std::vector<GatherJob> jobs;
    for (size_t j = 0; j < n; ++j)
      if (gathers[j]) jobs.push_back({&delta[j], series[j].present, &receivers[j], &next[j]});
    gather_many(op, jobs, options.threads, level);
    parallel_for(int(n), jobs_threads, [&](int jj) {
      const size_t j = size_t(jj);
      if (!running[j]) return;
      Series& s = series[j];
      if (CoarseMap* extra = extra_of(s)) {
        for (size_t c = 0; c < nc; ++c) next[j][c] += (*extra)[c];
        CoarseMap().swap(*extra);
      }
      CoarseMap& sum = b == 1 ? s.out.second : s.out.rest;
      for (size_t c = 0; c < nc; ++c) sum[c] += next[j][c];
      if (s.stats) s.stats->bounces = b + 1;
      delta[j].swap(next[j]);
    });
  }
}

}  // namespace

GatherReach gather_reach(const GatherOperator& op, int threads) {
  constexpr uint32_t kLevels = GatherOperator::kLevels;
  const size_t nc = op.grid.size(), n_tiles = op.tile_coarse.size();
  // A ray's class: how many levels leave it out (levels read prefixes, shorter level by level),
  // so a receiver is in level l's list of a tile if its first ray there has class < kLevels - l.
  auto class_of = [&](int k) {
    uint32_t cls = 0;
    for (uint32_t l = 0; l < kLevels; ++l) cls += k >= op.level_rays[l] ? 1 : 0;
    return cls;
  };
  // Calls emit(c, key) once for each tile that a receiver c of `item` reaches, key = tile *
  // kLevels + the class of its first ray there; receivers in ascending order.
  constexpr size_t kItems = 16;  // few: each item keeps a count per key
  const size_t per_item = (nc + kItems - 1) / kItems;
  auto walk = [&](size_t item, auto&& emit) {
    std::vector<uint32_t> seen(n_tiles, kNoTexel);  // tile -> the receiver that last listed it
    const uint32_t end = uint32_t(std::min(nc, (item + 1) * per_item));
    for (uint32_t c = uint32_t(item * per_item); c < end; ++c) {
      const uint32_t* hits = op.hit.data() + size_t(c) * size_t(op.rays);
      uint32_t rec = op.crossing_offset[c];
      const int rays = op.traced_rays(c);
      for (int k = 0; k < rays; ++k) {
        const uint32_t cls = class_of(k);
        auto add = [&](uint32_t coarse) {
          if (coarse == kNoTexel) return;
          const uint32_t t = op.tile_of[coarse];
          if (seen[t] == c) return;
          seen[t] = c;
          emit(c, t * kLevels + cls);
        };
        add(hits[k]);
        for (; rec < op.crossing_offset[c + 1] && int(op.crossings[rec].ray) == k; ++rec) {
          const Crossing& cr = op.crossings[rec];
          for (uint32_t j = cr.first; j < cr.first + cr.count; ++j) add(op.crossing_hits[j].coarse);
        }
      }
    }
  };
  // A counting sort by key in two walks (no list of every pair held): count per item and key,
  // then write each item's receivers after the earlier items' of the same key.
  const size_t n_keys = n_tiles * kLevels;
  std::vector<uint32_t> at(kItems * n_keys, 0);
  parallel_for(int(kItems), threads, [&](int item) {
    uint32_t* count = at.data() + size_t(item) * n_keys;
    walk(size_t(item), [&](uint32_t, uint32_t key) { ++count[key]; });
  });
  GatherReach r;
  r.offset.assign(n_keys + 1, 0);
  uint32_t total = 0;
  for (size_t key = 0; key < n_keys; ++key) {
    r.offset[key] = total;
    for (size_t item = 0; item < kItems; ++item) {
      const uint32_t n = at[item * n_keys + key];
      at[item * n_keys + key] = total;
      total += n;
    }
  }
  r.offset[n_keys] = total;
  r.receivers.resize(total);
  parallel_for(int(kItems), threads, [&](int item) {
    uint32_t* next = at.data() + size_t(item) * n_keys;
    walk(size_t(item), [&](uint32_t c, uint32_t key) { r.receivers[next[key]++] = c; });
  });
  r.target_offset.assign(n_tiles + 1, 0);
  for (const std::vector<uint32_t>& from : op.sources)
    for (uint32_t s : from) ++r.target_offset[s + 1];
  for (size_t t = 0; t < n_tiles; ++t) r.target_offset[t + 1] += r.target_offset[t];
  r.targets.resize(r.target_offset[n_tiles]);
  std::vector<uint32_t> fill(r.target_offset.begin(), r.target_offset.end() - 1);
  for (size_t t = 0; t < n_tiles; ++t)
    for (uint32_t s : op.sources[t]) r.targets[fill[s]++] = uint32_t(t);
  return r;
}

CoarseMap coarse_source(const GatherOperator& op, const TexelSet& texels, const FloatImage& d) {
  const size_t ch = size_t(d.channels);
  return coarse_source_of(op, texels, [&](size_t t) {
    const float* v = d.data.data() + t * ch;
    return ch == 3 ? glm::vec3(v[0], v[1], v[2]) : glm::vec3(v[0]);
  });
}

NearIndex near_index(const GatherOperator& op) {
  NearIndex x;
  const size_t nc = op.grid.size(), n = op.near.size();
  x.receiver.resize(n);
  x.by_hit_offset.assign(nc + 1, 0);
  auto hit_of = [&](uint32_t i) {
    return op.hit[size_t(x.receiver[i]) * size_t(op.rays) + op.near[i].ray];
  };
  for (size_t c = 0; c < nc; ++c)
    for (uint32_t i = op.near_offset[c]; i < op.near_offset[c + 1]; ++i)
      x.receiver[i] = uint32_t(c);
  for (uint32_t i = 0; i < n; ++i)
    if (hit_of(i) != kNoTexel) ++x.by_hit_offset[hit_of(i) + 1];
  for (size_t h = 0; h < nc; ++h) x.by_hit_offset[h + 1] += x.by_hit_offset[h];
  x.by_hit.resize(x.by_hit_offset[nc]);
  std::vector<uint32_t> next(x.by_hit_offset.begin(), x.by_hit_offset.end() - 1);
  for (uint32_t i = 0; i < n; ++i)
    if (hit_of(i) != kNoTexel) x.by_hit[next[hit_of(i)]++] = i;
  return x;
}

CoarseMap Bounces::total() const {
  CoarseMap out(first.size());
  for (size_t c = 0; c < out.size(); ++c) out[c] = first[c] + second[c] + rest[c];
  return out;
}

namespace {

// One source of solve_sources: what it reads at the near hits (may be null), where its
// statistics go (may be null) and its series' tolerance.
struct SourceJob {
  const CoarseMap* source;
  const NearSource* near;
  SolveStats* stats;
  float tolerance;
};

// The series of each source with the objects of `crossings` in place, side by side: the first
// bounce's gathers in one gather_many, then run_series.
std::vector<Bounces> solve_sources(const GatherOperator& op, const PresentCrossings& crossings,
                                   const std::vector<SourceJob>& jobs,
                                   const SolveOptions& options) {
  const size_t n = jobs.size();
  std::vector<std::vector<uint32_t>> receivers(n);
  std::vector<Series> series(n);
  std::vector<GatherJob> gathers(n);
  parallel_for(int(n), std::min(options.threads, int(n)), [&](int jj) {
    const size_t j = size_t(jj);
    const CoarseMap& source = *jobs[j].source;
    receivers[j] = receivers_of(op, source, options.reach, 0);
    series[j].present = &crossings;
    series[j].tolerance = jobs[j].tolerance;
    series[j].stats = jobs[j].stats;
    series[j].first.assign(source.size(), glm::vec3(0.0f));
    gathers[j] = {&source, &crossings, &receivers[j], &series[j].first};
  });
  gather_many(op, gathers, options.threads, 0);
  for (size_t j = 0; j < n; ++j) {
    if (jobs[j].near) add_near(op, *options.near, *jobs[j].source, *jobs[j].near, series[j].first);
    if (jobs[j].stats) jobs[j].stats->gathers += uint64_t(receivers[j].size()) * uint64_t(op.rays);
  }
  run_series(op, series, options);
  std::vector<Bounces> out(n);
  for (size_t j = 0; j < n; ++j) out[j] = std::move(series[j].out);
  return out;
}

}  // namespace

Bounces solve_indirect(const GatherOperator& op, const std::vector<uint8_t>& present,
                       const CoarseMap& source, const SolveOptions& options, SolveStats* stats,
                       const NearSource* near) {
  const PresentCrossings crossings = present_crossings(op, present);
  return std::move(
      solve_sources(op, crossings, {{&source, near, stats, options.tolerance}}, options)[0]);
}

std::vector<Bounces> solve_indirect_many(const GatherOperator& op,
                                         const std::vector<CoarseMap>& sources,
                                         const std::vector<const NearSource*>& near,
                                         const SolveOptions& options,
                                         std::vector<SolveStats>* stats,
                                         const std::vector<float>& tolerance) {
  const size_t n = sources.size();
  if (stats) stats->assign(n, SolveStats{});
  std::vector<SourceJob> jobs(n);
  for (size_t j = 0; j < n; ++j)
    jobs[j] = {&sources[j], j < near.size() ? near[j] : nullptr, stats ? &(*stats)[j] : nullptr,
               tolerance.empty() ? options.tolerance : tolerance[j]};
  const PresentCrossings none;  // no object present: no ray changes
  return solve_sources(op, none, jobs, options);
}

EmptyRadiance empty_radiance(const GatherOperator& op, const CoarseMap& source,
                             const Bounces& bounces) {
  EmptyRadiance e;
  e.direct = source;
  e.first.resize(source.size());
  e.later.resize(source.size());
  for (size_t c = 0; c < source.size(); ++c) {
    e.first[c] = op.grid.albedo[c] * bounces.first[c];
    e.later[c] = op.grid.albedo[c] * (bounces.second[c] + bounces.rest[c]);
  }
  return e;
}

std::vector<CoarseMap> solve_changes(const GatherOperator& op, const std::vector<ChangeJob>& jobs,
                                     const SolveOptions& options, std::vector<SolveStats>* stats,
                                     const std::function<void(size_t)>& done) {
  const size_t nc = op.grid.size(), n = jobs.size();
  if (stats) stats->assign(n, SolveStats{});
  // Each term of I(present) reads through its rays what the previous term sends on; where a ray
  // now ends on an object, what the static hit sent in the empty series (the same term) is
  // replaced by what the object sends: the crossing terms, one per level. Built once for each
  // set of present objects.
  std::map<std::vector<uint8_t>, size_t> set_of;
  std::vector<size_t> uses(n);
  std::vector<const std::vector<uint8_t>*> sets;
  for (size_t j = 0; j < n; ++j) {
    const auto [it, fresh] = set_of.try_emplace(*jobs[j].present, sets.size());
    if (fresh) sets.push_back(jobs[j].present);
    uses[j] = it->second;
  }
  std::vector<PresentCrossings> crossings(sets.size());
  parallel_for(int(sets.size()), options.threads,
               [&](int i) { crossings[size_t(i)] = present_crossings(op, *sets[size_t(i)]); });
  std::vector<std::vector<uint32_t>> receivers(n);
  parallel_for(int(n), options.threads, [&](int jj) {
    const size_t j = size_t(jj);
    // The blocked direct light reaches only the receivers whose rays can see it (rays that now
    // end on an object included: their tiles are among each tile's sources).
    receivers[j] = receivers_of(op, jobs[j].direct_change, options.reach, 0);
  });
  // Batches of jobs whose first bounces share a pass (SharedPass), each job with the later ones
  // of the next few not yet taken; the batches are solved in parallel, each series in lockstep.
  constexpr size_t kLookAhead = kBatch;  // each look reads a job's receivers
  std::vector<std::vector<size_t>> batches;
  std::vector<uint8_t> taken(n, 0);
  SharedPass pass(nc);
  for (size_t j = 0; j < n; ++j) {
    if (taken[j]) continue;
    std::vector<size_t> batch = {j};
    taken[j] = 1;
    pass.start(receivers[j]);
    for (size_t i = j + 1, seen = 0; i < n && seen < kLookAhead && batch.size() < kBatch; ++i) {
      if (taken[i]) continue;
      ++seen;
      if (!pass.add(receivers[i])) continue;
      batch.push_back(i);
      taken[i] = 1;
    }
    batches.push_back(std::move(batch));
  }
  // Batches in parallel, each on one thread; a single batch gets them all.
  SolveOptions inner = options;
  inner.threads = batches.size() > 1 ? 1 : options.threads;
  std::vector<CoarseMap> out(n);
  parallel_for(int(batches.size()), options.threads, [&](int bi) {
    const std::vector<size_t>& batch = batches[size_t(bi)];
    const size_t k = batch.size();
    std::vector<Series> series(k);
    std::vector<GatherJob> gather(k);
    for (size_t i = 0; i < k; ++i) {
      const size_t j = batch[i];
      series[i].first.assign(nc, glm::vec3(0.0f));
      gather[i] = {&jobs[j].direct_change, &crossings[uses[j]], &receivers[j], &series[i].first};
    }
    gather_many(op, gather, inner.threads, 0);
    for (size_t i = 0; i < k; ++i) {
      const size_t j = batch[i];
      Series& s = series[i];
      const PresentCrossings& cross = crossings[uses[j]];
      const EmptyRadiance& empty = *jobs[j].empty;
      if (jobs[j].near_change)
        add_near(op, *options.near, jobs[j].direct_change, *jobs[j].near_change, s.first);
      s.extra_second.assign(nc, glm::vec3(0.0f));
      s.extra_rest.assign(nc, glm::vec3(0.0f));
      for (uint32_t c : cross.receivers) {
        s.first[c] += crossing_change(op, cross, empty.direct, 0, c);
        s.extra_second[c] += crossing_change(op, cross, empty.first, 1, c);
        s.extra_rest[c] += crossing_change(op, cross, empty.later, 2, c);
      }
      s.present = &cross;
      s.tolerance = jobs[j].tolerance;
      if (stats) {
        s.stats = &(*stats)[j];
        s.stats->gathers += uint64_t(receivers[j].size()) * uint64_t(op.rays);
      }
    }
    run_series(op, series, inner);
    for (size_t i = 0; i < k; ++i) {
      out[batch[i]] = series[i].out.total();
      series[i].out = Bounces{};
    }
    if (done) done(k);
  });
  return out;
}

CoarseMap solve_change(const GatherOperator& op, const std::vector<uint8_t>& present,
                       const EmptyRadiance& empty, const CoarseMap& direct_change,
                       const SolveOptions& options, SolveStats* stats,
                       const NearSource* near_change) {
  std::vector<SolveStats> st;
  CoarseMap out = std::move(solve_changes(
      op, {{&present, direct_change, near_change, &empty, options.tolerance}}, options, &st)[0]);
  if (stats) {
    stats->bounces = st[0].bounces;
    stats->gathers += st[0].gathers;
  }
  return out;
}

float first_change_peak(const GatherOperator& op, const std::vector<uint8_t>& present,
                        const EmptyRadiance& empty) {
  float best = 0.0f;
  const PresentCrossings crossings = present_crossings(op, present);
  for (uint32_t c : crossings.receivers) {
    const glm::vec3 v = crossing_change(op, crossings, empty.direct, 0, c) +
                        crossing_change(op, crossings, empty.first, 1, c) +
                        crossing_change(op, crossings, empty.later, 2, c);
    best = std::max(best, max3(v));
  }
  return best;
}

namespace {

// World distance between neighbouring coarse texels (median over the grid): the scale of the
// denoiser's plane-distance weight and of the near field.
float coarse_spacing(const CoarseGrid& grid) {
  const size_t nc = grid.size();
  std::vector<float> gaps;
  for (uint32_t c = 0; c < nc; c += std::max<uint32_t>(1, uint32_t(nc / 4096))) {
    const uint32_t r = grid.link(c, 0, 1, 0);
    if (r != kNoTexel) gaps.push_back(glm::length(grid.position[r] - grid.position[c]));
  }
  if (gaps.empty()) return 1.0f;
  std::nth_element(gaps.begin(), gaps.begin() + long(gaps.size() / 2), gaps.end());
  return std::max(gaps[gaps.size() / 2], 1e-12f);
}

}  // namespace

std::vector<float> near_field(const GatherOperator& op) {
  const CoarseGrid& grid = op.grid;
  const float reach = kNearFieldSpacings * coarse_spacing(grid);
  std::vector<float> out(grid.size(), 0.0f);
  if (op.rays <= 0) return out;
  std::vector<uint32_t> first(size_t(op.rays));  // what each of c's rays meets first
  for (size_t c = 0; c < grid.size(); ++c) {
    std::copy_n(op.hit.begin() + ptrdiff_t(c * size_t(op.rays)), op.rays, first.begin());
    // An object the ray crosses lies in front of its static hit (the nearest is listed first).
    for (uint32_t k = op.crossing_offset[c]; k < op.crossing_offset[c + 1]; ++k) {
      const Crossing& x = op.crossings[k];
      if (x.count > 0) first[x.ray] = op.crossing_hits[x.first].coarse;
    }
    float sum = 0.0f;
    for (const uint32_t h : first) {
      if (h >= grid.size()) continue;  // a miss or the back of a surface: far
      sum += std::exp(-glm::length(grid.position[h] - grid.position[c]) / reach);
    }
    // The mean over the rays it traced (a split texel traces fewer, gather.h fine_ray_count).
    out[c] = sum / float(op.traced_rays(uint32_t(c)));
  }
  return out;
}

float near_field_sigma(int rays) {
  return std::max(kNearFieldSigma, 1.0f / std::sqrt(float(std::max(rays, 1))));
}

DenoiseWeights denoise_weights(const CoarseGrid& grid, int levels, const std::vector<float>* near,
                               float near_sigma) {
  DenoiseWeights dw;
  dw.levels = std::max(0, std::min(levels, CoarseGrid::kLinkSteps));
  const size_t nc = grid.size();
  if (dw.levels == 0 || nc == 0) return dw;
  constexpr size_t kTaps = DenoiseWeights::kTaps;
  dw.weight.assign(size_t(dw.levels) * nc * kTaps, 0.0f);
  dw.total.assign(size_t(dw.levels) * nc, 0.0f);
  const float spacing = coarse_spacing(grid);
  constexpr float kKernel[3] = {0.25f, 0.5f, 0.25f};
  // Per texel, passes after the first blend open texels only (kOpenNearField): each texel's
  // openness, once.
  std::vector<float> open;
  if (near && grid.level == 1 && dw.levels > 1) {
    open.resize(nc);
    for (uint32_t c = 0; c < nc; ++c) {
      const float r = (*near)[c] / kOpenNearField;
      open[c] = std::exp(-r * r);
    }
  }
  for (int level = 0; level < dw.levels; ++level) {
    const float sigma = float(1 << level) * spacing;
    for (uint32_t c = 0; c < nc; ++c) {
      const size_t at = size_t(level) * nc + c;
      float wsum = 0.0f;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const uint32_t q = dx == 0 && dy == 0 ? c : grid.link(c, level, dx, dy);
          if (q == kNoTexel || !grid.alive[q]) continue;
          // A texel split from a block at a contact reads only other such texels: filtered with
          // the open surface beside it, it lost the contact again.
          if (q != c && grid.fine[c] && !grid.fine[q]) continue;
          const float nd = std::max(0.0f, glm::dot(grid.normal[c], grid.normal[q]));
          const float n2 = nd * nd, n4 = n2 * n2;
          const float plane = glm::dot(grid.normal[c], grid.position[q] - grid.position[c]) / sigma;
          float w = kKernel[dx + 1] * kKernel[dy + 1] * n4 * n4 * std::exp(-plane * plane);
          if (near) {
            const float dn = ((*near)[c] - (*near)[q]) / near_sigma;
            w *= std::exp(-dn * dn);
          }
          if (level > 0 && !open.empty() && q != c) w *= std::min(open[c], open[q]);
          dw.weight[at * kTaps + size_t((dy + 1) * 3 + dx + 1)] = w;
          wsum += w;
        }
      }
      dw.total[at] = wsum;
    }
  }
  return dw;
}

void denoise(const CoarseGrid& grid, const DenoiseWeights& weights, CoarseMap& map) {
  if (weights.levels <= 0 || map.empty()) return;
  const size_t nc = map.size();
  constexpr size_t kTaps = DenoiseWeights::kTaps;
  CoarseMap out(nc);
  for (int level = 0; level < weights.levels; ++level) {
    for (uint32_t c = 0; c < nc; ++c) {
      const size_t at = size_t(level) * nc + c;
      const float* w = weights.weight.data() + at * kTaps;
      glm::vec3 sum(0.0f);
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const uint32_t q = dx == 0 && dy == 0 ? c : grid.link(c, level, dx, dy);
          if (q == kNoTexel || !grid.alive[q]) continue;
          sum += w[(dy + 1) * 3 + dx + 1] * map[q];
        }
      }
      const float wsum = weights.total[at];
      out[c] = wsum > 0.0f ? sum / wsum : map[c];
    }
    map.swap(out);
  }
}

void denoise(const CoarseGrid& grid, int levels, CoarseMap& map, const std::vector<float>* near,
             float near_sigma) {
  if (levels <= 0 || map.empty()) return;
  denoise(grid, denoise_weights(grid, levels, near, near_sigma), map);
}

FloatImage block_image(const CoarseGrid& grid, const TexelSet& texels, int s,
                       const CoarseMap& map) {
  const int bw = texels.width / s, bh = texels.height / s;
  FloatImage out(bw, bh, 3);
  std::vector<float> count(size_t(bw) * bh, 0.0f);
  std::vector<int32_t> region(size_t(bw) * bh, -1);
  for (int y = 0; y < bh * s; ++y)
    for (int x = 0; x < bw * s; ++x) {
      const size_t t = texels.index(x, y);
      const size_t b = size_t(y / s) * bw + size_t(x / s);
      if (region[b] < 0) region[b] = texels.region[t];
      const uint32_t c = grid.coarse_of[t];
      if (!texels.valid[t] || c == kNoTexel || !grid.alive[c]) continue;
      for (int ch = 0; ch < 3; ++ch) out.data[b * 3 + size_t(ch)] += map[c][ch];
      count[b] += 1.0f;
    }
  for (size_t b = 0; b < count.size(); ++b)
    if (count[b] > 0.0f)
      for (int ch = 0; ch < 3; ++ch) out.data[b * 3 + size_t(ch)] /= count[b];
  // Rings: blocks without a value take the mean of their valued neighbours of the same region.
  std::vector<uint8_t> filled(count.size());
  for (size_t b = 0; b < count.size(); ++b) filled[b] = count[b] > 0.0f;
  for (int ring = 0; ring < 2; ++ring) {
    std::vector<std::pair<size_t, glm::vec3>> fill;
    for (int by = 0; by < bh; ++by)
      for (int bx = 0; bx < bw; ++bx) {
        const size_t b = size_t(by) * bw + size_t(bx);
        // Blocks outside every region too: a chart that reaches its region's edge (a node's
        // TEXCOORD_1 layout filling its rectangle, the page's edge) reads them.
        if (filled[b]) continue;
        glm::vec3 sum(0.0f);
        float n = 0.0f;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = bx + dx, ny = by + dy;
            if (nx < 0 || ny < 0 || nx >= bw || ny >= bh) continue;
            const size_t q = size_t(ny) * bw + size_t(nx);
            if (!filled[q] || (region[b] >= 0 && region[q] != region[b])) continue;
            sum += glm::vec3(out.data[q * 3], out.data[q * 3 + 1], out.data[q * 3 + 2]);
            n += 1.0f;
          }
        if (n > 0.0f) fill.push_back({b, sum / n});
      }
    for (const auto& [b, v] : fill) {
      for (int ch = 0; ch < 3; ++ch) out.data[b * 3 + size_t(ch)] = v[ch];
      filled[b] = 1;
    }
  }
  return out;
}

namespace {

// Calls out(x, y, v) with the magnified value v of every light-map texel (x, y) that has a
// coarse texel: add_magnified's and magnified_peak's one rule.
template <typename Out>
void magnify(const CoarseGrid& grid, const TexelSet& texels, const CoarseMap& map, Out&& out) {
  const int k = grid.level;
  const float inv_k = 1.0f / float(k);
  for (int y = 0; y < texels.height; ++y) {
    for (int x = 0; x < texels.width; ++x) {
      const size_t t = texels.index(x, y);
      const uint32_t own = grid.coarse_of[t];
      if (own == kNoTexel) continue;
      glm::vec3 v;
      if ((k == 1 || grid.fine[own]) && grid.alive[own]) {
        v = map[own];
      } else {
        const float cx = (float(x) + 0.5f) * inv_k - 0.5f, cy = (float(y) + 0.5f) * inv_k - 0.5f;
        const int x0 = int(std::floor(cx)), y0 = int(std::floor(cy));
        const float fx = cx - float(x0), fy = cy - float(y0);
        const uint32_t b = grid.block_of[own];
        const int obx = int(b % uint32_t(grid.width)), oby = int(b / uint32_t(grid.width));
        glm::vec3 sum(0.0f);
        float wsum = 0.0f;
        for (int j = 0; j < 2; ++j) {
          for (int i = 0; i < 2; ++i) {
            const int dx = x0 + i - obx, dy = y0 + j - oby;
            const uint32_t q = dx == 0 && dy == 0 ? own : grid.link(own, 0, dx, dy);
            if (q == kNoTexel || !grid.alive[q]) continue;
            const float w = (i ? fx : 1.0f - fx) * (j ? fy : 1.0f - fy);
            sum += w * map[q];
            wsum += w;
          }
        }
        if (wsum > 0.0f) {
          v = sum / wsum;
        } else {  // a buried texel: the mean of the neighbours that have a value
          v = glm::vec3(0.0f);
          float n = 0.0f;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const uint32_t q = dx == 0 && dy == 0 ? kNoTexel : grid.link(own, 0, dx, dy);
              if (q == kNoTexel || !grid.alive[q]) continue;
              v += map[q];
              n += 1.0f;
            }
          if (n > 0.0f) v /= n;
        }
      }
      out(x, y, v);
    }
  }
}

}  // namespace

void add_magnified(const CoarseGrid& grid, const TexelSet& texels, const CoarseMap& map,
                   FloatImage& fine, float scale) {
  magnify(grid, texels, map, [&](int x, int y, const glm::vec3& v) {
    for (int ch = 0; ch < 3; ++ch) fine.at(x, y, ch) += scale * v[ch];
  });
}

float magnified_peak(const CoarseGrid& grid, const TexelSet& texels, const CoarseMap& map) {
  float p = 0.0f;
  magnify(grid, texels, map, [&](int, int, const glm::vec3& v) {
    for (int ch = 0; ch < 3; ++ch)
      if (std::isfinite(v[ch])) p = std::max(p, v[ch]);
  });
  return p;
}

float peak(const CoarseMap& map) {
  float p = 0.0f;
  for (const glm::vec3& v : map) p = std::max(p, max3(v));
  return p;
}

}  // namespace lightpatch::cooker
