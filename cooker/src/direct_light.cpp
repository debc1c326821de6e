#include "direct_light.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lightpatch::cooker {

namespace {

constexpr float kPi = 3.14159265358979f;

uint64_t splitmix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Orthonormal basis around unit w (Duff et al. 2017).
void basis(const glm::vec3& w, glm::vec3& t, glm::vec3& b) {
  const float sign = std::copysign(1.0f, w.z);
  const float a = -1.0f / (sign + w.z);
  const float c = w.x * w.y * a;
  t = glm::vec3(1.0f + sign * w.x * w.x * a, sign * c, -sign * w.x);
  b = glm::vec3(c, sign + w.y * w.y * a, -w.y);
}

}  // namespace

uint64_t sample_hash(uint64_t seed, uint64_t texel, uint64_t light, uint64_t sample) {
  return splitmix(splitmix(splitmix(splitmix(seed) ^ texel) ^ light) ^ sample);
}

float hash_to_unit(uint64_t h) {
  return static_cast<float>(h >> 40) * (1.0f / 16777216.0f);
}

float spot_attenuation(const Light& light, const glm::vec3& to_point_unit) {
  const float cos_outer = std::cos(light.outer_cone);
  const float cos_inner = std::cos(light.inner_cone);
  const float scale = 1.0f / std::max(0.001f, cos_inner - cos_outer);
  const float offset = -cos_outer * scale;
  const float cd = glm::dot(light.direction, to_point_unit);
  const float a = std::clamp(cd * scale + offset, 0.0f, 1.0f);
  return a * a;
}

float range_window(float range, float d) {
  if (!(range > 0.0f)) return 1.0f;
  const float x = d / range;
  const float x2 = x * x;
  return std::clamp(1.0f - x2 * x2, 0.0f, 1.0f);
}

namespace {

// The spot cone's scale and offset (KHR_lights_punctual), computed once per texel, not per sample.
struct Cone {
  float scale = 0.0f, offset = 0.0f;
  explicit Cone(const Light& light) {
    if (light.type != LightType::kSpot) return;
    const float cos_outer = std::cos(light.outer_cone);
    scale = 1.0f / std::max(0.001f, std::cos(light.inner_cone) - cos_outer);
    offset = -cos_outer * scale;
  }
};

float irradiance_with_cone(const Light& light, const Cone& cone, const glm::vec3& light_pos,
                           const glm::vec3& p, const glm::vec3& n, float eps2) {
  if (light.type == LightType::kDirectional) {
    return std::max(0.0f, glm::dot(n, -light.direction));
  }
  const glm::vec3 to_light = light_pos - p;
  const float d2 = glm::dot(to_light, to_light);
  const float d = std::sqrt(d2);
  if (!(d > 0.0f)) return 0.0f;
  const glm::vec3 l = to_light / d;
  const float cos_theta = glm::dot(n, l);
  if (cos_theta <= 0.0f) return 0.0f;
  float e = cos_theta / (d2 + eps2) * range_window(light.range, d);
  if (light.type == LightType::kSpot) {
    const float a =
        std::clamp(glm::dot(light.direction, -l) * cone.scale + cone.offset, 0.0f, 1.0f);
    e *= a * a;
  }
  return e;
}

}  // namespace

float punctual_irradiance(const Light& light, const glm::vec3& light_pos, const glm::vec3& p,
                          const glm::vec3& n, float eps2) {
  if (light.type == LightType::kDirectional) {
    return std::max(0.0f, glm::dot(n, -light.direction));
  }
  const glm::vec3 to_light = light_pos - p;
  const float d2 = glm::dot(to_light, to_light);
  const float d = std::sqrt(d2);
  if (!(d > 0.0f)) return 0.0f;
  const glm::vec3 l = to_light / d;
  const float cos_theta = glm::dot(n, l);
  if (cos_theta <= 0.0f) return 0.0f;
  float e = cos_theta / (d2 + eps2) * range_window(light.range, d);
  if (light.type == LightType::kSpot) e *= spot_attenuation(light, -l);
  return e;
}

float light_reach(const Light& light, float cutoff) {
  if (light.type == LightType::kDirectional || !(cutoff > 0.0f)) {
    return std::numeric_limits<float>::infinity();
  }
  float reach = 1.0f / std::sqrt(cutoff);  // cos <= 1, window <= 1, cone <= 1
  if (light.range > 0.0f) reach = std::min(reach, light.range);
  return reach + light.radius;
}

bool view_sphere_light(const Light& light, const glm::vec3& p, SphereView* view) {
  const float r = light.radius;
  if (light.type == LightType::kDirectional || !(r > 0.0f)) return false;
  const glm::vec3 to_centre = light.position - p;
  const float d = glm::length(to_centre);
  SphereView v;
  v.radius = r;
  v.distance = d;
  // Spot and range act on the direction and distance from the centre to the receiver (at the
  // centre itself the light's own direction).
  const glm::vec3 from_centre = d > 0.0f ? -to_centre / d : light.direction;
  float scale = range_window(light.range, d);
  if (light.type == LightType::kSpot) scale *= spot_attenuation(light, from_centre);
  v.radiance = scale / (kPi * r * r);
  if (!(v.radiance > 0.0f) || !std::isfinite(v.radiance)) return false;
  if (d > r) {
    v.axis = to_centre / d;
    const float s2 = (r / d) * (r / d);  // sin^2 of the cone's half angle
    v.cos_max = std::sqrt(std::max(0.0f, 1.0f - s2));
    v.one_minus_cos = s2 / (1.0f + v.cos_max);
  } else {
    v.axis = d > 0.0f ? to_centre / d : glm::vec3(0.0f, 0.0f, 1.0f);
    v.cos_max = -1.0f;  // inside: the sphere fills every direction
    v.one_minus_cos = 2.0f;
  }
  *view = v;
  return true;
}

glm::vec3 sample_sphere_view(const SphereView& view, float u, float v, float* t_surface) {
  // cos = 1 - u (1 - cos_max); sin^2 = (1 - cos)(1 + cos) keeps small cones exact.
  const float a = u * view.one_minus_cos;
  const float c = 1.0f - a;
  const float s = std::sqrt(std::max(0.0f, a * (2.0f - a)));
  const float phi = 2.0f * kPi * v;
  glm::vec3 t, b;
  basis(view.axis, t, b);
  const glm::vec3 dir =
      glm::normalize(t * (s * std::cos(phi)) + b * (s * std::sin(phi)) + view.axis * c);
  // Along dir the centre is at projection d c and off-axis distance d s.
  const float d = view.distance, r = view.radius;
  const float h2 = std::max(0.0f, r * r - d * d * s * s);
  const float near = d * c - std::sqrt(h2);
  *t_surface = near > 0.0f ? near : d * c + std::sqrt(h2);  // inside: the far side
  return dir;
}

float sphere_hit_distance(const glm::vec3& p, const glm::vec3& dir, const glm::vec3& centre,
                          float radius) {
  const glm::vec3 oc = centre - p;
  const float tc = glm::dot(oc, dir);
  const float q2 = glm::dot(oc, oc) - tc * tc;  // squared distance of the centre from the ray
  const float h2 = radius * radius - q2;
  if (!(h2 >= 0.0f)) return -1.0f;
  const float h = std::sqrt(h2);
  if (tc - h > 0.0f) return tc - h;
  if (tc + h > 0.0f) return tc + h;
  return -1.0f;
}

float sphere_cosine_integral(float cos_theta, float sin2_sigma) {
  const float s2 = std::clamp(sin2_sigma, 0.0f, 1.0f);
  const float c = std::clamp(cos_theta, -1.0f, 1.0f);
  if (c * c >= s2) return c > 0.0f ? kPi * s2 * c : 0.0f;  // wholly above or below the horizon
  const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - c * c));
  const float x = std::sqrt(std::max(0.0f, 1.0f / s2 - 1.0f));  // cot sigma
  const float y = std::clamp(-x * c / sin_theta, -1.0f, 1.0f);
  const float sy = sin_theta * std::sqrt(std::max(0.0f, 1.0f - y * y));
  const float e = (c * std::acos(y) - x * sy) * s2 + std::atan2(sy, x);
  return std::max(0.0f, e);
}

bool sample_punctual(const Light& light, const glm::vec3& p, const glm::vec3& n, int samples,
                     uint64_t rng, float eps, float extent, float cutoff,
                     std::vector<LightSample>& out) {
  const glm::vec3 origin = p + n * eps;
  const float eps2 = eps * eps;
  if (light.type == LightType::kDirectional) {
    const glm::vec3 dir = -light.direction;
    const float e = std::max(0.0f, glm::dot(n, dir));
    if (e <= 0.0f || e < cutoff) return false;
    out.push_back({origin, dir, eps, extent, glm::vec3(e)});
    return true;
  }
  const glm::vec3 to_light = light.position - p;
  const float d = glm::length(to_light);
  const float r = std::max(0.0f, light.radius);
  // Early outs before any ray: whole light behind the surface, beyond range, too dim even at
  // its nearest point.
  if (glm::dot(to_light, n) <= -r) return false;
  const float nearest = std::max(d - r, 0.0f);
  if (light.range > 0.0f && nearest >= light.range) return false;
  const float bound = range_window(light.range, nearest) / (nearest * nearest + eps2);
  if (bound < cutoff) return false;
  const Cone cone(light);
  if (r <= 0.0f) {
    const float e = irradiance_with_cone(light, cone, light.position, p, n, eps2);
    if (e <= 0.0f || e < cutoff) return false;
    const glm::vec3 to_l = light.position - origin;
    const float dl = glm::length(to_l);
    if (!(dl > 2.0f * eps)) return false;  // the light sits on the surface: no ray can reach it
    out.push_back({origin, to_l / dl, eps, dl - eps, glm::vec3(e)});
    return true;
  }
  SphereView view;
  if (!view_sphere_light(light, p, &view)) return false;
  if (samples <= 1) {
    // The exact unshadowed irradiance, its visibility from one ray towards the centre.
    const float cos_theta = d > 0.0f ? glm::dot(n, to_light / d) : 1.0f;
    const float s2 = d > r ? (r / d) * (r / d) : 1.0f;
    const float e =
        d > r ? view.radiance * sphere_cosine_integral(cos_theta, s2) : view.radiance * kPi;
    if (e <= 0.0f || e < cutoff) return false;
    const glm::vec3 to_l = light.position - origin;
    const float dl = glm::length(to_l);
    // Inside the sphere nothing stands between the receiver and the light.
    const float reach = std::max(eps, dl - r);
    out.push_back({origin, dl > 0.0f ? to_l / dl : n, eps, reach, glm::vec3(e)});
    return true;
  }
  // The visible cone, stratified g x g (cos by u, angle by v) and jittered per texel; each sample
  // brings L cos(n, w) Omega / count.
  const int g = std::max(1, static_cast<int>(std::sqrt(static_cast<float>(samples))));
  const int count = g * g;
  const float per_sample = view.radiance * view.solid_angle() / static_cast<float>(count);
  const size_t first = out.size();
  float total = 0.0f;
  for (int i = 0; i < count; ++i) {
    const uint64_t h = sample_hash(rng, 0, 0, static_cast<uint64_t>(i));
    const float u = (static_cast<float>(i % g) + hash_to_unit(h)) / static_cast<float>(g);
    const float v = (static_cast<float>(i / g) + hash_to_unit(splitmix(h))) / static_cast<float>(g);
    float t_surface = 0.0f;
    const glm::vec3 w = sample_sphere_view(view, u, v, &t_surface);
    const float e = per_sample * glm::dot(n, w);
    if (!(e > 0.0f)) continue;
    const glm::vec3 to_s = p + w * t_surface - origin;
    const float ds = glm::length(to_s);
    // A surface point inside the sphere has nothing to trace.
    out.push_back({origin, ds > 0.0f ? to_s / ds : w, eps, std::max(eps, ds - eps), glm::vec3(e)});
    total += e;
  }
  if (total <= 0.0f || total < cutoff) {
    out.resize(first);
    return false;
  }
  return true;
}

EmissiveLights::EmissiveLights(const Scene& scene) {
  double total = 0.0;
  std::vector<double> power;
  mesh_first_.assign(scene.meshes.size(), -1);
  for (size_t mi = 0; mi < scene.meshes.size(); ++mi) {
    const MeshInstance& mesh = scene.meshes[mi];
    if (mesh.object >= 0) continue;  // semi-dynamic emitters are not baked as lights
    if (mesh.material < 0 || static_cast<size_t>(mesh.material) >= scene.materials.size()) continue;
    const glm::vec3 L = scene.materials[static_cast<size_t>(mesh.material)].emissive;
    const float peak = std::max({L.x, L.y, L.z});
    if (!(peak > 0.0f) || !std::isfinite(peak)) continue;
    mesh_first_[mi] = static_cast<int32_t>(tri_of_.size());
    tri_of_.resize(tri_of_.size() + mesh.indices.size() / 3, -1);
    for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
      const uint32_t a = mesh.indices[i], bb = mesh.indices[i + 1], c = mesh.indices[i + 2];
      Tri tri;
      tri.p0 = mesh.positions[a];
      tri.e1 = mesh.positions[bb] - tri.p0;
      tri.e2 = mesh.positions[c] - tri.p0;
      const glm::vec3 cr = glm::cross(tri.e1, tri.e2);
      const float len = glm::length(cr);
      if (!(len > 0.0f)) continue;
      tri.area = 0.5f * len;
      tri.normal = cr / len;
      // Emit from the side the shading normals face.
      if (!mesh.normals.empty()) {
        const glm::vec3 sn = mesh.normals[a] + mesh.normals[bb] + mesh.normals[c];
        if (glm::dot(sn, tri.normal) < 0.0f) tri.normal = -tri.normal;
      }
      tri.radiance = L;
      tri_of_[static_cast<size_t>(mesh_first_[mi]) + i / 3] = static_cast<int32_t>(tris_.size());
      tris_.push_back(tri);
      total += static_cast<double>(peak) * tri.area;
      power.push_back(total);
    }
  }
  cdf_.resize(power.size());
  for (size_t i = 0; i < power.size(); ++i) cdf_[i] = static_cast<float>(power[i] / total);
  if (!cdf_.empty()) cdf_.back() = 1.0f;
}

void EmissiveLights::sample(const glm::vec3& p, const glm::vec3& n, int samples, uint64_t rng,
                            float eps, std::vector<LightSample>& out) const {
  if (tris_.empty() || samples <= 0) return;
  const glm::vec3 origin = p + n * eps;
  const float inv_n = 1.0f / static_cast<float>(samples);
  for (int i = 0; i < samples; ++i) {
    const uint64_t h = sample_hash(rng, 1, 0, static_cast<uint64_t>(i));
    const float u = (static_cast<float>(i) + hash_to_unit(h)) * inv_n;  // stratified in power
    const size_t k =
        std::min(cdf_.size() - 1,
                 static_cast<size_t>(std::upper_bound(cdf_.begin(), cdf_.end(), u) - cdf_.begin()));
    const Tri& tri = tris_[k];
    const float p_tri = cdf_[k] - (k > 0 ? cdf_[k - 1] : 0.0f);
    if (!(p_tri > 0.0f)) continue;
    float r1 = hash_to_unit(splitmix(h));
    float r2 = hash_to_unit(splitmix(splitmix(h)));
    if (r1 + r2 > 1.0f) {
      r1 = 1.0f - r1;
      r2 = 1.0f - r2;
    }
    const glm::vec3 q = tri.p0 + tri.e1 * r1 + tri.e2 * r2;
    // The ray starts at the lifted origin and stops short of the emitter, which is geometry too.
    const glm::vec3 to_q = q - origin;
    const float d2 = glm::dot(to_q, to_q);
    const float d = std::sqrt(d2);
    if (!(d > 4.0f * eps)) continue;
    const glm::vec3 dir = to_q / d;
    const float cos_a = glm::dot(n, dir);
    const float cos_b = -glm::dot(tri.normal, dir);
    if (cos_a <= 0.0f || cos_b <= 0.0f) continue;
    // Area this sample stands for: A / (N p); its disc-like area A_s / pi guards the inverse
    // square so an emitter touching the receiver stays finite (a disc's exact on-axis limit).
    const float area_per_sample = tri.area / (static_cast<float>(samples) * p_tri);
    const float g = cos_a * cos_b * area_per_sample / (d2 + area_per_sample / kPi);
    out.push_back({origin, dir, eps, d - 2.0f * eps, tri.radiance * g});
  }
}

EmissiveLights::Point EmissiveLights::emitter(int i) const {
  const Tri& tri = tris_[static_cast<size_t>(i)];
  const float p_tri =
      cdf_[static_cast<size_t>(i)] - (i > 0 ? cdf_[static_cast<size_t>(i) - 1] : 0.0f);
  Point pt;
  pt.position = tri.p0;
  pt.normal = tri.normal;
  pt.radiance = tri.radiance;
  pt.pdf_area = p_tri / tri.area;
  return pt;
}

EmissiveLights::Point EmissiveLights::sample_point(float u0, float u1, float u2) const {
  if (tris_.empty()) return Point{};
  const size_t k =
      std::min(cdf_.size() - 1,
               static_cast<size_t>(std::upper_bound(cdf_.begin(), cdf_.end(), u0) - cdf_.begin()));
  Point pt = emitter(static_cast<int>(k));
  if (u1 + u2 > 1.0f) {
    u1 = 1.0f - u1;
    u2 = 1.0f - u2;
  }
  const Tri& tri = tris_[k];
  pt.position = tri.p0 + tri.e1 * u1 + tri.e2 * u2;
  return pt;
}

int EmissiveLights::find(int mesh, int triangle) const {
  if (mesh < 0 || static_cast<size_t>(mesh) >= mesh_first_.size() || triangle < 0) return -1;
  const int32_t first = mesh_first_[static_cast<size_t>(mesh)];
  if (first < 0) return -1;
  const size_t at = static_cast<size_t>(first) + static_cast<size_t>(triangle);
  return at < tri_of_.size() ? tri_of_[at] : -1;
}

}  // namespace lightpatch::cooker
