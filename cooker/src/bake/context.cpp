#include "context.h"

#include <algorithm>
#include <cmath>

#include "indirect/integrator.h"
#include "lightpatch/cooker/error.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {

// Floor of output_step for a scene that is black at its authored state and has no semi-dynamic
// light to expose for.
constexpr float kMinOutputStep = 1e-6f;

int preset_texel_samples(Quality q) {
  switch (q) {
    case Quality::kDraft:
      return 1;
    case Quality::kPreview:
      return 4;
    case Quality::kProduction:
      return 9;
  }
  return 4;
}

int preset_samples(Quality q) {
  switch (q) {
    case Quality::kDraft:
      return 4;
    case Quality::kPreview:
      return 16;
    case Quality::kProduction:
      return 64;
  }
  return 16;
}

}  // namespace

void check_bake_inputs(const Scene& scene, const TexelSet& texels) {
  const size_t n = size_t(std::max(0, texels.width)) * size_t(std::max(0, texels.height));
  if (texels.width <= 0 || texels.height <= 0 || texels.position.size() != n ||
      texels.normal.size() != n || texels.valid.size() != n) {
    throw CookError("bake: inconsistent texel set");
  }
  for (const Light& l : scene.lights) {
    const bool finite = std::isfinite(l.intensity) && std::isfinite(max3(l.color)) &&
                        std::isfinite(l.position.x + l.position.y + l.position.z) &&
                        std::isfinite(l.direction.x + l.direction.y + l.direction.z) &&
                        std::isfinite(l.range) && std::isfinite(l.radius);
    if (!finite || l.intensity < 0.0f || std::min({l.color.x, l.color.y, l.color.z}) < 0.0f) {
      throw CookError("light '" + l.name + "' has a negative or non-finite value");
    }
  }
}

namespace {

// The largest unit * 2^(k/4) <= v (v, unit > 0, finite). The output step comes from every
// light of the authored state, and every light group's maps and content hash (cook_jobs.h) from
// the step: rounded, moving or recolouring one light keeps the step, so the other groups' jobs
// are reused, unless it crosses a quarter octave. Never coarser than the unrounded step, at most
// 16% finer. `unit` scales as irradiance does with the scene (1 cd at the scene's diagonal), so a
// scene scaled by k gets the step scaled by 1/k^2 exactly.
float quarter_octave_below(float v, float unit) {
  static constexpr double kRoots[4] = {1.0, 1.189207115002721, 1.414213562373095,
                                       1.681792830507429};
  if (!(unit > 0.0f) || !std::isfinite(unit)) unit = 1.0f;
  const double x = double(v) / double(unit);
  int k = static_cast<int>(std::floor(4.0 * std::log2(x)));
  auto grid = [&](int i) {
    const int r = ((i % 4) + 4) % 4;
    return std::ldexp(kRoots[r], (i - r) / 4);
  };
  if (grid(k) > x) --k;
  return float(grid(k) * double(unit));
}

// Unshadowed irradiance of the authored state (max channel) at each valid texel; its 99th
// percentile is the top of the 8-bit range, output_step one 255th of it.
float percentile_step(const BakeContext& b, bool authored) {
  const TexelSet& texels = b.texels;
  std::vector<float> values(texels.position.size(), -1.0f);
  const float eps2 = b.eps * b.eps;
  parallel_for(texels.height, b.threads, [&](int y) {
    std::vector<LightSample> samples;
    for (int x = 0; x < texels.width; ++x) {
      const size_t t = texels.index(x, y);
      if (!texels.valid[t]) continue;
      glm::vec3 e(0.0f);
      for (const Light& l : b.scene.lights) {
        if (!authored && !l.semi_dynamic) continue;
        if (l.moving) continue;  // its direct light is the game's, not the maps'
        const glm::vec3 c = authored ? l.color * l.intensity : glm::vec3(1.0f);
        e += c * punctual_irradiance(l, l.position, texels.position[t], texels.normal[t], eps2);
      }
      if (authored && !b.emissive.empty()) {
        samples.clear();
        b.emissive.sample(texels.position[t], texels.normal[t], std::min(b.area_samples, 4),
                          b.texel_rng(t, 0), b.eps, samples);
        for (const LightSample& s : samples) e += s.irradiance;
      }
      values[t] = std::isfinite(max3(e)) ? max3(e) : 0.0f;
    }
  });
  // Over the static surfaces' texels where there are any: semi-dynamic objects move and hide, and
  // the step (so every group's maps and job hash) should not follow them.
  std::vector<float> on_static;
  for (size_t t = 0; t < values.size(); ++t) {
    const int32_t m = t < texels.mesh.size() ? texels.mesh[t] : -1;
    const bool object =
        m >= 0 && size_t(m) < b.scene.meshes.size() && b.scene.meshes[size_t(m)].object >= 0;
    if (values[t] != -1.0f && !object) on_static.push_back(values[t]);
  }
  if (!on_static.empty()) values = std::move(on_static);
  values.erase(std::remove(values.begin(), values.end(), -1.0f), values.end());
  if (values.empty()) return 0.0f;
  const size_t k = std::min(values.size() - 1, values.size() * 99 / 100);
  std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
  return values[k] / 255.0f;
}

// Per scene light: the peak over valid texels of its unshadowed direct irradiance at colour
// (1,1,1) and intensity 1.
std::vector<float> own_peaks(const BakeContext& b) {
  const TexelSet& texels = b.texels;
  const size_t n = b.scene.lights.size();
  std::vector<float> rows(static_cast<size_t>(texels.height) * n, 0.0f);
  const float eps2 = b.eps * b.eps;
  parallel_for(texels.height, b.threads, [&](int y) {
    for (size_t i = 0; i < n; ++i) {
      float peak = 0.0f;
      for (int x = 0; x < texels.width; ++x) {
        const size_t t = texels.index(x, y);
        if (!texels.valid[t]) continue;
        const Light& l = b.scene.lights[i];
        const float e =
            punctual_irradiance(l, l.position, texels.position[t], texels.normal[t], eps2);
        if (std::isfinite(e)) peak = std::max(peak, e);
      }
      rows[static_cast<size_t>(y) * n + i] = peak;
    }
  });
  std::vector<float> peaks(n, 0.0f);
  for (size_t r = 0; r < rows.size(); ++r) peaks[r % n] = std::max(peaks[r % n], rows[r]);
  return peaks;
}

}  // namespace

float max3(const glm::vec3& v) {
  return std::max({v.x, v.y, v.z});
}

BakeContext::BakeContext(const Scene& s, const Layout& l, const TexelSet& t, const Tracer& tr,
                         const BakeOptions& o)
    : scene(s), layout(l), texels(t), tracer(tr), options(o), emissive(s) {
  check_bake_inputs(scene, texels);
  threads = worker_count(o.threads);
  area_samples = o.area_samples > 0 ? o.area_samples : preset_samples(o.quality);
  texel_samples = o.texel_samples > 0 ? o.texel_samples : preset_texel_samples(o.quality);
  if (texel_samples > 1) footprints = texel_footprints(texels, &tracer, threads);
  eps = tracer.epsilon();
  const float scale = scene.scale() > 0.0f ? scene.scale() : 1.0f;
  extent = 1.5f * scale;  // any segment inside the bounds is shorter than the diagonal
  float step = percentile_step(*this, true);
  if (!(step > 0.0f)) step = percentile_step(*this, false);
  // The floor is for a black scene only: as a floor under every scene it was an absolute
  // irradiance, not scaled with the scene (a 10 km room under the same candela is 1e-8 as bright
  // as a 1 m one, below 1e-6, and every texel was culled as insignificant).
  output_step = step > 0.0f ? quarter_octave_below(step, 1.0f / (scale * scale)) : kMinOutputStep;
  if (o.output_step > 0.0f) output_step = o.output_step;
  float s_max = 0.0f;
  for (const Light& light : scene.lights)
    s_max = std::max(s_max, max3(light.color) * light.intensity);
  const std::vector<float> own = own_peaks(*this);
  // The static lights' brightest peak at their authored colours (a lower bound of the base map's
  // peak). Emissive surfaces are not in it: with no punctual static light the step stays.
  float static_peak = 0.0f;
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    const Light& light = scene.lights[i];
    LightPlan p;
    // A light authored dim (or at 0) is given the significance of a light 1/100 as bright as the
    // brightest, so that it keeps its patches when turned up at run time.
    const float a = max3(light.color) * light.intensity;
    float sig = std::max(a, 1e-2f * s_max);
    if (!(sig > 0.0f)) sig = 1.0f;
    p.threshold = output_step / sig;
    // A semi-dynamic light may be the only one on: its significance is also at most one 8-bit
    // step of its own peak, so a 1e-2 cd light beside a 1e4 cd one still recomposes alone to 8
    // bits (pack_builder.cpp cuts patches by the same rule). Static lights follow the same rule,
    // so a light bakes the same whether static or semi-dynamic.
    if (own[i] > 0.0f) p.threshold = std::min(p.threshold, own[i] / 255.0f);
    p.cutoff = kEarlyOutFraction * p.threshold;
    p.samples = (light.radius > 0.0f && light.type != LightType::kDirectional) ? area_samples : 1;
    lights.push_back(p);
    if (!light.semi_dynamic && a > 0.0f && std::isfinite(a))
      static_peak = std::max(static_peak, own[i] * a);
  }
  static_step = static_peak > 0.0f ? std::min(output_step, static_peak / 255.0f) : output_step;
}

BakeContext::~BakeContext() = default;

uint64_t BakeContext::texel_rng(size_t texel, int slot) const {
  return sample_hash(options.seed, texel, static_cast<uint64_t>(slot), 0);
}

void BakeContext::light_samples(int li, size_t t, std::vector<LightSample>& out,
                                const Light* posed) const {
  const LightPlan& p = lights[static_cast<size_t>(li)];
  sample_punctual(posed ? *posed : scene.lights[static_cast<size_t>(li)], texels.position[t],
                  texels.normal[t], p.samples, texel_rng(t, li + 1), eps, extent, p.cutoff, out,
                  footprint(t), texel_samples);
}

namespace {
constexpr uint64_t kPenumbraSalt = 0x70656e756d627261ull;  // "penumbra"
}  // namespace

bool BakeContext::penumbra_light_samples(int li, size_t t, std::vector<LightSample>& out,
                                         const Light* posed) const {
  const LightPlan& p = lights[static_cast<size_t>(li)];
  const Light& light = posed ? *posed : scene.lights[static_cast<size_t>(li)];
  const TexelFootprint* f = footprint(t);
  const bool sized = light.type != LightType::kDirectional && light.radius > 0.0f;
  if (!f && !sized) return false;
  sample_punctual(light, texels.position[t], texels.normal[t], p.samples * kPenumbraFactor,
                  sample_hash(texel_rng(t, li + 1), kPenumbraSalt, 0, 0), eps, extent, p.cutoff,
                  out, f, texel_samples * kPenumbraFactor);
  return true;
}

void BakeContext::emissive_samples(size_t t, std::vector<LightSample>& out) const {
  emissive.sample(texels.position[t], texels.normal[t], area_samples, texel_rng(t, 0), eps, out,
                  footprint(t));
}

namespace {
// Salt of the DirectPoints' random numbers, apart from the texels'.
constexpr uint64_t kPointSalt = 0x706f696e74ull;  // "point"
}  // namespace

void BakeContext::point_light_samples(const DirectPoints& pts, int li, size_t i,
                                      std::vector<LightSample>& out, const Light* posed) const {
  const LightPlan& p = lights[static_cast<size_t>(li)];
  sample_punctual(posed ? *posed : scene.lights[static_cast<size_t>(li)], pts.position[i],
                  pts.normal[i], 1,
                  sample_hash(options.seed, i, static_cast<uint64_t>(li + 1), kPointSalt), eps,
                  extent, p.cutoff, out);
}

void BakeContext::point_emissive_samples(const DirectPoints& pts, size_t i,
                                         std::vector<LightSample>& out) const {
  emissive.sample(pts.position[i], pts.normal[i], 1, sample_hash(options.seed, i, 0, kPointSalt),
                  eps, out);
}

std::string BakeContext::light_name(int li) const {
  const std::string& n = scene.lights[static_cast<size_t>(li)].name;
  return n.empty() ? "light#" + std::to_string(li) : n;
}

Bounds object_bounds(const Scene& scene, const Object& o) {
  Bounds b;
  for (int m : o.meshes) {
    for (const glm::vec3& p : scene.meshes[static_cast<size_t>(m)].positions) {
      b.lo = glm::min(b.lo, p);
      b.hi = glm::max(b.hi, p);
    }
  }
  return b;
}

std::string precull_pair(const Light& light, const LightPlan& plan, const Bounds& b) {
  if (b.empty()) return "object has no geometry";
  if (light.type == LightType::kDirectional) return "";
  const float reach = light_reach(light, plan.cutoff);
  const glm::vec3 nearest = glm::clamp(light.position, b.lo, b.hi);
  const float dist = glm::length(nearest - light.position);
  if (dist > reach) {
    return "outside the light's reach (nearest " + std::to_string(dist) + " m, reach " +
           std::to_string(reach) + " m)";
  }
  if (light.type == LightType::kSpot) {
    const glm::vec3 c = 0.5f * (b.lo + b.hi);
    const float radius = 0.5f * glm::length(b.hi - b.lo) + light.radius;
    const glm::vec3 to_c = c - light.position;
    const float d = glm::length(to_c);
    if (d > radius) {
      const float angle = std::acos(std::clamp(glm::dot(to_c / d, light.direction), -1.0f, 1.0f));
      const float half = std::asin(std::clamp(radius / d, 0.0f, 1.0f));
      if (angle - half > light.outer_cone) return "outside the spot light's outer cone";
    }
  }
  return "";
}

}  // namespace lightpatch::cooker
