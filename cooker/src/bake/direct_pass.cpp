#include "direct_pass.h"

#include <algorithm>
#include <cmath>
#include <mutex>

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

DirectPass trace_direct(const BakeContext& b, int light, const Candidates& cand, int channels,
                        Progress& progress) {
  const Scene& scene = b.scene;
  const TexelSet& texels = b.texels;
  const Tracer& tracer = b.tracer;
  const int w = texels.width, h = texels.height;
  DirectPass gm;
  gm.map = FloatImage(w, h, channels);
  gm.shadow.reserve(cand.sets.size());
  for (size_t j = 0; j < cand.sets.size(); ++j) gm.shadow.emplace_back(w, h, channels);
  std::mutex pair_mutex;
  const int max_objects = static_cast<int>(scene.objects.size());
  const size_t nc = cand.sets.size();
  parallel_for(h, b.threads, [&](int y) {
    std::vector<LightSample> samples;
    SampleRays batch;
    std::vector<int> slots;
    std::vector<glm::vec3> s_acc(nc);
    std::vector<std::pair<std::pair<int, int>, glm::vec3>> p_acc;  // this texel's pair terms
    std::vector<std::pair<std::pair<int, int>, std::pair<int, glm::vec3>>> row_pairs;
    double doubly = 0.0, triply = 0.0;
    for (int x = 0; x < w; ++x) {
      const size_t t = texels.index(x, y);
      if (!texels.valid[t]) continue;
      glm::vec3 c_acc(0.0f);
      bool any = false;  // some shadow accumulator touched
      p_acc.clear();
      // A segment carrying `e` and its answer: blocked by static geometry (n < 0), or crossing
      // the n candidates `hit`.
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
      // One light's samples of this texel, traced together; `scale` gives each its energy.
      auto trace = [&](const glm::vec3& scale, bool per_channel) {
        batch.trace(tracer, samples, nc == 0 ? 0 : max_objects);
        for (size_t i = 0; i < samples.size(); ++i) {
          const glm::vec3 e = per_channel ? samples[i].irradiance : scale * samples[i].irradiance.x;
          segment(batch.counts[i], batch.objects_of(i), e);
        }
      };
      if (light < 0) {
        for (size_t l = 0; l < scene.lights.size(); ++l) {
          const Light& sl = scene.lights[l];
          if (sl.semi_dynamic) continue;
          samples.clear();
          b.light_samples(static_cast<int>(l), t, samples);
          trace(sl.color * sl.intensity, false);
        }
        samples.clear();
        b.emissive_samples(t, samples);
        trace(glm::vec3(1.0f), true);
      } else {
        samples.clear();
        b.light_samples(light, t, samples);
        trace(glm::vec3(1.0f), false);
      }
      for (int ch = 0; ch < channels; ++ch) gm.map.at(x, y, ch) = c_acc[ch];
      for (const auto& [key, e] : p_acc) row_pairs.push_back({key, {x, e}});
      if (!any) continue;  // shadow maps start at zero: most texels touch none
      for (size_t j = 0; j < nc; ++j) {
        if (s_acc[j] == glm::vec3(0.0f)) continue;
        float* r = gm.shadow[j].row(y) + size_t(x) * size_t(channels);
        for (int ch = 0; ch < channels; ++ch) r[ch] = s_acc[j][ch];
      }
    }
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
    progress.advance();
  });
  return gm;
}

}  // namespace lightpatch::cooker
