// Direct irradiance from punctual lights (KHR_lights_punctual) and emissive triangles, as shadow
// ray samples: each sample is a segment from the texel towards a point of the light and the
// irradiance it brings if nothing blocks it. The baker decides what blocks it.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

#include "lightpatch/cooker/scene.h"
#include "sample_hash.h"
#include "texel_footprint.h"

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

// The emitter a point or spot light stands for, one definition for every integrator (the cook's
// direct light and the reference path tracer). A light of radius r > 0 (extras.lightRadius) is a
// sphere of radius r around its position with uniform radiance L = I / (pi r^2), I the intensity
// (1 here: callers scale by colour * intensity), seen from a receiver p through the spot cone's
// falloff of the direction from the light's centre to p and the range window of p's distance to
// the centre. From d = |c - p| >= r with the whole sphere above p's horizon it gives I cos / d^2,
// a point light's irradiance; a light touching or enclosing the receiver stays finite (at most
// pi L). The sphere is an emitter only: it occludes nothing (a flame or bulb mesh around it is
// geometry of its own). r = 0 is a point light.
struct SphereView {
  glm::vec3 axis{0.0f, 0.0f, 1.0f};  // unit, from p towards the centre
  float distance = 0.0f;             // d = |c - p|
  float cos_max = 1.0f;              // cosine of the visible cone's half angle; -1 inside
  float one_minus_cos = 0.0f;        // 1 - cos_max without cancellation (small cones)
  float radiance = 0.0f;             // L * spot * window, intensity 1 (W/m^2/sr per cd)
  float radius = 0.0f;
  float solid_angle() const { return 6.28318530718f * one_minus_cos; }
};

// The sphere of a point or spot light with radius > 0 as seen from p. False when it sends p no
// light (outside the spot cone, beyond the range, radiance 0).
bool view_sphere_light(const Light& light, const glm::vec3& p, SphereView* view);

// A direction towards the sphere for (u, v) in [0,1)^2 and the distance from p to the sphere's
// surface along it (its far side from inside). Outside the sphere uniform in the visible cone
// (density 1 / solid_angle()); inside, where every direction meets it, cosine-weighted about the
// receiver's normal n (density cos / pi), which makes an unshadowed estimate exact.
glm::vec3 sample_sphere_view(const SphereView& view, const glm::vec3& n, float u, float v,
                             float* t_surface);

// The density per solid angle with which sample_sphere_view picks the unit direction w (0 for
// a direction outside the cone or below the horizon inside).
float sphere_view_pdf(const SphereView& view, const glm::vec3& n, const glm::vec3& w);

// Distance along the unit `dir` from p to where the ray meets the sphere (centre, radius) first
// at t > 0 (its far side when p is inside), or -1 when it misses.
float sphere_hit_distance(const glm::vec3& p, const glm::vec3& dir, const glm::vec3& centre,
                          float radius);

// Integral of max(0, n . w) over the directions w of a cone of half angle sigma whose axis makes
// angle theta with n (sin2_sigma = sin^2 sigma, cos_theta = cos theta): the horizon-clipped
// cosine-weighted solid angle of a sphere (Snyder 1996, "Area light sources for real-time
// graphics"). Times the radiance it is a sphere light's unshadowed irradiance.
float sphere_cosine_integral(float cos_theta, float sin2_sigma);

// Orthonormal basis (t, b) completing unit w (Duff et al. 2017).
void orthonormal_basis(const glm::vec3& w, glm::vec3& t, glm::vec3& b);

// A cosine-weighted direction about unit n for (u, v) in [0,1)^2 (density cos / pi).
glm::vec3 cosine_direction(const glm::vec3& n, float u, float v);

// Appends to `out` the shadow samples of one punctual light (intensity 1, white) for the texel at
// p/n; `samples` per light with a radius (rounded down to a square, at least 1), one otherwise.
// A light with a radius is its sphere (SphereView): with one sample, the exact unshadowed
// irradiance and one ray to a random point of its visible cone above the horizon (the centre
// from inside it); with more, its visible cone stratified g x g, each ray
// ending on the sphere's surface.
// With a footprint (texel_footprint.h), every sample leaves its own point of the texel's surface
// patch, and a light without a radius (or with one sample) gets `positions` samples, one per
// point, each a share of the irradiance there: the texel's mean over its patch.
// Returns false without appending when an early out fires: light behind the surface, beyond its
// range, or unshadowed irradiance below `cutoff`. `extent` bounds directional shadow rays.
bool sample_punctual(const Light& light, const glm::vec3& p, const glm::vec3& n, int samples,
                     uint64_t rng, float eps, float extent, float cutoff,
                     std::vector<LightSample>& out, const TexelFootprint* footprint = nullptr,
                     int positions = 1);

// The emissive triangles of static meshes, as area lights (radiance L = Material::emissive).
class EmissiveLights {
 public:
  explicit EmissiveLights(const Scene& scene);
  bool empty() const { return tris_.empty(); }
  size_t triangle_count() const { return tris_.size(); }
  // Appends `samples` shadow samples (area-weighted by power, stratified) for the texel at p/n;
  // with a footprint, each from its own point of the texel's surface patch.
  void sample(const glm::vec3& p, const glm::vec3& n, int samples, uint64_t rng, float eps,
              std::vector<LightSample>& out, const TexelFootprint* footprint = nullptr) const;

  // For a path tracer. The emitters are grouped in clusters (the connected pieces of each
  // emitting mesh: a flame, a panel; beyond kMaxClusters, neighbouring pieces merged): a point is
  // drawn for a receiver at x by picking a cluster with probability proportional to its power
  // over max(squared distance to x, its radius squared), a triangle in it by power, a point
  // uniform on that (u0, u1, u2 in [0,1)).
  static constexpr int kMaxClusters = 64;
  struct Point {
    glm::vec3 position{0.0f}, normal{0.0f};  // normal: the side it emits from
    glm::vec3 radiance{0.0f};
    float pdf_area = 0.0f;  // probability density of the point per unit area
    int emitter = -1;
  };
  Point sample_point(const glm::vec3& x, float u0, float u1, float u2) const;
  // The emitter that triangle `triangle` of mesh `mesh` is, or -1 (triangle within the mesh).
  int find(int mesh, int triangle) const;
  // Emitter i (from find()): its normal, radiance and the density per unit area with which
  // sample_point(x, ...) picks its points; position is its first vertex.
  Point emitter(int i, const glm::vec3& x) const;
  // False for an emitter on a mesh with castShadows false: no ray can hit it, only sampling
  // finds it.
  bool hittable(int i) const { return tris_[static_cast<size_t>(i)].hittable; }
  size_t cluster_count() const { return clusters_.size(); }

 private:
  struct Tri {
    glm::vec3 p0, e1, e2, normal;
    float area;
    glm::vec3 radiance;
    bool hittable = true;
    int cluster = 0;
    float p_in_cluster = 0.0f;  // its share of the cluster's power
  };
  struct Cluster {
    glm::vec3 centre{0.0f};
    float radius2 = 0.0f;        // squared radius of a sphere around its triangles
    float power = 0.0f;          // sum of peak radiance x area
    std::vector<uint32_t> tris;  // indices into tris_
    std::vector<float> cdf;      // cumulative power over `tris`, 1 at the end
  };
  void build_clusters(const Scene& scene);
  // Cumulative pick probabilities of the clusters for a receiver at x (1 at the end).
  void cluster_cdf(const glm::vec3& x, float* cdf) const;
  std::vector<Tri> tris_;
  std::vector<Cluster> clusters_;
  std::vector<float> cdf_;           // cumulative power, normalized to 1 at the end
  std::vector<int32_t> mesh_first_;  // per mesh: its first entry in tri_of_, or -1
  std::vector<int32_t> tri_of_;      // per triangle of an emitting mesh: index in tris_ or -1
};

}  // namespace lightpatch::cooker
