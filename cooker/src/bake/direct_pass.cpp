#include "direct_pass.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include "indirect/integrator.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

float* SparseMap::row(int y) {
  std::unique_ptr<float[]>& r = rows_[size_t(y)];
  if (!r) r = std::make_unique<float[]>(size_t(width_) * size_t(channels_));
  return r.get();
}

FloatImage SparseMap::dense() const {
  FloatImage m(width_, height_, channels_);
  const size_t n = size_t(width_) * size_t(channels_);
  for (int y = 0; y < height_; ++y) {
    if (rows_[size_t(y)]) std::copy_n(rows_[size_t(y)].get(), n, m.data.begin() + long(n) * y);
  }
  return m;
}

void SampleRays::trace(const Tracer& tracer, const std::vector<LightSample>& samples,
                       int max_objects) {
  const size_t n = samples.size();
  rays.resize(n);
  for (size_t i = 0; i < n; ++i)
    rays[i] = {samples[i].origin, samples[i].tmin, samples[i].dir, samples[i].tmax};
  counts.resize(n);
  stride = size_t(std::max(0, max_objects));
  objects.resize(std::max<size_t>(1, n * stride));
  tracer.shadow_query_many(rays.data(), int(n), counts.data(), objects.data(), max_objects);
}

float peak_of(const FloatImage& map, const TexelSet& texels) {
  float peak = 0.0f;
  const size_t ch = size_t(map.channels);
  for (size_t t = 0; t < map.data.size() / ch; ++t) {
    if (!texels.valid[t]) continue;
    for (size_t c = 0; c < ch; ++c) peak = std::max(peak, std::fabs(map.data[t * ch + c]));
  }
  return peak;
}

namespace {

// Shadow samples traced in one batch: enough for full packets from receivers of one sample a
// light, few enough that the batch's object lists stay small.
constexpr size_t kBatchSamples = 64;

// The pass over a w x h image of receivers: valid(t), and their samples of a light
// (light_samples(li, t, out); in a penumbra, penumbra_samples(li, t, out) instead where it gives
// any) and of the emissive surfaces (emissive_samples(t, out)).
template <typename Valid, typename LightSamples, typename PenumbraSamples, typename EmissiveSamples>
DirectPass trace_receivers(const BakeContext& b, int light, const Candidates& cand, int channels,
                           int w, int h, const Valid& valid, const LightSamples& light_samples,
                           const PenumbraSamples& penumbra_samples,
                           const EmissiveSamples& emissive_samples, Progress* progress) {
  const Scene& scene = b.scene;
  const Tracer& tracer = b.tracer;
  DirectPass gm;
  gm.map = FloatImage(w, h, channels);
  gm.shadow.reserve(cand.sets.size());
  for (size_t j = 0; j < cand.sets.size(); ++j) gm.shadow.emplace_back(w, h, channels);
  std::mutex pair_mutex;
  const int max_objects = static_cast<int>(scene.objects.size());
  const size_t nc = cand.sets.size();
  parallel_for(h, b.threads, [&](int y) {
    std::vector<LightSample> samples;  // of the receivers pending, traced together
    SampleRays batch;
    std::vector<LightSample> dense;  // the penumbras' samples drawn again, traced together
    SampleRays dense_batch;
    // One light's samples of one receiver: samples[first, first + count) (dense: of `dense`),
    // each carrying scale * its irradiance (per_channel: its irradiance as it is).
    struct Chunk {
      uint32_t first, count;
      glm::vec3 scale;
      bool per_channel;
      int light;  // scene light, -1 for the emissive surfaces
      bool dense;
    };
    std::vector<Chunk> chunks;
    std::vector<std::pair<int, size_t>> pending;  // (x, its first chunk)
    std::vector<int> slots;
    std::vector<glm::vec3> s_acc(nc);
    std::vector<std::pair<std::pair<int, int>, glm::vec3>> p_acc;  // this texel's pair terms
    std::vector<std::pair<std::pair<int, int>, std::pair<int, glm::vec3>>> row_pairs;
    double doubly = 0.0, triply = 0.0;
    // The pending receivers' samples traced at once (a receiver of a few samples, a point of
    // one a light, would trace packets of one ray), then each receiver's answers summed.
    auto flush = [&]() {
      batch.trace(tracer, samples, nc == 0 ? 0 : max_objects);
      dense.clear();
      for (size_t r = 0; r < pending.size(); ++r) {
        const size_t c_end = r + 1 < pending.size() ? pending[r + 1].second : chunks.size();
        const size_t t = size_t(y) * size_t(w) + size_t(pending[r].first);
        for (size_t k = pending[r].second; k < c_end; ++k) {
          Chunk& ck = chunks[k];
          if (ck.light < 0 || !batch.penumbra(ck.first, ck.count)) continue;
          const size_t first = dense.size();
          if (!penumbra_samples(ck.light, t, dense)) continue;
          ck.first = uint32_t(first);
          ck.count = uint32_t(dense.size() - first);
          ck.dense = true;
        }
      }
      if (!dense.empty()) dense_batch.trace(tracer, dense, nc == 0 ? 0 : max_objects);
      for (size_t r = 0; r < pending.size(); ++r) {
        const int x = pending[r].first;
        const size_t c_end = r + 1 < pending.size() ? pending[r + 1].second : chunks.size();
        glm::vec3 c_acc(0.0f);
        bool any = false;  // some shadow accumulator touched
        p_acc.clear();
        // A segment carrying `e` and its answer: blocked by static geometry (n < 0), or
        // crossing the n candidates `hit`.
        auto segment = [&](int n, const int* hit, const glm::vec3& e) {
          if (n < 0) return;
          c_acc += e;
          slots.clear();
          for (int j = 0; j < n; ++j)
            for (int sl : cand.slots_of[size_t(hit[size_t(j)])]) slots.push_back(sl);
          for (int sl : slots) {
            if (!any) std::fill(s_acc.begin(), s_acc.end(), glm::vec3(0.0f));
            any = true;
            s_acc[size_t(sl)] += e;
          }
          if (slots.size() >= 2) {
            std::sort(slots.begin(), slots.end());
            for (size_t a = 0; a < slots.size(); ++a)
              for (size_t c = a + 1; c < slots.size(); ++c) {
                const std::pair<int, int> key(slots[a], slots[c]);
                auto it = std::find_if(p_acc.begin(), p_acc.end(),
                                       [&](const auto& v) { return v.first == key; });
                if (it == p_acc.end())
                  p_acc.push_back({key, e});
                else
                  it->second += e;
              }
            (slots.size() == 2 ? doubly : triply) += max3(e);
          }
        };
        for (size_t k = pending[r].second; k < c_end; ++k) {
          const Chunk& ck = chunks[k];
          const std::vector<LightSample>& from = ck.dense ? dense : samples;
          const SampleRays& answers = ck.dense ? dense_batch : batch;
          for (size_t i = ck.first; i < size_t(ck.first) + ck.count; ++i) {
            const glm::vec3 e =
                ck.per_channel ? from[i].irradiance : ck.scale * from[i].irradiance.x;
            segment(answers.counts[i], answers.objects_of(i), e);
          }
        }
        for (int ch = 0; ch < channels; ++ch) gm.map.at(x, y, ch) = c_acc[ch];
        for (const auto& [key, e] : p_acc) row_pairs.push_back({key, {x, e}});
        if (!any) continue;  // shadow maps start at zero: most texels touch none
        for (size_t j = 0; j < nc; ++j) {
          if (s_acc[j] == glm::vec3(0.0f)) continue;
          float* row = gm.shadow[j].row(y) + size_t(x) * size_t(channels);
          for (int ch = 0; ch < channels; ++ch) row[ch] = s_acc[j][ch];
        }
      }
      samples.clear();
      chunks.clear();
      pending.clear();
    };
    for (int x = 0; x < w; ++x) {
      const size_t t = size_t(y) * size_t(w) + size_t(x);
      if (!valid(t)) continue;
      pending.push_back({x, chunks.size()});
      auto add = [&](auto&& sample, const glm::vec3& scale, bool per_channel, int li) {
        const size_t first = samples.size();
        sample();
        chunks.push_back(
            {uint32_t(first), uint32_t(samples.size() - first), scale, per_channel, li, false});
      };
      if (light < 0) {
        for (size_t l = 0; l < scene.lights.size(); ++l) {
          const Light& sl = scene.lights[l];
          if (sl.semi_dynamic) continue;
          add([&] { light_samples(static_cast<int>(l), t, samples); }, sl.color * sl.intensity,
              false, static_cast<int>(l));
        }
        add([&] { emissive_samples(t, samples); }, glm::vec3(1.0f), true, -1);
      } else {
        add([&] { light_samples(light, t, samples); }, glm::vec3(1.0f), false, light);
      }
      if (samples.size() >= kBatchSamples) flush();
    }
    if (!pending.empty()) flush();
    if (!row_pairs.empty() || doubly > 0.0 || triply > 0.0) {
      std::lock_guard<std::mutex> lock(pair_mutex);
      gm.doubly_blocked += doubly;
      gm.triply_blocked += triply;
      for (const auto& [key, xe] : row_pairs) {
        auto it = gm.pairs.find(key);
        if (it == gm.pairs.end()) it = gm.pairs.emplace(key, FloatImage(w, h, channels)).first;
        for (int ch = 0; ch < channels; ++ch) it->second.at(xe.first, y, ch) += xe.second[ch];
      }
    }
    if (progress) progress->advance();
  });
  return gm;
}

}  // namespace

DirectPass trace_direct(const BakeContext& b, int light, const Candidates& cand, int channels,
                        Progress& progress) {
  const TexelSet& texels = b.texels;
  DirectPass gm = trace_receivers(
      b, light, cand, channels, texels.width, texels.height,
      [&](size_t t) { return texels.valid[t] != 0; },
      [&](int li, size_t t, std::vector<LightSample>& out) { b.light_samples(li, t, out); },
      [&](int li, size_t t, std::vector<LightSample>& out) {
        return b.penumbra_light_samples(li, t, out);
      },
      [&](size_t t, std::vector<LightSample>& out) { b.emissive_samples(t, out); }, &progress);
  const DirectPoints* pts = b.indirect ? b.indirect->direct_points() : nullptr;
  if (pts && pts->size() > 0) {
    gm.points = std::make_unique<DirectPass>(trace_receivers(
        b, light, cand, channels, pts->width, pts->height,
        [&](size_t i) { return i < pts->size(); },
        [&](int li, size_t i, std::vector<LightSample>& out) {
          b.point_light_samples(*pts, li, i, out);
        },
        // A point's one sample is never a penumbra.
        [](int, size_t, std::vector<LightSample>&) { return false; },
        [&](size_t i, std::vector<LightSample>& out) { b.point_emissive_samples(*pts, i, out); },
        nullptr));
  }
  return gm;
}

}  // namespace lightpatch::cooker
