// The baker (DESIGN.md, "The method in one screen"). B: static lights and emissive surfaces,
// semi-dynamic objects absent. For each semi-dynamic light, one pass over its shadow rays: each
// ray is traced once against the static scene and, in the same traversal, collects the
// semi-dynamic objects it crosses; an unblocked sample adds to C_l and to S_ol of every object o
// crossing it (T_ol = C_l minus what o blocks). So a semi-dynamic cook costs about one bake.
//
// Indirect light (indirect_light.h): B adds the static lights' photons as virtual indirect lights
// (VPLs), objects absent. C_l adds light l's VPLs, S_ol what object o changes in them: the VPL
// rays o blocks (found by the same shadow_query that gives the static occlusion), the power its
// presence moves between the static VPLs (photon paths cut at o and continued from o's surface),
// and the VPLs on o itself (its bounce, negative in S_ol). bake_state runs the same photons with
// the state's objects present, so for one object it computes exactly T_ol.
#include "lightpatch/cooker/bake.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "direct_light.h"
#include "gather.h"
#include "indirect_light.h"
#include "indirect_solve.h"
#include "lightpatch/cooker/error.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {

// Pairs whose shadow map never exceeds this fraction of the light's significance threshold
// (half an 8-bit step at the authored exposure) would round away: they are skipped.
constexpr float kPairKeepFraction = 0.5f;
// The reason of every decision made with the plan off (BakeOptions::plan_effects).
constexpr const char* kForced = "forced on (--no-plan)";
// Floor of output_step for a scene that is black at its authored state and has no semi-dynamic
// light to expose for.
constexpr float kMinOutputStep = 1e-6f;
// Final gathering: bounce terms below this fraction of a group's significance threshold are
// dropped (the Neumann series stops when a bounce adds less anywhere).
constexpr float kBounceTolerance = 0.02f;

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

float max3(const glm::vec3& v) {
  return std::max({v.x, v.y, v.z});
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

GatherPreset preset_gather(Quality q) {
  switch (q) {
    case Quality::kDraft:
      return {64, 4, 2};
    case Quality::kPreview:
      return {256, 2, 2};
    case Quality::kProduction:
      return {1024, 2, 1};
  }
  return {256, 2, 2};
}

IndirectPreset preset_indirect(Quality q) {
  switch (q) {
    case Quality::kDraft:
      return {30000, 192, 1.0f};
    case Quality::kPreview:
      return {120000, 512, 1.0f};
    case Quality::kProduction:
      return {500000, 2048, 0.5f};
  }
  return {120000, 512, 1.0f};
}

// Photons and VPLs of one light group (all static emitters, or one semi-dynamic light).
struct GroupSize {
  int photons = 0;
  int lights = 0;
};

// A light group's indirect light, planned.
struct Indirect {
  std::unique_ptr<PhotonGroup> photons;
  bool enabled = false;
  std::string reason;
  float threshold = 0.0f;         // significance of this group's irradiance (its map's units)
  float cutoff = 0.0f;            // per-VPL early out
  std::vector<uint8_t> relevant;  // per object: photons crossing it matter (its bounce is traced)
  std::vector<std::string> irrelevant_reason;
};

struct LightPlan {
  int index = 0;           // Scene::lights
  float threshold = 0.0f;  // significance of intensity-1 irradiance: output_step / authored scale
  float cutoff = 0.0f;     // early out: kEarlyOutFraction * threshold
  int samples = 1;
};

struct Baker {
  const Scene& scene;
  const TexelSet& texels;
  const Tracer& tracer;
  int threads = 1;
  int area_samples = 16;
  uint64_t seed = 1;
  float eps = 0.0f;
  float extent = 0.0f;
  float output_step = 0.0f;
  // Significance of the static group (base map, static indirect, static shadows): output_step, or
  // one 8-bit step of the brightest static light's own peak where that is finer, so that a static
  // light far dimmer than the semi-dynamic ones keeps 8 bits of its own when they are off.
  float static_step = 0.0f;
  EmissiveLights emissive;
  std::vector<LightPlan> plans;  // parallel to Scene::lights
  bool indirect = false;
  bool plan = true;  // BakeOptions::plan_effects; false: everything forced on
  Integrator integrator = Integrator::kGather;
  GatherPreset gp;
  std::unique_ptr<GatherOperator> gather;  // built by bake_maps / bake_state when gathering
  IndirectPreset preset;
  IndirectSettings settings;
  std::vector<Emitter> static_emitters;
  GroupSize static_size;
  std::vector<GroupSize> light_size;  // parallel to Scene::lights (semi-dynamic ones)

  Baker(const Scene& s, const TexelSet& t, const Tracer& tr, const BakeOptions& o)
      : scene(s), texels(t), tracer(tr), emissive(s) {
    threads = worker_count(o.threads);
    area_samples = o.area_samples > 0 ? o.area_samples : preset_samples(o.quality);
    seed = o.seed;
    eps = tracer.epsilon();
    const float scale = scene.scale() > 0.0f ? scene.scale() : 1.0f;
    extent = 1.5f * scale;  // any segment inside the bounds is shorter than the diagonal
    output_step = compute_output_step();
    build_tiles();
    float s_max = 0.0f;
    for (const Light& l : scene.lights) s_max = std::max(s_max, max3(l.color) * l.intensity);
    const std::vector<float> own = own_peaks();
    // The static lights' brightest peak at their authored colours (a lower bound of the base map's
    // peak). Emissive surfaces are not in it: with no punctual static light the step stays.
    float static_peak = 0.0f;
    for (size_t i = 0; i < scene.lights.size(); ++i) {
      const Light& l = scene.lights[i];
      LightPlan p;
      p.index = static_cast<int>(i);
      // A light authored dim (or at 0) is given the significance of a light 1/100 as bright as
      // the brightest, so that it keeps its patches when turned up at run time.
      const float a = max3(l.color) * l.intensity;
      float s = std::max(a, 1e-2f * s_max);
      if (!(s > 0.0f)) s = 1.0f;
      p.threshold = output_step / s;
      // A semi-dynamic light may be the only one on: its significance is also at most one 8-bit
      // step of its own peak, so a 1e-2 cd light beside a 1e4 cd one still recomposes alone to 8
      // bits (pack_builder.cpp cuts patches by the same rule). Static lights follow the same rule,
      // so a light bakes the same whether static or semi-dynamic.
      if (own[i] > 0.0f) p.threshold = std::min(p.threshold, own[i] / 255.0f);
      p.cutoff = kEarlyOutFraction * p.threshold;
      p.samples = (l.radius > 0.0f && l.type != LightType::kDirectional) ? area_samples : 1;
      plans.push_back(p);
      if (!l.semi_dynamic && a > 0.0f && std::isfinite(a))
        static_peak = std::max(static_peak, own[i] * a);
    }
    static_step = static_peak > 0.0f ? std::min(output_step, static_peak / 255.0f) : output_step;
    indirect = o.indirect;
    plan = o.plan_effects;
    preset = indirect_preset(o);
    settings.photons = preset.photons;
    settings.virtual_lights = preset.virtual_lights;
    settings.area_bias = preset.area_bias;
    integrator = o.integrator;
    gp = gather_preset(o);
    if (photons()) plan_photons(s_max);
  }

  bool photons() const { return indirect && integrator == Integrator::kPhotons; }
  bool gathering() const { return indirect && integrator == Integrator::kGather; }

  // Traces the gather rays once for the whole bake.
  void build_gather(const Layout& layout, Progress& progress, Report& report) {
    if (!gathering()) return;
    progress.begin("gather rays", 1);
    GatherOptions go;
    go.rays = gp.rays;
    go.seed = seed;
    go.threads = threads;
    gather = std::make_unique<GatherOperator>(
        cooker::build_gather(scene, layout, texels, tracer, gp.level, go));
    report.stage_time("bake.gather_rays", progress.end());
    std::lock_guard<std::mutex> lock(report.mutex());
    nlohmann::json& g = report.root()["gather"];
    g["level"] = gp.level;
    g["rays_per_coarse_texel"] = gp.rays;
    g["denoise_passes"] = gp.denoise;
    g["coarse_texels"] = gather->grid.size();
    g["rays"] = gather->rays_traced;
    g["crossings"] = gather->crossings.size();
  }

  // Photon counts proportional to power (seed 004 §6.3.2): the static group's emitted flux at its
  // authored colours, each semi-dynamic light's at its authored colour and intensity (floored
  // like its significance, so a light authored dim still gets photons). VPLs follow the photons,
  // so an all-static and a semi-dynamic cook of one scene gather about the same number.
  void plan_photons(float s_max) {
    for (const Light& l : scene.lights) {
      if (!l.semi_dynamic) {
        static_emitters.push_back(
            light_emitter(l, l.color * l.intensity, scene.bounds_min, scene.bounds_max));
      }
    }
    for (const Emitter& e : emissive_emitters(scene)) static_emitters.push_back(e);
    double p_static = 0.0;
    for (const Emitter& e : static_emitters) p_static += std::max(0.0f, max3(e.flux));
    std::vector<double> p_light(scene.lights.size(), 0.0);
    double total = p_static;
    for (size_t i = 0; i < scene.lights.size(); ++i) {
      const Light& l = scene.lights[i];
      if (!l.semi_dynamic) continue;
      float s = std::max(max3(l.color) * l.intensity, 1e-2f * s_max);
      if (!(s > 0.0f)) s = 1.0f;
      const Emitter e = light_emitter(l, glm::vec3(1.0f), scene.bounds_min, scene.bounds_max);
      p_light[i] = std::max(0.0, static_cast<double>(max3(e.flux)) * s);
      total += p_light[i];
    }
    auto size_for = [&](double p) {
      GroupSize g;
      if (!(p > 0.0) || !(total > 0.0)) return g;
      const double n = static_cast<double>(preset.photons);
      g.photons = static_cast<int>(std::max(n / 64.0, std::round(n * p / total)));
      g.lights = static_cast<int>(
          std::max(8.0, std::round(preset.virtual_lights * static_cast<double>(g.photons) / n)));
      return g;
    };
    static_size = size_for(p_static);
    light_size.resize(scene.lights.size());
    for (size_t i = 0; i < scene.lights.size(); ++i) light_size[i] = size_for(p_light[i]);
  }

  // Bounds of the valid texels' positions and normals in 16 x 16 blocks of the texel grid: where
  // a VPL can shine.
  struct Tile {
    glm::vec3 lo, hi, n_lo, n_hi;
  };
  std::vector<Tile> tiles;
  void build_tiles() {
    constexpr int kTile = 16;
    for (int ty = 0; ty < texels.height; ty += kTile) {
      for (int tx = 0; tx < texels.width; tx += kTile) {
        const glm::vec3 big(std::numeric_limits<float>::max());
        Tile tile{big, -big, big, -big};
        bool any = false;
        for (int y = ty; y < std::min(ty + kTile, texels.height); ++y) {
          for (int x = tx; x < std::min(tx + kTile, texels.width); ++x) {
            const size_t t = texels.index(x, y);
            if (!texels.valid[t]) continue;
            tile.lo = glm::min(tile.lo, texels.position[t]);
            tile.hi = glm::max(tile.hi, texels.position[t]);
            tile.n_lo = glm::min(tile.n_lo, texels.normal[t]);
            tile.n_hi = glm::max(tile.n_hi, texels.normal[t]);
            any = true;
          }
        }
        if (any) tiles.push_back(tile);
      }
    }
  }

  // Largest form factor cosA cosB / (pi r^2 + bias A) VPL v gives any valid texel of a tile:
  // cosB <= h / r, h the height of the tile's texels above the VPL's plane, cosA <= g / r, g the
  // largest n . (VPL - texel) over the tile's normals and positions (interval bounds), r at least
  // the distance to the tile less the gather's offsets (which only lower both cosines). 0 where
  // the texels lie in or behind the VPL's plane: an open plane's VPLs light nothing.
  float vpl_bound(const VirtualLight& v, float bias) const {
    constexpr float kPi = 3.14159265358979f;
    float best = 0.0f;
    for (const Tile& tile : tiles) {
      float h = -std::numeric_limits<float>::max();
      for (int c = 0; c < 8; ++c) {
        const glm::vec3 corner(c & 1 ? tile.hi.x : tile.lo.x, c & 2 ? tile.hi.y : tile.lo.y,
                               c & 4 ? tile.hi.z : tile.lo.z);
        h = std::max(h, glm::dot(v.normal, corner - v.position));
      }
      if (!(h > 0.0f)) continue;
      float g = 0.0f;
      for (int i = 0; i < 3; ++i) {
        const float q_lo = v.position[i] - tile.hi[i], q_hi = v.position[i] - tile.lo[i];
        g += std::max(
            {tile.n_lo[i] * q_lo, tile.n_lo[i] * q_hi, tile.n_hi[i] * q_lo, tile.n_hi[i] * q_hi});
      }
      if (!(g > 0.0f)) continue;
      const float dist = glm::length(glm::clamp(v.position, tile.lo, tile.hi) - v.position);
      const float r = std::max(dist - 2.0f * eps, 2.0f * eps);
      const float f = std::min(1.0f, h / r) * std::min(1.0f, g / r) / (kPi * r * r + bias * v.area);
      best = std::max(best, f);
    }
    return best;
  }

  // Traces a group's photons and decides whether its indirect light is worth gathering.
  // li < 0: the static group. `track`: record the objects photon paths cross.
  Indirect make_indirect(int li, bool track) const {
    Indirect ind;
    const GroupSize size = li < 0 ? static_size : light_size[static_cast<size_t>(li)];
    std::vector<Emitter> emitters;
    if (li < 0) {
      emitters = static_emitters;
      ind.threshold = static_step;
    } else {
      const Light& l = scene.lights[static_cast<size_t>(li)];
      emitters.push_back(light_emitter(l, glm::vec3(1.0f), scene.bounds_min, scene.bounds_max));
      ind.threshold = plans[static_cast<size_t>(li)].threshold;
    }
    ind.relevant.assign(scene.objects.size(), 0);
    ind.irrelevant_reason.assign(scene.objects.size(), "");
    if (emitters.empty() || size.photons <= 0) {
      ind.reason = "emits no power";
      return ind;
    }
    ind.photons = std::make_unique<PhotonGroup>(scene, tracer, std::move(emitters), size.photons,
                                                size.lights, settings, seed,
                                                static_cast<uint64_t>(li + 1), threads, track);
    const PhotonGroup& g = *ind.photons;
    const float bias = std::max(settings.area_bias, 0.1f);
    if (g.emitted() == 0) {
      ind.reason = "emits no power";
      return ind;
    }
    if (!plan) {
      // Every object's bounce traced, whatever its photons carry.
      ind.enabled = true;
      ind.cutoff = kEarlyOutFraction * ind.threshold /
                   static_cast<float>(std::max<size_t>(1, g.lights().size()));
      ind.reason = std::string(kForced) + ": " + std::to_string(g.emitted()) + " photons, " +
                   std::to_string(g.lights().size()) + " virtual lights";
      ind.relevant.assign(scene.objects.size(), 1);
      return ind;
    }
    if (g.deposits() == 0) {
      ind.reason = g.lost() == g.emitted()
                       ? "all " + std::to_string(g.emitted()) +
                             " photons left the scene (open geometry or light facing away)"
                       : "no photon was reflected (" + std::to_string(g.lost()) + " of " +
                             std::to_string(g.emitted()) + " left the scene, the rest hit black)";
      return ind;
    }
    // Peak irradiance the VPLs could give any texel (each at the tile it lights most).
    std::vector<float> per_vpl(g.lights().size());
    parallel_for(static_cast<int>(per_vpl.size()), threads, [&](int i) {
      const VirtualLight& v = g.lights()[size_t(i)];
      per_vpl[size_t(i)] = max3(v.power) * vpl_bound(v, bias);
    });
    double bound = 0.0;
    for (float f : per_vpl) bound += f;
    if (bound < 0.5 * ind.threshold) {
      ind.reason = "indirect irradiance bound " + std::to_string(bound) +
                   " below half an output step (" + std::to_string(0.5f * ind.threshold) + ")";
      return ind;
    }
    ind.enabled = true;
    ind.cutoff = kEarlyOutFraction * ind.threshold / static_cast<float>(g.lights().size());
    ind.reason = std::to_string(g.emitted()) + " photons (" + std::to_string(g.lost()) +
                 " left the scene), " + std::to_string(g.deposits()) + " stored, " +
                 std::to_string(g.lights().size()) + " virtual lights";
    // An object's bounce and the photons it blocks are traced only where the power of the photon
    // paths crossing it, gathered in one VPL of mean area, would show.
    for (size_t o = 0; o < scene.objects.size(); ++o) {
      const float p = track ? g.crossing_power()[o] : 0.0f;
      const float peak = p / (bias * g.mean_area());
      if (peak >= 0.5f * ind.threshold) {
        ind.relevant[o] = 1;
      } else {
        ind.irrelevant_reason[o] = p > 0.0f ? "photons crossing it carry " + std::to_string(p) +
                                                  " W, peak bound " + std::to_string(peak) +
                                                  " below half an output step"
                                            : "no photon of the light crosses it";
      }
    }
    return ind;
  }

  uint64_t texel_rng(size_t texel, int slot) const {
    return sample_hash(seed, texel, static_cast<uint64_t>(slot), 0);
  }

  // Unshadowed irradiance of the authored state (max channel) at each valid texel; its 99th
  // percentile is the top of the 8-bit range, output_step one 255th of it.
  float percentile_step(bool authored) const {
    std::vector<float> values(texels.position.size(), -1.0f);
    const float eps2 = eps * eps;
    parallel_for(texels.height, threads, [&](int y) {
      std::vector<LightSample> samples;
      for (int x = 0; x < texels.width; ++x) {
        const size_t t = texels.index(x, y);
        if (!texels.valid[t]) continue;
        glm::vec3 e(0.0f);
        for (const Light& l : scene.lights) {
          if (!authored && !l.semi_dynamic) continue;
          const glm::vec3 c = authored ? l.color * l.intensity : glm::vec3(1.0f);
          e += c * punctual_irradiance(l, l.position, texels.position[t], texels.normal[t], eps2);
        }
        if (authored && !emissive.empty()) {
          samples.clear();
          emissive.sample(texels.position[t], texels.normal[t], std::min(area_samples, 4),
                          texel_rng(t, 0), eps, samples);
          for (const LightSample& s : samples) e += s.irradiance;
        }
        values[t] = std::isfinite(max3(e)) ? max3(e) : 0.0f;
      }
    });
    values.erase(std::remove(values.begin(), values.end(), -1.0f), values.end());
    if (values.empty()) return 0.0f;
    const size_t k = std::min(values.size() - 1, values.size() * 99 / 100);
    std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
    return values[k] / 255.0f;
  }

  // Per scene light: the peak over valid texels of its unshadowed direct irradiance at colour
  // (1,1,1) and intensity 1.
  std::vector<float> own_peaks() const {
    const size_t n = scene.lights.size();
    std::vector<float> rows(static_cast<size_t>(texels.height) * n, 0.0f);
    const float eps2 = eps * eps;
    parallel_for(texels.height, threads, [&](int y) {
      for (size_t i = 0; i < n; ++i) {
        float peak = 0.0f;
        for (int x = 0; x < texels.width; ++x) {
          const size_t t = texels.index(x, y);
          if (!texels.valid[t]) continue;
          const Light& l = scene.lights[i];
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

  float compute_output_step() const {
    float step = percentile_step(true);
    if (!(step > 0.0f)) step = percentile_step(false);
    // The floor is for a black scene only: as a floor under every scene it was an absolute
    // irradiance, not scaled with the scene (a 10 km room under the same candela is 1e-8 as
    // bright as a 1 m one, below 1e-6, and every texel was culled as insignificant).
    return step > 0.0f ? step : kMinOutputStep;
  }

  // Shadow samples of scene light `li` (intensity 1, white) at texel t.
  void light_samples(int li, size_t t, std::vector<LightSample>& out) const {
    const LightPlan& p = plans[static_cast<size_t>(li)];
    sample_punctual(scene.lights[static_cast<size_t>(li)], texels.position[t], texels.normal[t],
                    p.samples, texel_rng(t, li + 1), eps, extent, p.cutoff, out);
  }
  void emissive_samples(size_t t, std::vector<LightSample>& out) const {
    emissive.sample(texels.position[t], texels.normal[t], area_samples, texel_rng(t, 0), eps, out);
  }
};

struct Bounds {
  glm::vec3 lo{std::numeric_limits<float>::max()};
  glm::vec3 hi{-std::numeric_limits<float>::max()};
  bool empty() const { return lo.x > hi.x; }
};

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

// Geometric pair culling: can object o stand between light l and a texel the light reaches
// above its early-out cutoff? Exact with respect to the baker's early outs (see bake.cpp notes):
// a shadow ray through o starts beyond o, so if o is beyond the light's reach so is the texel;
// a spot's samples outside its cone carry no light. Returns "" when the pair must be traced.
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

std::string light_name(const Scene& scene, int li) {
  const std::string& n = scene.lights[static_cast<size_t>(li)].name;
  return n.empty() ? "light#" + std::to_string(li) : n;
}

void check_inputs(const Scene& scene, const TexelSet& texels) {
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

void add_indirect_report(Report& report, const std::string& group, const Indirect& ind) {
  nlohmann::json g = {{"group", group}, {"enabled", ind.enabled}, {"reason", ind.reason}};
  if (ind.photons) {
    const PhotonGroup& p = *ind.photons;
    g["photons_emitted"] = p.emitted();
    g["photons_lost"] = p.lost();
    g["photons_stored"] = p.deposits();
    g["virtual_lights"] = p.lights().size();
    g["reflected_power"] = p.deposited_power();
    g["mean_virtual_light_area"] = p.mean_area();
  }
  std::lock_guard<std::mutex> lock(report.mutex());
  nlohmann::json& groups = report.root()["indirect"]["groups"];
  if (!groups.is_array()) groups = nlohmann::json::array();
  groups.push_back(std::move(g));
}

void fill_report_bake(Report& report, const Baker& b, Quality q, double seconds, uint64_t rays0) {
  const uint64_t rays = b.tracer.rays_traced() - rays0;
  std::lock_guard<std::mutex> lock(report.mutex());
  nlohmann::json& j = report.root()["bake"];
  j["output_step"] = b.output_step;
  j["static_step"] = b.static_step;
  j["output_step_definition"] =
      "99th percentile over valid texels of the authored state's unshadowed direct irradiance "
      "(max channel) / 255";
  j["static_step_definition"] =
      "min(output_step, the brightest static light's peak unshadowed irradiance / 255): the "
      "significance of the base map, static indirect light and static shadows";
  j["quality"] = quality_name(q);
  j["plan_effects"] = b.plan;
  j["area_samples"] = b.area_samples;
  j["threads"] = b.threads;
  j["epsilon"] = b.eps;
  j["rays"] = j.value("rays", uint64_t{0}) + rays;
  j["seconds"] = j.value("seconds", 0.0) + seconds;
  const double total_s = j["seconds"].get<double>();
  j["rays_per_second"] =
      total_s > 0.0 ? static_cast<double>(j["rays"].get<uint64_t>()) / total_s : 0.0;
  nlohmann::json& ind = report.root()["indirect"];
  ind["enabled"] = b.indirect;
  ind["integrator"] = integrator_name(b.integrator);
  if (b.integrator == Integrator::kGather) {
    ind["rays_per_coarse_texel"] = b.gp.rays;
    ind["level"] = b.gp.level;
    ind["denoise_passes"] = b.gp.denoise;
    return;
  }
  ind["photons"] = b.preset.photons;
  ind["virtual_lights"] = b.preset.virtual_lights;
  ind["area_bias"] = b.preset.area_bias;
  ind["form_factor"] = "cosA cosB / (pi r^2 + bias A), A = area of the VPL's merged photons";
}

// What one light group's pass traces: slots, each a set of objects whose joint presence the slot's
// map measures (one object for S, two for the joint change of an overlapping pair).
struct Candidates {
  explicit Candidates(size_t objects) : slots_of(objects) {}
  void add(std::vector<int> set) {
    for (int o : set) slots_of[size_t(o)].push_back(int(sets.size()));
    objects.push_back(set.front());
    sets.push_back(std::move(set));
  }
  void add(int o) { add(std::vector<int>{o}); }
  std::vector<std::vector<int>> sets;      // slot -> Scene::objects indices
  std::vector<int> objects;                // slot -> its first object
  std::vector<std::vector<int>> slots_of;  // Scene::objects index -> slots holding it
};

// What each candidate changes in a group's photons: power moved between the group's VPLs
// (sparse, per VPL) and the VPLs on the object itself.
struct ObjectChanges {
  struct Delta {
    int slot;
    glm::vec3 power;
  };
  struct ObjectLight {
    int slot;
    VirtualLight light;
    float bound;
  };
  std::vector<std::vector<Delta>> deltas;  // per VPL of the group
  std::vector<ObjectLight> object_lights;
};

ObjectChanges object_changes(const Baker& b, const Scene& scene, int li, const Indirect& ind,
                             const Candidates& cand, Progress& progress, Report& report) {
  ObjectChanges out;
  if (!ind.enabled) return out;
  const PhotonGroup& g = *ind.photons;
  out.deltas.resize(g.lights().size());
  const std::string group = li < 0 ? "static lights" : light_name(scene, li);
  progress.begin("bounce of objects: " + group, cand.sets.size());
  for (size_t j = 0; j < cand.sets.size(); ++j) {
    const int o = cand.objects[j];
    std::string names;
    std::vector<uint8_t> present(scene.objects.size(), 0);
    bool relevant = false;
    for (int m : cand.sets[j]) {
      names += (names.empty() ? "" : " + ") + scene.objects[size_t(m)].name;
      present[size_t(m)] = ind.relevant[size_t(m)];
      relevant |= ind.relevant[size_t(m)] != 0;
    }
    const std::string what = "indirect bounce: " + group + " / " + names;
    if (!relevant) {
      report.add_decision(what, false, ind.irrelevant_reason[size_t(o)]);
      progress.advance();
      continue;
    }
    const auto tc = std::chrono::steady_clock::now();
    const PhotonGroup::Change ch = g.change(present);
    const double change_s = seconds_since(tc);
    for (size_t v = 0; v < ch.delta.size(); ++v) {
      if (ch.delta[v] != glm::vec3(0.0f)) out.deltas[v].push_back({int(j), ch.delta[v]});
    }
    for (size_t i = 0; i < ch.object_lights.size(); ++i) {
      out.object_lights.push_back({int(j), ch.object_lights[i], ch.object_bound[i]});
    }
    if (cand.sets[j].size() == 1)
      report.add_decision(what, true,
                          (b.plan ? "" : std::string(kForced) + ": ") +
                              std::to_string(g.crossing_power()[size_t(o)]) +
                              " W of photon paths cross it; " +
                              std::to_string(ch.object_lights.size()) + " virtual lights on it",
                          change_s);
    progress.advance();
  }
  progress.end();
  return out;
}

// One group's bounce light by final gathering, after its direct pass: the group's own indirect
// light (objects absent) and, per candidate slot, what its objects change in it (coarse, not yet
// denoised). `sources` gives each slot's fine direct change.
struct GatherGroup {
  bool enabled = false;
  CoarseMap indirect;     // I with no object present
  CoarseMap empty_total;  // source + albedo * I: the radiance the slots' changes start from
  std::vector<CoarseMap> change;
  // Objects that block none of the group's direct light but may change its bounce light: their
  // change where it was worth solving (parallel to gather_group's `bounce_only`; empty if not).
  std::vector<CoarseMap> bounce_change;
  std::vector<std::string> bounce_reason;
};

// The tolerance shrinks with the scene's mean albedo: a series cut at a term t leaves a tail of
// about t * albedo / (1 - albedo), which is what the decomposition and bake_state may differ by.
SolveOptions solve_options(const GatherOperator& op, float threshold, int threads) {
  SolveOptions so;
  so.tolerance = kBounceTolerance * threshold * (1.0f - op.mean_albedo);
  so.max_bounces = 1024;
  so.threads = threads;
  return so;
}

// A bounce-only object is solved when the first bounce of its change could reach this fraction of
// half an output step; its change only shrinks with further bounces at albedos below one half,
// and the solved change is kept or dropped by its own peak like every other map.
constexpr float kBounceOnlyFraction = 0.5f;

template <typename SlotSource>
GatherGroup gather_group(const Baker& b, const std::string& group, float threshold,
                         const FloatImage& direct, const Candidates& cand,
                         const SlotSource& slot_source, const std::vector<int>& bounce_only,
                         Progress& progress, Report& report) {
  GatherGroup out;
  const GatherOperator& op = *b.gather;
  const auto t0 = std::chrono::steady_clock::now();
  const CoarseMap source = coarse_source(op, b.texels, direct);
  SolveStats st;
  out.indirect = solve_indirect(op, {}, source, solve_options(op, threshold, b.threads), &st);
  const float pk = peak(out.indirect);
  out.enabled = !b.plan || pk >= 0.5f * threshold;
  report.add_decision("indirect light: " + group, out.enabled,
                      (b.plan ? "" : std::string(kForced) + ": ") + "bounce peak " +
                          std::to_string(pk) + (pk >= 0.5f * threshold ? " above" : " below") +
                          " half an output step (" + std::to_string(0.5f * threshold) + "); " +
                          std::to_string(st.bounces) + " bounces",
                      seconds_since(t0));
  out.bounce_change.resize(bounce_only.size());
  out.bounce_reason.assign(bounce_only.size(), "the group's bounce light is off");
  if (!out.enabled) return out;
  out.empty_total = total_radiance(op, source, out.indirect);
  out.change.resize(cand.sets.size());
  const size_t jobs = cand.sets.size() + bounce_only.size();
  std::vector<double> seconds(jobs, 0.0);
  progress.begin("bounce of objects: " + group, jobs);
  parallel_for(int(jobs), b.threads, [&](int j) {
    const auto tj = std::chrono::steady_clock::now();
    std::vector<uint8_t> present(b.scene.objects.size(), 0);
    if (size_t(j) < cand.sets.size()) {
      for (int o : cand.sets[size_t(j)]) present[size_t(o)] = 1;
      const CoarseMap dsrc = slot_source(size_t(j));
      out.change[size_t(j)] =
          solve_change(op, present, out.empty_total, dsrc, solve_options(op, threshold, 1));
    } else {
      const size_t k = size_t(j) - cand.sets.size();
      present[size_t(bounce_only[k])] = 1;
      const float first = first_change_peak(op, present, out.empty_total);
      const float at = kBounceOnlyFraction * 0.5f * threshold;
      if (b.plan && first < at) {
        out.bounce_reason[k] = "first bounce of its change " + std::to_string(first) +
                               " below a quarter output step (" + std::to_string(at) + ")";
      } else {
        out.bounce_reason[k] = (b.plan ? "" : std::string(kForced) + ": ") +
                               "first bounce of its change " + std::to_string(first);
        out.bounce_change[k] =
            solve_change(op, present, out.empty_total, CoarseMap(op.grid.size(), glm::vec3(0.0f)),
                         solve_options(op, threshold, 1));
      }
    }
    seconds[size_t(j)] = seconds_since(tj);
    progress.advance();
  });
  progress.end();
  for (size_t j = 0; j < cand.sets.size(); ++j) {
    std::string names;
    for (int m : cand.sets[j])
      names += (names.empty() ? "" : " + ") + b.scene.objects[size_t(m)].name;
    if (cand.sets[j].size() == 1)
      report.add_decision("indirect bounce: " + group + " / " + names, true,
                          (b.plan ? "" : std::string(kForced) + ": ") +
                              "blocks direct light: its change to the bounce light is solved",
                          seconds[j]);
  }
  for (size_t k = 0; k < bounce_only.size(); ++k)
    report.add_decision(
        "indirect bounce: " + group + " / " + b.scene.objects[size_t(bounce_only[k])].name,
        !out.bounce_change[k].empty(), out.bounce_reason[k], seconds[cand.sets.size() + k]);
  return out;
}

// The first channel of a map whose three are equal (a light's grey transport).
FloatImage first_channel(const FloatImage& m) {
  if (m.channels == 1) return m;
  FloatImage out(m.width, m.height, 1);
  for (size_t i = 0; i < out.data.size(); ++i) out.data[i] = m.data[i * size_t(m.channels)];
  return out;
}

// A coarse map denoised and magnified into `fine` (3 channels), scaled.
void add_bounce(const Baker& b, CoarseMap map, FloatImage& fine, float scale = 1.0f) {
  denoise(b.gather->grid, b.gp.denoise, map);
  add_magnified(b.gather->grid, b.texels, map, fine, scale);
}

// A map whose rows are allocated when first written. A shadow usually darkens a corner of the
// light map: as dense images, a pass's candidates cost (objects x light map) of zeroed memory,
// written and scanned again for each peak; this costs the rows they touch. Each row is written by
// the one worker that traces it (parallel_for over rows), so allocation needs no lock.
class SparseRows {
 public:
  SparseRows(int width, int height, int channels)
      : width_(width), height_(height), channels_(channels), rows_(size_t(height)) {}

  // Row y, zeros until written; y is the caller's own row.
  float* row(int y) {
    std::unique_ptr<float[]>& r = rows_[size_t(y)];
    if (!r) r = std::make_unique<float[]>(size_t(width_) * size_t(channels_));
    return r.get();
  }
  float at(size_t texel, int channel) const {
    const std::unique_ptr<float[]>& r = rows_[texel / size_t(width_)];
    return r ? r[(texel % size_t(width_)) * size_t(channels_) + size_t(channel)] : 0.0f;
  }
  // Largest |value| over valid texels.
  float peak(const TexelSet& texels) const {
    float peak = 0.0f;
    for (int y = 0; y < height_; ++y) {
      const float* r = rows_[size_t(y)].get();
      if (!r) continue;
      for (int x = 0; x < width_; ++x) {
        if (!texels.valid[texels.index(x, y)]) continue;
        for (int c = 0; c < channels_; ++c)
          peak = std::max(peak, std::fabs(r[size_t(x) * size_t(channels_) + size_t(c)]));
      }
    }
    return peak;
  }
  FloatImage dense() const {
    FloatImage m(width_, height_, channels_);
    const size_t n = size_t(width_) * size_t(channels_);
    for (int y = 0; y < height_; ++y) {
      if (rows_[size_t(y)]) std::copy_n(rows_[size_t(y)].get(), n, m.data.begin() + long(n) * y);
    }
    return m;
  }

 private:
  int width_, height_, channels_;
  std::vector<std::unique_ptr<float[]>> rows_;
};

// One light group's maps: its own (B for the static group, C_l for light l) and, per candidate
// slot, what the object changes in it (S), and per pair of slots (a < b) the light both block,
// which S_a + S_b removes twice (P).
struct GroupMaps {
  FloatImage map;
  std::vector<SparseRows> shadow;
  std::map<std::pair<int, int>, FloatImage> pairs;
  double doubly_blocked = 0.0;  // energy (max channel, summed over texels) blocked by 2 objects
  double triply_blocked = 0.0;  // ... by 3 or more
};

// The pass over one group's rays. li < 0: the static group (every static light at its authored
// colour and intensity, and the emissive surfaces); otherwise light li at intensity 1, white.
// Each ray is traced once: shadow_query gives the static occlusion and the objects it crosses.
GroupMaps trace_group(const Baker& b, int li, const Indirect& ind, const Candidates& cand,
                      const ObjectChanges& changes, int channels, Progress& progress) {
  const Scene& scene = b.scene;
  const TexelSet& texels = b.texels;
  const Tracer& tracer = b.tracer;
  const int w = texels.width, h = texels.height;
  GroupMaps gm;
  gm.map = FloatImage(w, h, channels);
  gm.shadow.reserve(cand.sets.size());
  for (size_t j = 0; j < cand.sets.size(); ++j) gm.shadow.emplace_back(w, h, channels);
  // Pair terms only in a pass over single objects (a joint pass measures them exactly).
  const bool singles = cand.sets.empty() || cand.sets.front().size() == 1;
  std::mutex pair_mutex;
  const int max_objects = static_cast<int>(scene.objects.size());
  const size_t nc = cand.sets.size();
  parallel_for(h, b.threads, [&](int y) {
    std::vector<LightSample> samples;
    std::vector<int> hit(static_cast<size_t>(std::max(1, max_objects)));
    std::vector<int> slots;
    std::vector<glm::vec3> s_acc(nc);
    std::vector<uint8_t> blocked(nc, 0);
    std::vector<std::pair<std::pair<int, int>, glm::vec3>> p_acc;  // this texel's pair terms
    std::vector<std::pair<std::pair<int, int>, std::pair<int, glm::vec3>>> row_pairs;
    double doubly = 0.0, triply = 0.0;
    for (int x = 0; x < w; ++x) {
      const size_t t = texels.index(x, y);
      if (!texels.valid[t]) continue;
      glm::vec3 c_acc(0.0f);
      bool any = false;  // some shadow accumulator touched
      auto touch = [&] {
        if (!any) std::fill(s_acc.begin(), s_acc.end(), glm::vec3(0.0f));
        any = true;
      };
      p_acc.clear();
      // A segment carrying `e`: static occlusion, then the candidates it crosses.
      auto segment = [&](const glm::vec3& o, const glm::vec3& d, float tmin, float tmax,
                         const glm::vec3& e, bool mark) {
        const int n = nc == 0 ? (tracer.occluded_static(o, d, tmin, tmax) ? -1 : 0)
                              : tracer.shadow_query(o, d, tmin, tmax, hit.data(), max_objects);
        if (n < 0) return -1;
        c_acc += e;
        slots.clear();
        for (int j = 0; j < n; ++j) {
          for (int sl : cand.slots_of[size_t(hit[size_t(j)])]) slots.push_back(sl);
        }
        if (!singles) {  // a pair's slot is blocked once, by either object
          std::sort(slots.begin(), slots.end());
          slots.erase(std::unique(slots.begin(), slots.end()), slots.end());
        }
        for (int sl : slots) {
          touch();
          s_acc[size_t(sl)] += e;
          if (mark) blocked[size_t(sl)] = 1;
        }
        if (singles && slots.size() >= 2) {
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
        return n;
      };
      if (li < 0) {
        for (size_t l = 0; l < scene.lights.size(); ++l) {
          const Light& light = scene.lights[l];
          if (light.semi_dynamic) continue;
          samples.clear();
          b.light_samples(static_cast<int>(l), t, samples);
          const glm::vec3 radiant = light.color * light.intensity;
          for (const LightSample& s : samples)
            segment(s.origin, s.dir, s.tmin, s.tmax, radiant * s.irradiance.x, false);
        }
        samples.clear();
        b.emissive_samples(t, samples);
        for (const LightSample& s : samples)
          segment(s.origin, s.dir, s.tmin, s.tmax, s.irradiance, false);
      } else {
        samples.clear();
        b.light_samples(li, t, samples);
        for (const LightSample& s : samples)
          segment(s.origin, s.dir, s.tmin, s.tmax, glm::vec3(s.irradiance.x), false);
      }
      if (ind.enabled) {
        const PhotonGroup& g = *ind.photons;
        const glm::vec3 p = texels.position[t], nrm = texels.normal[t];
        for (size_t v = 0; v < g.lights().size(); ++v) {
          glm::vec3 o, d;
          float tmax = 0.0f;
          const float f =
              vpl_factor(g.lights()[v], p, nrm, b.settings.area_bias, b.eps, &o, &d, &tmax);
          if (!(f > 0.0f) || g.bound_power(v) * f < ind.cutoff) continue;
          // S = map − T: the object blocks the ray (T has none of it), or leaves it open and T
          // has this VPL at its changed power. Pair terms cover the rays both objects block.
          if (segment(o, d, b.eps, tmax, g.lights()[v].power * f, true) < 0) continue;
          for (const ObjectChanges::Delta& dl : changes.deltas[v]) {
            if (blocked[size_t(dl.slot)]) continue;
            touch();
            s_acc[size_t(dl.slot)] -= dl.power * f;
          }
          for (int sl : slots) blocked[size_t(sl)] = 0;
        }
        // The object's own bounce: in T only, so negative in S; the object itself can hide it.
        for (const ObjectChanges::ObjectLight& ol : changes.object_lights) {
          glm::vec3 o, d;
          float tmax = 0.0f;
          const float f = vpl_factor(ol.light, p, nrm, b.settings.area_bias, b.eps, &o, &d, &tmax);
          if (!(f > 0.0f) || ol.bound * f < ind.cutoff) continue;
          const int n = tracer.shadow_query(o, d, b.eps, tmax, hit.data(), max_objects);
          if (n < 0) continue;
          bool hidden = false;  // by an object of the slot's own set
          for (int m : cand.sets[size_t(ol.slot)])
            hidden |= std::find(hit.begin(), hit.begin() + n, m) != hit.begin() + n;
          if (hidden) continue;
          touch();
          s_acc[size_t(ol.slot)] -= ol.light.power * f;
        }
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

// Largest |value| of a map over valid texels.
float peak_of(const FloatImage& map, const TexelSet& texels) {
  float peak = 0.0f;
  const size_t ch = size_t(map.channels);
  for (size_t i = 0; i < map.data.size(); ++i) {
    if (texels.valid[i / ch]) peak = std::max(peak, std::fabs(map.data[i]));
  }
  return peak;
}

std::string keep_reason(float peak, float keep_at, const std::string& what) {
  if (peak > keep_at)
    return what + " peak " + std::to_string(peak) + " above half an output step (" +
           std::to_string(keep_at) + ")";
  if (peak > 0.0f)
    return what + " peak " + std::to_string(peak) + " below half an output step (" +
           std::to_string(keep_at) + ")";
  return "blocks none of the light's rays to any texel";
}

// Triple overlaps (three objects blocking one ray) are not corrected: the report says how much
// light they carry next to the pair overlaps that are.
void report_triples(Report& report, const std::string& group, const GroupMaps& gm) {
  if (gm.doubly_blocked <= 0.0 && gm.triply_blocked <= 0.0) return;
  const double share = gm.triply_blocked / (gm.doubly_blocked + gm.triply_blocked);
  report.add_decision("triple overlap corrections: " + group, false,
                      std::to_string(100.0 * share) +
                          "% of the light blocked by several objects is blocked by three or "
                          "more; only pairs are corrected");
  std::lock_guard<std::mutex> lock(report.mutex());
  nlohmann::json& o = report.root()["overlaps"][group];
  o["doubly_blocked"] = gm.doubly_blocked;
  o["triply_blocked"] = gm.triply_blocked;
}

// Seconds of one light group's whole pass (photons, bounce changes, pass, overlaps), for
// `cook --measure-plan`'s attribution of the time an indirect-light decision saved.
void group_time(Report& report, const std::string& group, double seconds) {
  std::lock_guard<std::mutex> lock(report.mutex());
  report.root()["bake"]["group_seconds"][group] = seconds;
}

}  // namespace

const char* quality_name(Quality q) {
  switch (q) {
    case Quality::kDraft:
      return "draft";
    case Quality::kPreview:
      return "preview";
    case Quality::kProduction:
      return "production";
  }
  return "preview";
}

IndirectPreset indirect_preset(const BakeOptions& options) {
  IndirectPreset p = preset_indirect(options.quality);
  if (options.photons > 0) p.photons = options.photons;
  if (options.virtual_lights > 0) p.virtual_lights = options.virtual_lights;
  if (options.area_bias >= 0.0f && std::isfinite(options.area_bias))
    p.area_bias = options.area_bias;
  return p;
}

Quality parse_quality(const std::string& name) {
  if (name == "draft") return Quality::kDraft;
  if (name == "preview") return Quality::kPreview;
  if (name == "production") return Quality::kProduction;
  throw CookError("unknown quality '" + name + "' (expected draft, preview or production)");
}

const char* integrator_name(Integrator i) {
  return i == Integrator::kPhotons ? "photons" : "gather";
}

Integrator parse_integrator(const std::string& name) {
  if (name == "gather") return Integrator::kGather;
  if (name == "photons") return Integrator::kPhotons;
  throw CookError("unknown integrator '" + name + "' (expected gather or photons)");
}

GatherPreset gather_preset(const BakeOptions& options) {
  GatherPreset p = preset_gather(options.quality);
  if (options.gather_rays > 0) p.rays = options.gather_rays;
  if (options.indirect_level > 0) p.level = options.indirect_level;
  if (options.denoise >= 0) p.denoise = options.denoise;
  return p;
}

BakedMaps bake_maps(const Scene& scene, const Layout& layout, const TexelSet& texels,
                    const Tracer& tracer, const BakeOptions& options, Progress& progress,
                    Report& report) {
  check_inputs(scene, texels);
  const auto t0 = std::chrono::steady_clock::now();
  const uint64_t rays0 = tracer.rays_traced();
  progress.begin("plan", 1);
  Baker b(scene, texels, tracer, options);
  const int w = texels.width, h = texels.height;
  BakedMaps maps;
  maps.output_step = b.output_step;

  // Effects planned and skipped.
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    const Light& l = scene.lights[i];
    const std::string what = "soft shadows: " + light_name(scene, static_cast<int>(i));
    if (l.radius > 0.0f && l.type == LightType::kDirectional) {
      report.add_decision(what, false, "directional light: a radius in metres has no angular size");
    } else if (l.radius > 0.0f) {
      report.add_decision(what, true,
                          "radius " + std::to_string(l.radius) + " m, " +
                              std::to_string(b.plans[i].samples) + " samples");
    } else {
      report.add_decision(what, false,
                          b.plan ? "no lightRadius: a point source gives hard shadows"
                                 : "no lightRadius: a point source has no size, nothing to force");
    }
  }
  report.add_decision("emissive area lights", !b.emissive.empty(),
                      b.emissive.empty()
                          ? "no emissive static surfaces"
                          : std::to_string(b.emissive.triangle_count()) + " emissive triangles, " +
                                std::to_string(b.area_samples) + " samples/texel");
  if (!b.indirect) {
    report.add_decision("indirect light", false, "turned off by the bake options");
  } else if (b.gathering()) {
    report.add_decision("indirect light", true,
                        "final gathering: " + std::to_string(b.gp.rays) +
                            " rays per coarse texel of " + std::to_string(b.gp.level) + " x " +
                            std::to_string(b.gp.level) + " texels, " +
                            std::to_string(b.gp.denoise) + " denoise passes");
  } else {
    report.add_decision("indirect light", true,
                        std::to_string(b.preset.photons) + " photons, " +
                            std::to_string(b.preset.virtual_lights) +
                            " virtual indirect lights for the scene (split by power), area bias " +
                            std::to_string(b.preset.area_bias));
  }

  // Pair pre-culling.
  std::vector<Bounds> bounds;
  for (const Object& o : scene.objects) bounds.push_back(object_bounds(scene, o));
  std::vector<int> semi;
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    if (scene.lights[i].semi_dynamic) semi.push_back(static_cast<int>(i));
  }
  progress.end();
  b.build_gather(layout, progress, report);
  // Each candidate slot's fine direct change, as a coarse radiance source.
  auto slot_source = [&](const auto& gm) {
    return [&](size_t j) {
      return coarse_source_of(*b.gather, texels, [&](size_t t) {
        const SparseRows& r = gm.shadow[j];
        return glm::vec3(r.at(t, 0), r.at(t, 1), r.at(t, 2));
      });
    };
  };

  // Base map and static shadows: the static lights' pass.
  nlohmann::json pairs = nlohmann::json::array();
  {
    const auto ts = std::chrono::steady_clock::now();
    // Objects the static light can touch: some static light reaches them, emissive surfaces
    // (sampled everywhere) or the static group's bounce.
    Indirect ind;
    if (b.photons()) {
      progress.begin("photons: static lights", 1);
      ind = b.make_indirect(-1, !scene.objects.empty());
      progress.end();
      if (ind.photons || !b.static_emitters.empty()) {
        report.add_decision("indirect light: static lights", ind.enabled, ind.reason);
      }
      add_indirect_report(report, "static", ind);
    }
    Candidates cand(scene.objects.size());
    std::vector<int> bounce_only;  // final gathering: may change the bounce light only
    for (size_t o = 0; o < scene.objects.size(); ++o) {
      bool reach = !b.plan || !b.emissive.empty() || (ind.enabled && !bounds[o].empty());
      for (size_t i = 0; i < scene.lights.size() && !reach; ++i) {
        reach = !scene.lights[i].semi_dynamic &&
                precull_pair(scene.lights[i], b.plans[i], bounds[o]).empty();
      }
      if (reach) {
        cand.add(int(o));
      } else if (b.gathering() && !bounds[o].empty()) {
        bounce_only.push_back(int(o));
      } else {
        report.add_decision("static shadow of object " + scene.objects[o].name, false,
                            "no static light, emissive surface or static bounce reaches it");
      }
    }
    const ObjectChanges changes = object_changes(b, scene, -1, ind, cand, progress, report);
    progress.begin("base map", static_cast<uint64_t>(h));
    GroupMaps gm = trace_group(b, -1, ind, cand, changes, 3, progress);
    report.stage_time("bake.base", progress.end());
    GatherGroup gg;
    if (b.gathering()) {
      gg = gather_group(b, "static lights", b.static_step, gm.map, cand, slot_source(gm),
                        bounce_only, progress, report);
      if (gg.enabled) add_bounce(b, gg.indirect, gm.map);
      report.stage_time("bake.base_bounce", seconds_since(ts));
    }
    report.stage_time("bake.base_with_photons", seconds_since(ts));
    maps.base = std::move(gm.map);
    for (size_t j = 0; j < cand.objects.size(); ++j) {
      FloatImage change = gm.shadow[j].dense();
      if (gg.enabled) add_bounce(b, std::move(gg.change[j]), change);
      const float peak = peak_of(change, texels);
      const float keep_at = kPairKeepFraction * b.static_step;
      const bool keep = !b.plan || peak > keep_at;
      report.add_decision("static shadow of object " + scene.objects[size_t(cand.objects[j])].name,
                          keep, b.plan ? keep_reason(peak, keep_at, "change") : kForced);
      if (keep) maps.static_shadows.push_back({cand.objects[j], std::move(change)});
    }
    for (size_t k = 0; k < bounce_only.size(); ++k) {
      const std::string what =
          "static shadow of object " + scene.objects[size_t(bounce_only[k])].name;
      if (gg.bounce_change.empty() || gg.bounce_change[k].empty()) {
        report.add_decision(
            what, false,
            "no static light or emissive surface reaches it; " +
                (gg.bounce_reason.empty() ? std::string("no bounce light") : gg.bounce_reason[k]));
        continue;
      }
      FloatImage change(w, h, 3);
      add_bounce(b, std::move(gg.bounce_change[k]), change);
      const float peak = peak_of(change, texels);
      const float keep_at = kPairKeepFraction * b.static_step;
      const bool keep = !b.plan || peak > keep_at;
      report.add_decision(what, keep,
                          b.plan ? keep_reason(peak, keep_at, "bounce change") : kForced);
      if (keep) maps.static_shadows.push_back({bounce_only[k], std::move(change)});
    }
    std::sort(
        maps.static_shadows.begin(), maps.static_shadows.end(),
        [](const StaticShadowMap& a, const StaticShadowMap& c) { return a.object < c.object; });
    // The pack has no static pair corrections: overlapping static shadows stay the paper's
    // approximation, reported with their size.
    for (auto& [key, img] : gm.pairs) {
      const float peak = peak_of(img, texels);
      if (peak <= kPairKeepFraction * b.static_step) continue;
      report.add_decision("static shadow overlap " +
                              scene.objects[size_t(cand.objects[size_t(key.first)])].name + " + " +
                              scene.objects[size_t(cand.objects[size_t(key.second)])].name,
                          false,
                          "peak " + std::to_string(peak) +
                              ": static lights have no pair corrections in pack format 1; "
                              "where both are visible their overlap is darkened twice");
    }
    report_triples(report, "static lights", gm);
    group_time(report, "static lights", seconds_since(ts));
  }

  // Contribution, shadow and pair-correction maps: one pass per semi-dynamic light.
  for (size_t k = 0; k < semi.size(); ++k) {
    const int li = semi[k];
    const Light& light = scene.lights[static_cast<size_t>(li)];
    const LightPlan& plan = b.plans[static_cast<size_t>(li)];
    const auto ts = std::chrono::steady_clock::now();
    Indirect ind;
    if (b.photons()) {
      progress.begin("photons: " + light_name(scene, li), 1);
      ind = b.make_indirect(li, true);
      progress.end();
      report.add_decision("indirect light: " + light_name(scene, li), ind.enabled, ind.reason);
      add_indirect_report(report, light.name, ind);
    }
    // Every object is a candidate while the light has indirect light (an object anywhere in the
    // room blocks some of its bounce); otherwise only those the direct light can reach.
    Candidates cand(scene.objects.size());
    std::vector<int> bounce_only;  // final gathering: may change the bounce light only
    std::vector<std::string> bounce_why;
    for (size_t o = 0; o < scene.objects.size(); ++o) {
      const std::string why = precull_pair(light, plan, bounds[o]);
      if (!b.plan || why.empty() || (ind.enabled && !bounds[o].empty())) {
        cand.add(int(o));
      } else if (b.gathering() && !bounds[o].empty()) {
        bounce_only.push_back(int(o));
        bounce_why.push_back(why);
      } else {
        pairs.push_back({{"light", light.name},
                         {"object", scene.objects[o].name},
                         {"kept", false},
                         {"stage", "geometric"},
                         {"reason", why}});
      }
    }
    const ObjectChanges changes = object_changes(b, scene, li, ind, cand, progress, report);
    const int channels = ind.enabled || b.gathering() ? 3 : 1;
    progress.begin("light " + light_name(scene, li), static_cast<uint64_t>(h));
    GroupMaps gm = trace_group(b, li, ind, cand, changes, channels, progress);
    report.stage_time("bake.contribution", progress.end());
    GatherGroup gg;
    if (b.gathering()) {
      gg = gather_group(b, light_name(scene, li), plan.threshold, gm.map, cand, slot_source(gm),
                        bounce_only, progress, report);
      if (gg.enabled) add_bounce(b, gg.indirect, gm.map);
      report.stage_time("bake.contribution_bounce", seconds_since(ts));
    }
    report.stage_time("bake.contribution_with_photons", seconds_since(ts));
    // Without bounce light the light's transport is grey: one channel.
    const bool grey = b.gathering() && !gg.enabled;
    maps.lights.push_back(li);
    maps.contribution.push_back(grey ? first_channel(gm.map) : std::move(gm.map));
    const float keep_at = kPairKeepFraction * plan.threshold;
    std::vector<uint8_t> shadow_kept(cand.objects.size(), 0);
    std::vector<const FloatImage*> shadow_map_of(scene.objects.size(), nullptr);
    const size_t first_shadow = maps.shadows.size();
    std::vector<FloatImage> dense(cand.objects.size());
    for (size_t j = 0; j < cand.objects.size(); ++j) {
      dense[j] = gm.shadow[j].dense();
      if (gg.enabled) add_bounce(b, gg.change[j], dense[j]);
      if (grey) dense[j] = first_channel(dense[j]);
      const float peak = peak_of(dense[j], texels);
      const Object& obj = scene.objects[static_cast<size_t>(cand.objects[j])];
      const bool keep = !b.plan || peak > keep_at;
      shadow_kept[j] = keep ? 1 : 0;
      pairs.push_back({{"light", light.name},
                       {"object", obj.name},
                       {"kept", keep},
                       {"stage", "traced"},
                       {"peak", peak},
                       {"reason", b.plan ? keep_reason(peak, keep_at, "shadow") : kForced}});
      if (keep) {
        ShadowMap sm;
        sm.light = static_cast<int>(k);
        sm.object = cand.objects[j];
        sm.map = std::move(dense[j]);
        maps.shadows.push_back(std::move(sm));
      }
    }
    for (size_t i = first_shadow; i < maps.shadows.size(); ++i)
      shadow_map_of[size_t(maps.shadows[i].object)] = &maps.shadows[i].map;
    // Where two objects block the same rays, S_a + S_b removes that light twice: the pair's
    // correction adds it back while both are visible (inclusion-exclusion, DESIGN.md). For direct
    // light the pass above measured it exactly; bounce makes the pair's joint change more than the
    // sum of its parts (one object hides the other's bounce), so with indirect light the kept
    // pairs get a joint pass and P_ab = S_a + S_b - S_ab.
    std::vector<PairCorrectionMap> kept_pairs;
    std::vector<std::pair<int, int>> kept_slots;
    for (auto& [key, img] : gm.pairs) {
      const int oa = cand.objects[size_t(key.first)], ob = cand.objects[size_t(key.second)];
      const float peak = peak_of(img, texels);
      const bool keep = (!b.plan || peak > keep_at) && shadow_kept[size_t(key.first)] &&
                        shadow_kept[size_t(key.second)];
      report.add_decision("overlap correction " + light_name(scene, li) + " / " +
                              scene.objects[size_t(oa)].name + " + " +
                              scene.objects[size_t(ob)].name,
                          keep, b.plan ? keep_reason(peak, keep_at, "overlap") : kForced);
      if (!keep) continue;
      PairCorrectionMap pc;
      pc.light = static_cast<int>(k);
      pc.object_a = std::min(oa, ob);
      pc.object_b = std::max(oa, ob);
      pc.map = grey ? first_channel(img) : std::move(img);
      kept_pairs.push_back(std::move(pc));
      kept_slots.push_back(key);
    }
    // Final gathering: the pair's joint change to the bounce light from the same rays, P_ab's
    // bounce part = change_a + change_b - change_ab (direct overlap measured above).
    if (gg.enabled && !kept_pairs.empty()) {
      progress.begin("overlaps " + light_name(scene, li), kept_pairs.size());
      parallel_for(int(kept_pairs.size()), b.threads, [&](int i) {
        PairCorrectionMap& pc = kept_pairs[size_t(i)];
        const auto [ja, jb] = kept_slots[size_t(i)];
        const SparseRows &ra = gm.shadow[size_t(ja)], &rb = gm.shadow[size_t(jb)];
        const CoarseMap joint_direct = coarse_source_of(*b.gather, texels, [&](size_t t) {
          const int x = int(t % size_t(w)), y = int(t / size_t(w));
          glm::vec3 v;
          for (int c = 0; c < 3; ++c) v[c] = ra.at(t, c) + rb.at(t, c) - pc.map.at(x, y, c);
          return v;
        });
        std::vector<uint8_t> present(scene.objects.size(), 0);
        present[size_t(pc.object_a)] = present[size_t(pc.object_b)] = 1;
        const CoarseMap joint = solve_change(*b.gather, present, gg.empty_total, joint_direct,
                                             solve_options(*b.gather, plan.threshold, 1));
        CoarseMap p(joint.size());
        for (size_t c = 0; c < p.size(); ++c)
          p[c] = gg.change[size_t(ja)][c] + gg.change[size_t(jb)][c] - joint[c];
        add_bounce(b, std::move(p), pc.map);
        progress.advance();
      });
      report.stage_time("bake.overlaps", progress.end());
    }
    if (ind.enabled && !kept_pairs.empty()) {
      Candidates joint(scene.objects.size());
      for (const PairCorrectionMap& pc : kept_pairs) joint.add({pc.object_a, pc.object_b});
      const ObjectChanges jc = object_changes(b, scene, li, ind, joint, progress, report);
      progress.begin("overlaps " + light_name(scene, li), static_cast<uint64_t>(h));
      GroupMaps jm = trace_group(b, li, ind, joint, jc, channels, progress);
      report.stage_time("bake.overlaps", progress.end());
      for (size_t j = 0; j < kept_pairs.size(); ++j) {
        const FloatImage& sa = *shadow_map_of[size_t(kept_pairs[j].object_a)];
        const FloatImage& sb = *shadow_map_of[size_t(kept_pairs[j].object_b)];
        FloatImage& p = kept_pairs[j].map;
        const int ch = p.channels;
        for (size_t i = 0; i < p.data.size(); ++i)
          p.data[i] =
              sa.data[i] + sb.data[i] - jm.shadow[j].at(i / size_t(ch), int(i % size_t(ch)));
      }
    }
    for (PairCorrectionMap& pc : kept_pairs) maps.pair_corrections.push_back(std::move(pc));
    // Objects that block none of the light's direct light, by their change to its bounce light.
    for (size_t q = 0; q < bounce_only.size(); ++q) {
      const Object& obj = scene.objects[size_t(bounce_only[q])];
      if (gg.bounce_change.empty() || gg.bounce_change[q].empty()) {
        pairs.push_back({{"light", light.name},
                         {"object", obj.name},
                         {"kept", false},
                         {"stage", "geometric"},
                         {"reason", bounce_why[q] + "; bounce: " +
                                        (gg.bounce_reason.empty() ? std::string("none")
                                                                  : gg.bounce_reason[q])}});
        continue;
      }
      FloatImage change(w, h, 3);
      add_bounce(b, std::move(gg.bounce_change[q]), change);
      const float peak = peak_of(change, texels);
      const bool keep = !b.plan || peak > keep_at;
      pairs.push_back({{"light", light.name},
                       {"object", obj.name},
                       {"kept", keep},
                       {"stage", "bounce"},
                       {"peak", peak},
                       {"reason", b.plan ? keep_reason(peak, keep_at, "bounce change") : kForced}});
      if (keep) maps.shadows.push_back({static_cast<int>(k), bounce_only[q], std::move(change)});
    }
    std::sort(maps.shadows.begin() + long(first_shadow), maps.shadows.end(),
              [](const ShadowMap& a, const ShadowMap& c) { return a.object < c.object; });
    report_triples(report, light_name(scene, li), gm);
    group_time(report, light_name(scene, li), seconds_since(ts));
  }
  for (const nlohmann::json& p : pairs) {
    report.add_decision(
        "pair " + p["light"].get<std::string>() + " / " + p["object"].get<std::string>(),
        p["kept"].get<bool>(), p["reason"].get<std::string>());
  }
  {
    std::lock_guard<std::mutex> lock(report.mutex());
    nlohmann::json& rp = report.root()["pairs"];
    if (!rp.is_array()) rp = nlohmann::json::array();
    int kept = 0;
    for (nlohmann::json& p : pairs) {
      kept += p["kept"].get<bool>() ? 1 : 0;
      rp.push_back(std::move(p));
    }
    report.root()["pairs_kept"] = kept;
    report.root()["pairs_skipped"] = static_cast<int>(rp.size()) - kept;
  }
  fill_report_bake(report, b, options.quality, seconds_since(t0), rays0);
  return maps;
}

FloatImage bake_state(const Scene& scene, const Layout& layout, const TexelSet& texels,
                      const Tracer& tracer, const StateSpec& state, const BakeOptions& options,
                      Progress& progress, Report& report) {
  check_inputs(scene, texels);
  // Resolve the state by name.
  std::vector<glm::vec3> radiant(scene.lights.size());  // colour * intensity, 0 when off
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    radiant[i] = scene.lights[i].color * scene.lights[i].intensity;
  }
  std::vector<std::string> unknown;
  for (const auto& [name, o] : state.lights) {
    size_t i = 0;
    while (i < scene.lights.size() && scene.lights[i].name != name) ++i;
    if (i == scene.lights.size()) {
      unknown.push_back("light '" + name + "'");
      continue;
    }
    const Light& l = scene.lights[i];
    if (!l.semi_dynamic) {
      throw CookError("state changes light '" + name +
                      "', which is static (only semi-dynamic lights can change)");
    }
    const glm::vec3 color = o.has_color ? glm::vec3(o.color[0], o.color[1], o.color[2]) : l.color;
    const float intensity = o.has_intensity ? o.intensity : l.intensity;
    radiant[i] = (o.has_on && !o.on) ? glm::vec3(0.0f) : color * intensity;
  }
  std::vector<uint8_t> visible(scene.objects.size(), 1);
  for (const auto& [name, vis] : state.objects) {
    size_t i = 0;
    while (i < scene.objects.size() && scene.objects[i].name != name) ++i;
    if (i == scene.objects.size()) {
      unknown.push_back("object '" + name + "'");
      continue;
    }
    visible[i] = vis ? 1 : 0;
  }
  if (!unknown.empty()) {
    std::string list;
    for (const std::string& u : unknown) list += (list.empty() ? "" : ", ") + u;
    throw CookError(
        "the state names what the scene does not have (or has not marked "
        "semiDynamic): " +
        list);
  }

  const auto t0 = std::chrono::steady_clock::now();
  const uint64_t rays0 = tracer.rays_traced();
  Baker b(scene, texels, tracer, options);
  const int w = texels.width, h = texels.height;
  FloatImage out(w, h, 3);
  const int max_objects = static_cast<int>(scene.objects.size());

  // Indirect light of every group that shines: the same photons and VPLs as bake_maps, the
  // state's visible objects present (their photon changes and their own VPLs).
  struct StateGroup {
    Indirect ind;
    glm::vec3 scale{1.0f};
    PhotonGroup::Change change;
  };
  std::vector<StateGroup> groups;
  if (b.photons()) {
    progress.begin("photons", 1);
    auto add_group = [&](int li, const glm::vec3& scale) {
      StateGroup g;
      g.ind = b.make_indirect(li, true);
      if (!g.ind.enabled) return;
      g.scale = scale;
      std::vector<uint8_t> present(scene.objects.size(), 0);
      bool any = false;
      for (size_t o = 0; o < scene.objects.size(); ++o) {
        present[o] = visible[o] && g.ind.relevant[o] ? 1 : 0;
        any |= present[o] != 0;
      }
      if (any) {
        g.change = g.ind.photons->change(present);
      } else {
        g.change.delta.assign(g.ind.photons->lights().size(), glm::vec3(0.0f));
      }
      groups.push_back(std::move(g));
    };
    if (!b.static_emitters.empty()) add_group(-1, glm::vec3(1.0f));
    for (size_t li = 0; li < scene.lights.size(); ++li) {
      if (scene.lights[li].semi_dynamic && max3(radiant[li]) > 0.0f)
        add_group(static_cast<int>(li), radiant[li]);
    }
    progress.end();
  }

  progress.begin("bake state", static_cast<uint64_t>(h));
  parallel_for(h, b.threads, [&](int y) {
    std::vector<LightSample> samples;
    std::vector<int> hit(static_cast<size_t>(std::max(1, max_objects)));
    auto visible_segment = [&](const glm::vec3& o, const glm::vec3& d, float tmin, float tmax) {
      const int n = tracer.shadow_query(o, d, tmin, tmax, hit.data(), max_objects);
      if (n < 0) return false;
      for (int j = 0; j < n; ++j) {
        if (visible[static_cast<size_t>(hit[static_cast<size_t>(j)])]) return false;
      }
      return true;
    };
    auto visible_through = [&](const LightSample& s) {
      return visible_segment(s.origin, s.dir, s.tmin, s.tmax);
    };
    for (int x = 0; x < w; ++x) {
      const size_t t = texels.index(x, y);
      if (!texels.valid[t]) continue;
      glm::vec3 e(0.0f);
      for (size_t li = 0; li < scene.lights.size(); ++li) {
        if (max3(radiant[li]) <= 0.0f) continue;
        samples.clear();
        b.light_samples(static_cast<int>(li), t, samples);
        float sum = 0.0f;
        for (const LightSample& s : samples) {
          if (visible_through(s)) sum += s.irradiance.x;
        }
        e += radiant[li] * sum;
      }
      samples.clear();
      b.emissive_samples(t, samples);
      for (const LightSample& s : samples) {
        if (visible_through(s)) e += s.irradiance;
      }
      const glm::vec3 p = texels.position[t], nrm = texels.normal[t];
      for (const StateGroup& g : groups) {
        const PhotonGroup& pg = *g.ind.photons;
        glm::vec3 sum(0.0f);
        for (size_t v = 0; v < pg.lights().size(); ++v) {
          glm::vec3 o, d;
          float tmax = 0.0f;
          const float f =
              vpl_factor(pg.lights()[v], p, nrm, b.settings.area_bias, b.eps, &o, &d, &tmax);
          if (!(f > 0.0f) || pg.bound_power(v) * f < g.ind.cutoff) continue;
          if (visible_segment(o, d, b.eps, tmax))
            sum += (pg.lights()[v].power + g.change.delta[v]) * f;
        }
        for (size_t i = 0; i < g.change.object_lights.size(); ++i) {
          glm::vec3 o, d;
          float tmax = 0.0f;
          const float f = vpl_factor(g.change.object_lights[i], p, nrm, b.settings.area_bias, b.eps,
                                     &o, &d, &tmax);
          if (!(f > 0.0f) || g.change.object_bound[i] * f < g.ind.cutoff) continue;
          if (visible_segment(o, d, b.eps, tmax)) sum += g.change.object_lights[i].power * f;
        }
        e += g.scale * sum;
      }
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = e[c];
    }
    progress.advance();
  });
  report.stage_time("bake.state", progress.end());
  if (b.gathering()) {
    // The state's bounce light in one solve: every group's direct light at its state's colour is
    // one source, the visible objects are present. The tolerance is the finest of the groups'
    // (each group's significance at its state's brightness), so the state is solved at least as
    // finely as the decomposition's maps.
    b.build_gather(layout, progress, report);
    progress.begin("bounce light", 1);
    float tolerance = b.static_step;
    for (size_t li = 0; li < scene.lights.size(); ++li) {
      if (scene.lights[li].semi_dynamic && max3(radiant[li]) > 0.0f)
        tolerance = std::min(tolerance, b.plans[li].threshold * max3(radiant[li]));
    }
    const CoarseMap source = coarse_source(*b.gather, texels, out);
    const CoarseMap bounce =
        solve_indirect(*b.gather, visible, source, solve_options(*b.gather, tolerance, b.threads));
    add_bounce(b, bounce, out);
    report.stage_time("bake.state_bounce", progress.end());
  }
  fill_report_bake(report, b, options.quality, seconds_since(t0), rays0);
  return out;
}

}  // namespace lightpatch::cooker
