// Direct irradiance from punctual lights (KHR_lights_punctual) and emissive triangles, as shadow
// ray samples: each sample is a segment from the texel towards a point of the light and the
// irradiance it brings if nothing blocks it. The baker decides what blocks it.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

#include "lightpatch/cooker/scene.h"

namespace lightpatch::cooker {

// Fraction of a light's significance threshold below which a texel's unshadowed irradiance is
// not computed at all (seed 004 §7.2, "0.1 / 255 of saturation").
constexpr float kEarlyOutFraction = 0.1f;

struct LightSample {
  glm::vec3 origin;  // texel position lifted off the surface by the tracer's epsilon
  glm::vec3 dir;     // unit, towards the light sample
  float tmin = 0.0f, tmax = 0.0f;
  glm::vec3 irradiance{0.0f};  // unshadowed irradiance this sample adds (all channels equal
                               // for punctual lights at colour (1,1,1), intensity 1)
};

// Unshadowed irradiance at `p` (normal `n`) from a punctual light with intensity 1 located at
// `light_pos` (ignored for directional lights): E = cos(theta) / d^2 (point), times the spot cone
// falloff and the range window of KHR_lights_punctual; E = cos(theta) for directional lights.
// `eps2` guards the inverse square (d^2 + eps2) so a light touching a surface stays finite.
float punctual_irradiance(const Light& light, const glm::vec3& light_pos, const glm::vec3& p,
                          const glm::vec3& n, float eps2);

// Spot cone attenuation per KHR_lights_punctual: clamp(cd * scale + offset, 0, 1)^2.
float spot_attenuation(const Light& light, const glm::vec3& to_point_unit);

// Range window per KHR_lights_punctual's recommended form: clamp(1 - (d / range)^4, 0, 1);
// 1 when range <= 0 (infinite).
float range_window(float range, float d);

// Distance beyond which a punctual light of intensity 1 brings less than `cutoff` (inverse
// square, range included); +inf for directional lights or cutoff <= 0.
float light_reach(const Light& light, float cutoff);

// Deterministic per-(seed, texel, light, sample) random numbers in [0,1).
uint64_t sample_hash(uint64_t seed, uint64_t texel, uint64_t light, uint64_t sample);
float hash_to_unit(uint64_t h);

// Appends to `out` the shadow samples of one punctual light (intensity 1, white) for the texel at
// p/n; `samples` per light with a radius (rounded down to a square, at least 1), one otherwise.
// Returns false without appending when an early out fires: light behind the surface, beyond its
// range, or unshadowed irradiance below `cutoff`. `extent` bounds directional shadow rays.
bool sample_punctual(const Light& light, const glm::vec3& p, const glm::vec3& n, int samples,
                     uint64_t rng, float eps, float extent, float cutoff,
                     std::vector<LightSample>& out);

// The emissive triangles of static meshes, as area lights (radiance L = Material::emissive).
class EmissiveLights {
 public:
  explicit EmissiveLights(const Scene& scene);
  bool empty() const { return tris_.empty(); }
  size_t triangle_count() const { return tris_.size(); }
  // Appends `samples` shadow samples (area-weighted by power, stratified) for the texel at p/n.
  void sample(const glm::vec3& p, const glm::vec3& n, int samples, uint64_t rng, float eps,
              std::vector<LightSample>& out) const;

 private:
  struct Tri {
    glm::vec3 p0, e1, e2, normal;
    float area;
    glm::vec3 radiance;
  };
  std::vector<Tri> tris_;
  std::vector<float> cdf_;  // cumulative power, normalized to 1 at the end
};

}  // namespace lightpatch::cooker
