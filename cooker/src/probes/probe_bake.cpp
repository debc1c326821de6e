// Lighting the probes per set from the finalized maps (probes.h). Per probe: `rays` directions of
// a Fibonacci lattice, each traced once to its static hit and once to the first semi-dynamic
// object before it, and each light's direct samples with the objects that block them. A set's
// radiance along a ray is the albedo / pi times the set's map at the texel the ray sees (plus
// the emission of an emissive surface, in the base); its SH projection times the cosine lobe's
// band factors is the set's irradiance SH. With one object present, a ray that meets it first
// sees the object's surface, lit by the maps as the state would draw them there; a ray that meets
// two objects is taken to meet the first only, and a direct sample blocked by two objects is
// taken away by each one's shadow set (the maps' pair corrections have no probe sets): the
// probes are exact for any one object at a time.
//
// Moving lights: their direct light at a probe is the game's, as on surfaces, so they have no
// direct samples. Each pane of theirs has a contribution set whose radiance along a ray that sees
// texel t is albedo / pi * ([t in the pane] + the pane's map at t): the pane's own irradiance 1,
// which the light map leaves to the game's direct light on the surface, is light the surface
// reflects, indirect light for the probe's object. Panes have no object sets: their maps ignore
// the objects too (a ray that meets an object sees the static texel behind it). An anchor's set
// (pack_format.h, "Anchors") takes the moving light standing at the anchor in place of the
// pane's irradiance 1: its irradiance at the texel's sample point (cosine over squared distance
// floored at the light's radius, range window), one shadow ray to the anchor, as the anchor's
// map draws it beyond its near field (the anchor's depth map instead: 17-19 % dark on the test
// scene's probes, its texels too coarse for surfaces seen obliquely).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>

#include "direct_light.h"
#include "indirect/gather.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/probes.h"
#include "lightpatch/moving_lights.h"
#include "lightpatch/spherical_harmonics.h"
#include "panes/anchors.h"
#include "panes/pane_cluster.h"
#include "probes/probe_rays.h"
#include "surface_albedo.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr int kMaxBlockers = 8;
constexpr int kSphereSamples = 16;  // direct samples of a light with a radius (4 x 4 strata)
using Sh = std::array<float, pack::kProbeShCount * 3>;

void add(Sh& sh, const float y[pack::kProbeShCount], const glm::vec3& l) {
  for (uint32_t k = 0; k < pack::kProbeShCount; ++k)
    for (int c = 0; c < 3; ++c) sh[k * 3 + c] += y[k] * l[c];
}

glm::vec3 value(const FloatImage& m, uint32_t texel) {
  if (texel == kNoTexel) return glm::vec3(0.0f);
  if (m.channels == 1) return glm::vec3(m.data[texel]);
  const float* v = &m.data[size_t(texel) * 3];
  return {v[0], v[1], v[2]};
}

// One gather ray of a probe: what it sees with the objects absent, and the first object before
// that, if any.
struct ProbeRay {
  float y[pack::kProbeShCount];  // Y_k(direction)
  uint32_t texel = kNoTexel;     // static hit's texel (kNoTexel: a miss, a back face, unmapped)
  glm::vec3 rho{0.0f};           // its albedo / pi
  glm::vec3 emission{0.0f};      // its radiance as an emitter
  int object = -1;               // the first semi-dynamic object before the static hit
  uint32_t object_texel = kNoTexel;
  glm::vec3 object_rho{0.0f};
};

// One direct sample of a light at a probe: its radiance SH weight (irradiance of a surface facing
// it, for the light at colour (1,1,1) and intensity 1) and the objects that block it.
struct DirectSample {
  int light = 0;  // Scene::lights index
  float y[pack::kProbeShCount];
  float weight = 0.0f;
  int blockers = 0;
  int blocker[kMaxBlockers];
};

class ProbeLighter {
 public:
  ProbeLighter(const Scene& scene, const Layout& layout, const TexelSet& texels,
               const Tracer& tracer, int rays, uint64_t seed)
      : scene_(scene),
        layout_(layout),
        texels_(texels),
        tracer_(tracer),
        rays_(rays),
        seed_(seed),
        surfaces_(texel_surfaces(texels)),
        eps_(tracer.epsilon()),
        extent_(2.0f * scene.scale()) {
    if (rays <= 0) throw CookError("light probes need at least one gather ray");
  }

  // A ray's share of the sphere: radiance sums times this are its SH projection.
  float ray_weight() const { return 4.0f * kPi / float(rays_); }

  // What probe `probe` at `p` sees: its gather rays and every light's direct samples.
  void observe(size_t probe, const glm::vec3& p, std::vector<ProbeRay>& rays,
               std::vector<DirectSample>& direct) const {
    trace(probe, p, rays);
    this->direct(p, direct);
  }

  void trace(size_t probe, const glm::vec3& p, std::vector<ProbeRay>& out) const {
    const float turn = 2.0f * kPi * hash_to_unit(sample_hash(seed_, probe, 0x70726F62u, 0));
    std::vector<Ray> batch(static_cast<size_t>(rays_));
    std::vector<Hit> hits(static_cast<size_t>(rays_));
    for (int r = 0; r < rays_; ++r)
      batch[size_t(r)] = {p, eps_, sphere_direction(r, rays_, turn),
                          std::numeric_limits<float>::max()};
    tracer_.intersect_many(batch.data(), rays_, hits.data(), false);
    out.assign(size_t(rays_), ProbeRay());
    for (int r = 0; r < rays_; ++r) {
      ProbeRay& pr = out[size_t(r)];
      const glm::vec3 dir = batch[size_t(r)].dir;
      sh_basis(dir.x, dir.y, dir.z, pr.y);
      const Hit& h = hits[size_t(r)];
      surface(h, p, dir, &pr.texel, &pr.rho);
      if (!h.hit) continue;
      if (glm::dot(dir, h.geometric_normal) < 0.0f)
        pr.emission = scene_.materials[size_t(scene_.meshes[size_t(h.mesh)].material)].emissive;
      batch[size_t(r)].tmax = h.t;  // objects beyond the static hit hide nothing
    }
    if (scene_.objects.empty()) return;
    tracer_.intersect_many(batch.data(), rays_, hits.data(), true);
    for (int r = 0; r < rays_; ++r) {
      const Hit& h = hits[size_t(r)];
      if (!h.hit) continue;
      const int object = scene_.meshes[size_t(h.mesh)].object;
      if (object < 0) continue;
      ProbeRay& pr = out[size_t(r)];
      pr.object = object;
      surface(h, p, batch[size_t(r)].dir, &pr.object_texel, &pr.object_rho);
    }
  }

  void direct(const glm::vec3& p, std::vector<DirectSample>& out) const {
    out.clear();
    for (size_t li = 0; li < scene_.lights.size(); ++li) {
      const Light& light = scene_.lights[li];
      if (light.moving) continue;  // the game's, at its pose (and no set holds it)
      if (light.type == LightType::kDirectional) {
        sample(int(li), p, -light.direction, extent_, 1.0f, out);
        continue;
      }
      const glm::vec3 to = light.position - p;
      const float d = glm::length(to);
      if (!(d > 2.0f * eps_)) continue;
      const glm::vec3 w = to / d;
      SphereView view;
      if (light.radius <= 0.0f || !view_sphere_light(light, p, &view) || view.cos_max <= -1.0f) {
        // A point light (or a probe inside a sized light's sphere: taken at its centre).
        const float e = punctual_irradiance(light, light.position, p, w, eps_ * eps_);
        if (e > 0.0f)
          sample(int(li), p, w, std::max(eps_, d - std::max(eps_, light.radius)), e, out);
        continue;
      }
      const uint64_t rng = sample_hash(seed_, uint64_t(li), 0x6C697465u, 0);
      for (int i = 0; i < kSphereSamples; ++i) {
        const float u = (float(i % 4) + hash_to_unit(sample_hash(rng, uint64_t(i), 1, 0))) / 4.0f;
        const float v = (float(i / 4) + hash_to_unit(sample_hash(rng, uint64_t(i), 2, 0))) / 4.0f;
        float t_surface = 0.0f;
        const glm::vec3 s = sample_sphere_view(view, view.axis, u, v, &t_surface);
        sample(int(li), p, s, std::max(eps_, t_surface - eps_),
               view.radiance * view.solid_angle() / float(kSphereSamples), out);
      }
    }
  }

 private:
  // The texel and albedo / pi a ray sees at hit `h` (nothing on a miss or a back face).
  void surface(const Hit& h, const glm::vec3& p, const glm::vec3& dir, uint32_t* texel,
               glm::vec3* rho) const {
    if (!h.hit || glm::dot(dir, h.geometric_normal) >= 0.0f) return;
    const glm::vec3 point = p + dir * h.t;
    *texel = texel_of_hit(texels_, surfaces_, h, point, texel_under(layout_, texels_, h));
    if (*texel != kNoTexel) *rho = surface_albedo(scene_, h) / kPi;
  }

  void sample(int light, const glm::vec3& p, const glm::vec3& dir, float tmax, float weight,
              std::vector<DirectSample>& out) const {
    if (!(weight > 0.0f) || !std::isfinite(weight)) return;
    DirectSample s;
    s.light = light;
    s.weight = weight;
    s.blockers = tracer_.shadow_query(p, dir, eps_, tmax, s.blocker, kMaxBlockers);
    if (s.blockers < 0) return;  // static geometry blocks it in every state
    sh_basis(dir.x, dir.y, dir.z, s.y);
    out.push_back(s);
  }

  const Scene& scene_;
  const Layout& layout_;
  const TexelSet& texels_;
  const Tracer& tracer_;
  int rays_;
  uint64_t seed_;
  std::vector<TexelSurface> surfaces_;
  float eps_, extent_;
};

// Radiance SH (ray sums times 4 pi / rays, direct weights as they are) to irradiance SH.
void to_irradiance(Sh& sh) {
  for (uint32_t k = 0; k < pack::kProbeShCount; ++k)
    for (int c = 0; c < 3; ++c) sh[k * 3 + c] *= kShCosineBand[sh_band(k)];
}

using SetKey = std::tuple<uint16_t, int, int>;  // kind, light (pack index), object

}  // namespace

void bake_probes(ProbeBake& probes, const Scene& scene, const Layout& layout,
                 const TexelSet& texels, const Tracer& tracer, const BakedMaps& maps,
                 const ProbeOptions& options, Progress& progress, Report& report) {
  if (probes.empty()) return;
  const ProbeLighter lighter(scene, layout, texels, tracer, options.rays, options.seed);
  const float ray_weight = lighter.ray_weight();
  const size_t objects = scene.objects.size();
  std::vector<int> pack_light(scene.lights.size(), -1);
  for (size_t i = 0; i < maps.lights.size(); ++i) pack_light[size_t(maps.lights[i])] = int(i);
  // The maps of the object sets: S_ol by (pack light, object), the static shadows by object.
  std::vector<const FloatImage*> shadow(maps.lights.size() * objects, nullptr);
  for (const ShadowMap& s : maps.shadows)
    shadow[size_t(s.light) * objects + size_t(s.object)] = &s.map;
  std::vector<const FloatImage*> static_shadow(objects, nullptr);
  for (const StaticShadowMap& s : maps.static_shadows) static_shadow[size_t(s.object)] = &s.map;
  // The panes are pack lights after the semi-dynamic and the moving lights (pack_builder.cpp);
  // each texel is a member of one pane at most (cluster_panes partitions them).
  const size_t panes = maps.panes.size();
  const int first_pane = int(maps.lights.size() + maps.moving_lights.size());
  const std::vector<int32_t> pane_of = pane_of_texels(maps.panes, texels.valid.size());
  // Anchors: the moving light they are baked for (panes.cpp checks that all share its range and
  // radius).
  const Light* anchor_light =
      maps.moving_lights.empty() ? nullptr : &scene.lights[size_t(maps.moving_lights.front())];

  std::vector<std::vector<std::pair<SetKey, Sh>>> per_probe(probes.probes.size());
  progress.begin("light probes", probes.probes.size());
  parallel_for(int(probes.probes.size()), worker_count(options.threads), [&](int pi) {
    set_worker_fp_mode();
    const glm::vec3 p = probes.probes[size_t(pi)].position;
    std::vector<ProbeRay> ray;
    std::vector<DirectSample> direct;
    lighter.observe(size_t(pi), p, ray, direct);
    std::map<SetKey, Sh> sets;
    auto set = [&](uint16_t kind, int light, int object) -> Sh& {
      auto [it, fresh] = sets.try_emplace(SetKey{kind, light, object});
      if (fresh) it->second.fill(0.0f);
      return it->second;
    };
    std::vector<uint8_t> seen(objects, 0);  // objects some ray meets first
    for (const ProbeRay& r : ray)
      if (r.object >= 0) seen[size_t(r.object)] = 1;
    // An object's set: what the state with that object present takes away from `m`'s radiance
    // (the rays that meet it see its surface lit by m - s instead; the others see m - s; s: the
    // object's map of m's light, or none).
    auto object_rays = [&](Sh& sh, const FloatImage& m, const FloatImage* s, int object,
                           bool emission) {
      for (const ProbeRay& r : ray) {
        glm::vec3 l(0.0f);
        if (r.object == object) {
          l = r.rho * value(m, r.texel) + (emission ? r.emission : glm::vec3(0.0f)) -
              r.object_rho *
                  (value(m, r.object_texel) - (s ? value(*s, r.object_texel) : glm::vec3(0.0f)));
        } else if (s) {
          l = r.rho * value(*s, r.texel);
        }
        add(sh, r.y, l * ray_weight);
      }
    };
    {  // Base: static lights and emitters with every object absent.
      Sh& base = set(pack::kGroupBase, -1, -1);
      for (const ProbeRay& r : ray)
        add(base, r.y, (r.rho * value(maps.base, r.texel) + r.emission) * ray_weight);
      for (const DirectSample& s : direct) {
        const Light& light = scene.lights[size_t(s.light)];
        if (light.semi_dynamic) continue;
        const glm::vec3 e = light.color * light.intensity * s.weight;
        add(base, s.y, e);
        for (int b = 0; b < s.blockers; ++b)
          add(set(pack::kGroupStaticShadow, -1, s.blocker[b]), s.y, e);
      }
      for (size_t o = 0; o < objects; ++o)
        if (seen[o] || static_shadow[o])
          object_rays(set(pack::kGroupStaticShadow, -1, int(o)), maps.base, static_shadow[o],
                      int(o), true);
    }
    for (size_t l = 0; l < maps.lights.size(); ++l) {
      const FloatImage& c = maps.contribution[l];
      Sh& contribution = set(pack::kGroupContribution, int(l), -1);
      for (const ProbeRay& r : ray) add(contribution, r.y, r.rho * value(c, r.texel) * ray_weight);
      for (const DirectSample& s : direct) {
        if (pack_light[size_t(s.light)] != int(l)) continue;
        add(contribution, s.y, glm::vec3(s.weight));
        for (int b = 0; b < s.blockers; ++b)
          add(set(pack::kGroupShadow, int(l), s.blocker[b]), s.y, glm::vec3(s.weight));
      }
      for (size_t o = 0; o < objects; ++o) {
        const FloatImage* s = shadow[l * objects + o];
        if (seen[o] || s) object_rays(set(pack::kGroupShadow, int(l), int(o)), c, s, int(o), false);
      }
    }
    if (panes > 0) {
      // Pane k's set: its members' irradiance 1 and its map, both reflected. Pane by pane over
      // the rays that see a texel, so that one map is read at a time.
      std::vector<Sh> pane(panes);
      for (Sh& sh : pane) sh.fill(0.0f);
      std::vector<const ProbeRay*> seeing;
      for (const ProbeRay& r : ray) {
        if (r.texel == kNoTexel) continue;
        seeing.push_back(&r);
        if (pane_of[r.texel] >= 0) add(pane[size_t(pane_of[r.texel])], r.y, r.rho * ray_weight);
      }
      for (size_t k = 0; k < panes; ++k) {
        const PaneMap& pm = maps.panes[k];
        const bool anchor = is_anchor(pm.record);
        const glm::vec3 eye(pm.record.eye[0], pm.record.eye[1], pm.record.eye[2]);
        for (const ProbeRay* r : seeing) {
          float b[3];
          pane_bounce_at(pm, uint32_t(texels.width), r->texel, b);
          glm::vec3 v(b[0], b[1], b[2]);
          if (anchor)
            v += glm::vec3(anchor_irradiance(scene, tracer, *anchor_light, eye,
                                             texels.position[r->texel], texels.normal[r->texel]));
          if (v != glm::vec3(0.0f)) add(pane[k], r->y, r->rho * v * ray_weight);
        }
        if (std::any_of(pane[k].begin(), pane[k].end(), [](float v) { return v != 0.0f; }))
          set(pack::kGroupContribution, first_pane + int(k), -1) = pane[k];
      }
    }
    auto& out = per_probe[size_t(pi)];
    for (auto& [key, sh] : sets) {
      if (std::all_of(sh.begin(), sh.end(), [](float v) { return v == 0.0f; })) continue;
      to_irradiance(sh);
      out.emplace_back(key, sh);
    }
    progress.advance();
  });
  std::map<SetKey, ProbeBake::Set> sets;
  size_t entries = 0;
  for (size_t pi = 0; pi < per_probe.size(); ++pi) {
    for (const auto& [key, sh] : per_probe[pi]) {
      ProbeBake::Set& s = sets[key];
      s.kind = std::get<0>(key);
      s.light = std::get<1>(key);
      s.object = std::get<2>(key);
      pack::ProbeEntry e{};
      e.probe = uint32_t(pi);
      std::copy(sh.begin(), sh.end(), e.sh);
      s.entries.push_back(e);
      ++entries;
    }
  }
  probes.sets.clear();
  for (auto& [key, s] : sets) probes.sets.push_back(std::move(s));
  const double seconds = progress.end();
  report.stage_time("probes", seconds);
  std::lock_guard<std::mutex> lock(report.mutex());
  nlohmann::json& r = report.root()["probes"];
  r["rays_per_probe"] = options.rays;
  r["sets"] = probes.sets.size();
  r["entries"] = entries;
}

std::vector<std::array<float, pack::kProbeShCount * 3>> bake_state_probes(
    const ProbeBake& probes, const Scene& scene, const Layout& layout, const TexelSet& texels,
    const Tracer& tracer, const FloatImage& state_map, const StateSpec& state,
    const ProbeOptions& options) {
  const ResolvedState resolved = resolve_state(scene, state);
  const ProbeLighter lighter(scene, layout, texels, tracer, options.rays, options.seed);
  const float ray_weight = lighter.ray_weight();
  std::vector<Sh> out(probes.probes.size());
  parallel_for(int(probes.probes.size()), worker_count(options.threads), [&](int pi) {
    set_worker_fp_mode();
    const glm::vec3 p = probes.probes[size_t(pi)].position;
    std::vector<ProbeRay> ray;
    std::vector<DirectSample> direct;
    lighter.observe(size_t(pi), p, ray, direct);
    Sh& sh = out[size_t(pi)];
    sh.fill(0.0f);
    for (const ProbeRay& r : ray) {
      const glm::vec3 l = r.object >= 0 && resolved.visible[size_t(r.object)]
                              ? r.object_rho * value(state_map, r.object_texel)
                              : r.rho * value(state_map, r.texel) + r.emission;
      add(sh, r.y, l * ray_weight);
    }
    for (const DirectSample& s : direct) {
      bool blocked = false;
      for (int b = 0; b < s.blockers; ++b)
        blocked = blocked || resolved.visible[size_t(s.blocker[b])];
      if (!blocked) add(sh, s.y, resolved.radiant[size_t(s.light)] * s.weight);
    }
    to_irradiance(sh);
  });
  return out;
}

}  // namespace lightpatch::cooker
