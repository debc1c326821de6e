// The path tracer behind `--integrator reference` (reference_integrator.h). Each work item is one
// row of texels for one pass of samples: its paths advance together, bounce by bounce, so every
// bounce's shadow rays and continuation rays go to the tracer as batches (Tracer::*_many).
//
// Estimator. E_k, the irradiance at vertex k, is estimated by next-event estimation to every light
// plus one cosine-sampled direction w (pdf cos/pi): E_k ~ NEE + pi L(w). Along w, L is the
// emission of the light spheres the ray crosses before its hit and of an emissive triangle hit
// from its front (both MIS-weighted against NEE), plus the hit's reflected radiance
// albedo / pi * E_{k+1}; so the throughput to E_{k+1} is the throughput to E_k times the albedo
// (divided by the Russian-roulette survival probability). Light spheres are emitters only: they
// occlude nothing, exactly as in the cook's direct and indirect light.
//
// A texel's irradiance is the mean over the visible part of its patch (texel_footprint.h). A path
// whose first ray meets the back of a static surface started inside solid geometry (a point of
// the patch under a wall or inside a table top that the footprint's closed cells do not cut away):
// it is no sample of what a viewer sees, and is dropped; the texel's estimate is the mean of the
// others. The cook decides the same per texel (a texel whose gather rays meet back faces more
// than a tenth of the time is buried and shows its surface's neighbours): counted as black, such
// paths made the path tracer's texel at a solid's edge up to 10x darker than every cook preset.
// Back faces of semi-dynamic objects keep their paths (a point under a present crate is dark).
#include "lightpatch/cooker/reference_integrator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "direct_light.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/progress.h"
#include "surface_albedo.h"
#include "texel_footprint.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr int kPassSamples = 16;
constexpr int kMinTargetSamples = 64;
// Steps over hidden objects a ray takes before it looks at static geometry only.
constexpr int kHiddenSteps = 16;

float max3(const glm::vec3& v) {
  return std::max({v.x, v.y, v.z});
}

// Power heuristic weight of the strategy with density a against one with density b.
float power_weight(float a, float b) {
  const float a2 = a * a, b2 = b * b;
  return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

// Random numbers of one path vertex: a key hashed from (seed, texel, sample, bounce), then a
// counter through one round of splitmix64.
struct Stream {
  uint64_t key, counter = 0;
  float next() {
    uint64_t x = key + 0x9e3779b97f4a7c15ull * ++counter;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return hash_to_unit(x ^ (x >> 31));
  }
};

struct LitLight {
  const Light* light;
  glm::vec3 radiant;         // colour * intensity of the state
  bool bounce_only = false;  // a moving light: not from the texel's own vertex (depth 0)
};

// One path between bounces.
struct PathState {
  glm::vec3 position, normal;  // vertex and its normal on the side the path arrived from
  glm::vec3 throughput;        // to this vertex's irradiance
  glm::vec3 dir{0.0f};         // continuation direction
  float cos_dir = 0.0f;        // normal . dir
  float roulette = 0.0f;       // the uniform number deciding survival at the next hit
  uint32_t value = 0;          // index of this sample's estimate in the row's values
  uint32_t texel = 0, sample = 0;
  int depth = 0;
};

class PathTracer {
 public:
  PathTracer(const Scene& scene, const TexelSet& texels, const std::vector<uint8_t>& traced,
             const Tracer& tracer, const ResolvedState& state, uint64_t seed, bool texel_patch,
             int threads, bool moving_direct)
      : scene_(scene),
        texels_(texels),
        traced_(traced),
        tracer_(tracer),
        visible_(state.visible),
        emissive_(scene),
        footprints_(texel_patch ? texel_footprints(texels, &tracer, threads)
                                : std::vector<TexelFootprint>()),
        seed_(seed) {
    // Moving lights at the state's pose (the pointers below point into posed_: sized first).
    posed_.assign(scene.lights.begin(), scene.lights.end());
    for (size_t i = 0; i < scene.lights.size(); ++i) {
      if (!scene.lights[i].moving) continue;
      if (i < state.position.size()) posed_[i].position = state.position[i];
      if (i < state.direction.size()) posed_[i].direction = state.direction[i];
    }
    for (size_t i = 0; i < scene.lights.size(); ++i) {
      if (max3(state.radiant[i]) > 0.0f)
        lights_.push_back({&posed_[i], state.radiant[i], scene.lights[i].moving && !moving_direct});
    }
    for (const LitLight& l : lights_) {
      if (l.light->type != LightType::kDirectional && l.light->radius > 0.0f) spheres_.push_back(l);
    }
    for (uint8_t v : visible_) {
      any_visible_ = any_visible_ || v != 0;
      any_hidden_ = any_hidden_ || v == 0;
    }
    eps_ = tracer.epsilon();
    const float scale = scene.scale() > 0.0f ? scene.scale() : 1.0f;
    extent_ = 1.5f * scale;  // any segment inside the bounds is shorter than the diagonal
  }

  // Traces samples [s0, s1) of the traced texels of row y; the estimate of sample s of the row's
  // k-th traced texel goes to values[k * (s1 - s0) + s - s0], and kept[...] is 0 where the path
  // started inside solid geometry (its first ray met a static back face: not a sample).
  void trace_row(int y, int s0, int s1, std::vector<glm::vec3>& values,
                 std::vector<uint8_t>& kept) const {
    std::vector<PathState> active, next;
    for (int x = 0; x < texels_.width; ++x) {
      const size_t t = texels_.index(x, y);
      if (!traced_[t]) continue;
      for (int s = s0; s < s1; ++s) {
        PathState p;
        p.position = footprints_.empty() ? texels_.position[t]
                                         : footprint_point(footprints_[t], texels_.position[t], s,
                                                           sample_hash(seed_, t, 0x666f6f74ull, 0));
        p.normal = texels_.normal[t];
        p.throughput = glm::vec3(1.0f);
        p.value = static_cast<uint32_t>(active.size());
        p.texel = static_cast<uint32_t>(t);
        p.sample = static_cast<uint32_t>(s);
        active.push_back(p);
      }
    }
    values.assign(active.size(), glm::vec3(0.0f));
    kept.assign(active.size(), 1);
    std::vector<Ray> shadow, rays;
    std::vector<glm::vec3> shadow_value;
    std::vector<uint32_t> shadow_owner;
    std::vector<uint8_t> blocked;
    std::vector<Hit> hits, shadow_hits;
    std::vector<int> found(std::max<size_t>(1, scene_.objects.size()));
    while (!active.empty()) {
      shadow.clear();
      shadow_value.clear();
      shadow_owner.clear();
      rays.clear();
      rays.reserve(active.size());
      shadow.reserve(active.size() * (lights_.size() + 1));
      for (PathState& p : active) {
        Stream rng{sample_hash(seed_, p.texel, p.sample, static_cast<uint64_t>(p.depth))};
        next_event(p, rng, shadow, shadow_value, shadow_owner);
        p.dir = cosine_direction(p.normal, rng.next(), rng.next());
        p.cos_dir = glm::dot(p.normal, p.dir);
        p.roulette = rng.next();
        rays.push_back({p.position + p.normal * eps_, eps_, p.dir, extent_});
      }
      blocked.resize(shadow.size());
      occluded(shadow, blocked, shadow_hits, found);
      for (size_t i = 0; i < shadow.size(); ++i) {
        if (!blocked[i]) values[shadow_owner[i]] += shadow_value[i];
      }
      hits.resize(rays.size());
      intersect(rays, hits);
      next.clear();
      for (size_t i = 0; i < active.size(); ++i) {
        PathState& p = active[i];
        const Hit& h = hits[i];
        glm::vec3& value = values[p.value];
        const float t_hit = h.hit ? h.t : std::numeric_limits<float>::infinity();
        const float pdf_dir = p.cos_dir / kPi;
        if (!(pdf_dir > 0.0f)) continue;
        // Light spheres crossed before the hit, seen from the vertex itself as next_event's cone
        // is: from the ray's origin, eps_ above it, a sphere a few eps_ away looks wider, and the
        // directions only the wider cone holds, which next_event never samples, counted in full
        // (candle wax 1 cm under its flame's sphere came out 1.2 % too bright in the inn).
        for (const LitLight& l : spheres_) {
          if (l.bounce_only && p.depth == 0) continue;
          const float ts =
              sphere_hit_distance(p.position, p.dir, l.light->position, l.light->radius);
          if (!(ts > 0.0f) || !(ts < t_hit)) continue;
          SphereView view;
          if (!view_sphere_light(*l.light, p.position, &view)) continue;
          const float w = power_weight(pdf_dir, sphere_view_pdf(view, p.normal, p.dir));
          value += p.throughput * l.radiant * (kPi * view.radiance * w);
        }
        if (!h.hit) continue;
        if (p.depth == 0 && scene_.meshes[size_t(h.mesh)].object < 0 &&
            glm::dot(h.geometric_normal, p.dir) > 0.0f) {
          kept[p.value] = 0;
          continue;
        }
        const int e = emissive_.find(h.mesh, h.triangle);
        if (e >= 0) {
          const EmissiveLights::Point pt = emissive_.emitter(e, p.position);
          const float cos_b = -glm::dot(pt.normal, p.dir);
          if (cos_b > 0.0f) {
            const float pdf_light = pt.pdf_area * h.t * h.t / cos_b;
            value += p.throughput * pt.radiance * (kPi * power_weight(pdf_dir, pdf_light));
          }
        }
        if (p.depth + 1 > kReferenceMaxBounces) continue;
        const glm::vec3 albedo = surface_albedo(scene_, h);
        const float q = std::min(1.0f, max3(albedo));
        if (!(p.roulette < q)) continue;
        PathState n = p;
        n.throughput = p.throughput * albedo / q;
        n.position = rays[i].origin + p.dir * h.t;
        n.normal =
            glm::dot(h.geometric_normal, p.dir) > 0.0f ? -h.geometric_normal : h.geometric_normal;
        n.depth = p.depth + 1;
        next.push_back(n);
      }
      active.swap(next);
    }
  }

 private:
  // One shadow ray per light (and one for the emissive triangles) from vertex p, with what it
  // brings if nothing blocks it.
  void next_event(const PathState& p, Stream& rng, std::vector<Ray>& rays,
                  std::vector<glm::vec3>& value, std::vector<uint32_t>& owner) const {
    const glm::vec3 origin = p.position + p.normal * eps_;
    auto add = [&](const glm::vec3& target, const glm::vec3& v, float stop_short) {
      const glm::vec3 to = target - origin;
      const float d = glm::length(to);
      if (!(d > 0.0f)) return;
      rays.push_back({origin, eps_, to / d, std::max(eps_, d - stop_short)});
      value.push_back(p.throughput * v);
      owner.push_back(p.value);
    };
    for (const LitLight& l : lights_) {
      if (l.bounce_only && p.depth == 0) continue;
      const Light& light = *l.light;
      if (light.type == LightType::kDirectional) {
        const float c = glm::dot(p.normal, -light.direction);
        if (!(c > 0.0f)) continue;
        rays.push_back({origin, eps_, -light.direction, extent_});
        value.push_back(p.throughput * l.radiant * c);
        owner.push_back(p.value);
        continue;
      }
      if (!(light.radius > 0.0f)) {
        const float e =
            punctual_irradiance(light, light.position, p.position, p.normal, eps_ * eps_);
        if (!(e > 0.0f)) continue;
        if (!(glm::length(light.position - origin) > 2.0f * eps_)) continue;
        add(light.position, l.radiant * e, eps_);
        continue;
      }
      const float u = rng.next(), v = rng.next();
      // Wholly behind the surface: nothing to sample.
      if (glm::dot(light.position - p.position, p.normal) <= -light.radius) continue;
      SphereView view;
      if (!view_sphere_light(light, p.position, &view)) continue;
      float t_surface = 0.0f;
      const glm::vec3 w = sample_sphere_view(view, p.normal, u, v, &t_surface);
      const float c = glm::dot(p.normal, w);
      const float pdf = sphere_view_pdf(view, p.normal, w);
      if (!(c > 0.0f) || !(pdf > 0.0f)) continue;
      const float weight = power_weight(pdf, c / kPi);
      add(p.position + w * t_surface, l.radiant * (view.radiance * c / pdf * weight), eps_);
    }
    if (emissive_.empty()) return;
    const float u0 = rng.next(), u1 = rng.next(), u2 = rng.next();
    const EmissiveLights::Point pt = emissive_.sample_point(p.position, u0, u1, u2);
    const glm::vec3 to = pt.position - origin;
    const float d2 = glm::dot(to, to);
    const float d = std::sqrt(d2);
    if (!(d > 4.0f * eps_) || !(pt.pdf_area > 0.0f)) return;
    const glm::vec3 dir = to / d;
    const float cos_a = glm::dot(p.normal, dir);
    const float cos_b = -glm::dot(pt.normal, dir);
    if (!(cos_a > 0.0f) || !(cos_b > 0.0f)) return;
    const float pdf_light = pt.pdf_area * d2 / cos_b;  // per solid angle
    // An emitter no ray can hit (castShadows false) is found by sampling alone: full weight.
    const float weight =
        emissive_.hittable(pt.emitter) ? power_weight(pdf_light, cos_a / kPi) : 1.0f;
    add(pt.position, pt.radiance * (cos_a / pdf_light * weight), 2.0f * eps_);
  }

  bool hidden(int mesh) const {
    const int o = scene_.meshes[static_cast<size_t>(mesh)].object;
    return o >= 0 && visible_[static_cast<size_t>(o)] == 0;
  }

  // Static geometry and visible objects block; hidden objects do not.
  void occluded(const std::vector<Ray>& rays, std::vector<uint8_t>& blocked, std::vector<Hit>& hits,
                std::vector<int>& found) const {
    const int n = static_cast<int>(rays.size());
    if (!any_visible_) {
      tracer_.occluded_static_many(rays.data(), n, blocked.data());
      return;
    }
    if (!any_hidden_) {
      tracer_.occluded_many(rays.data(), n, blocked.data());
      return;
    }
    hits.resize(rays.size());
    tracer_.intersect_many(rays.data(), n, hits.data(), true);
    for (size_t i = 0; i < rays.size(); ++i) {
      blocked[i] = hits[i].hit ? 1 : 0;
      if (!hits[i].hit || !hidden(hits[i].mesh)) continue;
      // A hidden object in the way: ask again along the whole segment.
      const Ray& r = rays[i];
      const int k = tracer_.shadow_query(r.origin, r.dir, r.tmin, r.tmax, found.data(),
                                         static_cast<int>(found.size()));
      bool b = k < 0;
      for (int j = 0; j < k && !b; ++j)
        b = visible_[static_cast<size_t>(found[static_cast<size_t>(j)])] != 0;
      blocked[i] = b ? 1 : 0;
    }
  }

  // Closest hits on static geometry and visible objects.
  void intersect(const std::vector<Ray>& rays, std::vector<Hit>& hits) const {
    tracer_.intersect_many(rays.data(), static_cast<int>(rays.size()), hits.data(), any_visible_);
    if (!any_visible_ || !any_hidden_) return;
    for (size_t i = 0; i < rays.size(); ++i) {
      if (!hits[i].hit || !hidden(hits[i].mesh)) continue;
      const Ray& r = rays[i];
      float tmin = hits[i].t + eps_;
      Hit h;
      int step = 0;
      for (; step < kHiddenSteps && r.tmax > tmin; ++step) {
        h = tracer_.intersect(r.origin, r.dir, tmin, r.tmax, true);
        if (!h.hit || !hidden(h.mesh)) break;
        tmin = h.t + eps_;
        h = Hit{};
      }
      if (step == kHiddenSteps && r.tmax > tmin) {
        h = tracer_.intersect(r.origin, r.dir, tmin, r.tmax, false);
      }
      hits[i] = h;
    }
  }

  const Scene& scene_;
  const TexelSet& texels_;
  const std::vector<uint8_t>& traced_;  // valid texels of the region
  const Tracer& tracer_;
  const std::vector<uint8_t>& visible_;
  EmissiveLights emissive_;
  // A texel's irradiance is its mean over its surface patch, as the cook defines it: each path
  // starts at its own point of the patch.
  std::vector<TexelFootprint> footprints_;
  uint64_t seed_;
  std::vector<Light> posed_;  // the scene's lights, moving ones at the state's pose
  std::vector<LitLight> lights_;
  std::vector<LitLight> spheres_;  // lit lights with a radius: MIS on the rays that cross them
  bool any_visible_ = false, any_hidden_ = false;
  float eps_ = 0.0f, extent_ = 0.0f;
};

// Per-texel running sums of the kept samples (in sample order, so any pass or thread split gives
// the same bits) and how many there are.
struct Accumulator {
  std::vector<double> sum, sum_sq;  // 3 per texel
  std::vector<uint32_t> count;      // kept samples per texel
  explicit Accumulator(size_t texels)
      : sum(3 * texels, 0.0), sum_sq(3 * texels, 0.0), count(texels, 0) {}
};

struct Noise {
  double mean_rel = 0.0, rel_rmse = 0.0;
};

// Mean and standard error of texel t over its kept samples (0 and 0 without any).
void texel_estimate(const Accumulator& acc, size_t t, glm::vec3* mean, glm::vec3* se) {
  const double n = acc.count[t];
  *mean = *se = glm::vec3(0.0f);
  if (n == 0) return;
  for (int c = 0; c < 3; ++c) {
    const double s = acc.sum[3 * t + size_t(c)], q = acc.sum_sq[3 * t + size_t(c)];
    const double m = s / n;
    const double var = n > 1 ? std::max(0.0, (q - s * m) / (n - 1)) : 0.0;
    (*mean)[c] = static_cast<float>(m);
    (*se)[c] = static_cast<float>(std::sqrt(var / n));
  }
}

Noise noise_of(const Accumulator& acc, const std::vector<uint8_t>& traced) {
  std::vector<float> peaks;
  double se2 = 0.0, m2 = 0.0;
  for (size_t t = 0; t < traced.size(); ++t) {
    if (!traced[t]) continue;
    glm::vec3 m, se;
    texel_estimate(acc, t, &m, &se);
    peaks.push_back(max3(m));
    se2 += glm::dot(glm::dvec3(se), glm::dvec3(se));
    m2 += glm::dot(glm::dvec3(m), glm::dvec3(m));
  }
  Noise out;
  out.rel_rmse = m2 > 0.0 ? std::sqrt(se2 / m2) : 0.0;
  if (peaks.empty()) return out;
  std::vector<float> sorted = peaks;
  const size_t k = std::min(sorted.size() - 1, sorted.size() * 99 / 100);
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(k), sorted.end());
  const float matter = 0.01f * sorted[k];
  double sum = 0.0;
  size_t count = 0;
  size_t i = 0;
  for (size_t t = 0; t < traced.size(); ++t) {
    if (!traced[t]) continue;
    const float peak = peaks[i++];
    if (!(peak > 0.0f) || peak < matter) continue;
    glm::vec3 m, se;
    texel_estimate(acc, t, &m, &se);
    sum += glm::length(glm::dvec3(se)) / glm::length(glm::dvec3(m));
    ++count;
  }
  out.mean_rel = count > 0 ? sum / static_cast<double>(count) : 0.0;
  return out;
}

std::string percent(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f %%", 100.0 * v);
  return buf;
}

}  // namespace

ReferenceBake bake_reference(const Scene& scene, const TexelSet& texels, const Tracer& tracer,
                             const StateSpec& state, const ReferenceOptions& options,
                             Progress& progress, Report& report) {
  check_bake_inputs(scene, texels);
  if (options.samples < 2) throw CookError("the reference integrator needs at least 2 samples");
  const ResolvedState resolved = resolve_state(scene, state);
  const auto t0 = std::chrono::steady_clock::now();
  const uint64_t rays0 = tracer.rays_traced();
  const int threads = worker_count(options.threads);
  if (!options.region.empty() && options.region.size() != texels.valid.size())
    throw CookError("the reference's region has " + std::to_string(options.region.size()) +
                    " flags for " + std::to_string(texels.valid.size()) + " texels");
  std::vector<uint8_t> traced(texels.valid.size());
  for (size_t t = 0; t < traced.size(); ++t)
    traced[t] = texels.valid[t] && (options.region.empty() || options.region[t]);
  const PathTracer tracer_of_paths(scene, texels, traced, tracer, resolved, options.seed,
                                   options.texel_patch, threads, options.moving_direct);
  const int w = texels.width, h = texels.height;
  Accumulator acc(texels.position.size());
  const int passes = (options.samples + kPassSamples - 1) / kPassSamples;
  progress.begin("reference", static_cast<uint64_t>(passes) * static_cast<uint64_t>(h));
  int done = 0;  // samples traced per texel
  for (int pass = 0; pass < passes; ++pass) {
    const int s0 = pass * kPassSamples, s1 = std::min(options.samples, s0 + kPassSamples);
    parallel_for(h, threads, [&](int y) {
      std::vector<glm::vec3> values;
      std::vector<uint8_t> kept;
      tracer_of_paths.trace_row(y, s0, s1, values, kept);
      size_t k = 0;
      for (int x = 0; x < w; ++x) {
        const size_t t = texels.index(x, y);
        if (!traced[t]) continue;
        for (int s = s0; s < s1; ++s, ++k) {
          if (!kept[k]) continue;
          ++acc.count[t];
          for (int c = 0; c < 3; ++c) {
            const double v = values[k][c];
            acc.sum[3 * t + size_t(c)] += v;
            acc.sum_sq[3 * t + size_t(c)] += v * v;
          }
        }
      }
      progress.advance();
    });
    done = s1;
    // Convergence so far, at each power of two; the noise target is checked from
    // kMinTargetSamples on (fewer samples estimate the spread too poorly to stop on).
    if (s1 < options.samples && (s1 & (s1 - 1)) == 0) {
      const bool check = options.target_noise > 0.0 && s1 >= kMinTargetSamples;
      if (check || !progress.quiet()) {
        const Noise n = noise_of(acc, traced);
        progress.message("reference: " + std::to_string(s1) +
                         " samples, mean relative standard "
                         "error " +
                         percent(n.mean_rel) + ", noise rel. RMSE " + percent(n.rel_rmse));
        if (check && n.rel_rmse <= options.target_noise) break;
      }
    }
  }
  const double stage_s = progress.end();

  ReferenceBake out;
  out.samples = done;
  out.map = FloatImage(w, h, 3);
  out.std_error = FloatImage(w, h, 3);
  uint64_t kept_paths = 0, traced_texels = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t t = texels.index(x, y);
      if (!traced[t]) continue;
      ++traced_texels;
      kept_paths += acc.count[t];
      // A texel with no path in the open (under a wall, inside a table top) is never seen: 0.
      if (acc.count[t] == 0) ++out.inside_texels;
      glm::vec3 m, se;
      texel_estimate(acc, t, &m, &se);
      for (int c = 0; c < 3; ++c) {
        out.map.at(x, y, c) = std::max(0.0f, m[c]);
        out.std_error.at(x, y, c) = se[c];
      }
    }
  }
  const uint64_t all_paths = traced_texels * uint64_t(done);
  out.inside_path_fraction =
      all_paths > 0 ? double(all_paths - kept_paths) / double(all_paths) : 0.0;
  const Noise noise = noise_of(acc, traced);
  out.mean_rel_std_error = noise.mean_rel;
  out.rel_rmse_noise = noise.rel_rmse;
  out.rays = tracer.rays_traced() - rays0;
  out.seconds = seconds_since(t0);

  report.stage_time("bake.reference", stage_s);
  std::lock_guard<std::mutex> lock(report.mutex());
  nlohmann::json& j = report.root()["reference"];
  j["integrator"] =
      "path tracing: cosine-weighted hemisphere, next-event estimation to every light with MIS "
      "(power heuristic) for light spheres and emissive triangles, Russian roulette on the albedo";
  j["samples"] = out.samples;
  j["max_samples"] = options.samples;
  j["target_noise"] = options.target_noise;
  j["seed"] = options.seed;
  j["threads"] = threads;
  j["max_bounces"] = kReferenceMaxBounces;
  j["rays"] = out.rays;
  j["seconds"] = out.seconds;
  j["rays_per_second"] = out.seconds > 0.0 ? static_cast<double>(out.rays) / out.seconds : 0.0;
  j["mean_rel_std_error"] = out.mean_rel_std_error;
  j["rel_rmse_noise"] = out.rel_rmse_noise;
  j["inside_texels"] = out.inside_texels;
  j["inside_path_fraction"] = out.inside_path_fraction;
  j["noise_definition"] =
      "mean_rel_std_error: mean over texels that matter (max channel >= 1% of its 99th "
      "percentile) of |standard error| / |irradiance| (RGB norms); rel_rmse_noise: sqrt(sum "
      "se^2 / sum E^2) over valid texels, the relative RMSE the reference's noise alone gives";
  return out;
}

}  // namespace lightpatch::cooker
