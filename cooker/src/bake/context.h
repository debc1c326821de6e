// What every part of one bake shares: the scene, texels and tracer, the sampling settings, and the
// significance of each light's maps (DESIGN.md, "Only what the scene calls for"). Built once per
// bake, deterministic for (scene, texels, options); read-only afterwards, so groups and states
// can use it from any thread.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "direct_light.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/texels.h"
#include "lightpatch/cooker/tracer.h"
#include "texel_footprint.h"

namespace lightpatch::cooker {

class IndirectIntegrator;
struct DirectPoints;

// A texel in a light's penumbra (some of its samples of the light clear, some not) draws that
// light again with this many times the samples and patch points: shadow edges are where a texel's
// few samples err the most (the room's worst production texel, a penumbra at a chart's corner,
// was 0.101 against a converged 0.059 with 64 samples).
constexpr int kPenumbraFactor = 4;

// A light's significance and sampling.
struct LightPlan {
  float threshold = 0.0f;  // significance of intensity-1 irradiance: output_step / authored scale
  float cutoff = 0.0f;     // early out: kEarlyOutFraction * threshold
  int samples = 1;         // shadow samples per texel (lights with a radius: the area samples)
};

struct BakeContext {
  BakeContext(const Scene& scene, const Layout& layout, const TexelSet& texels,
              const Tracer& tracer, const BakeOptions& options);
  ~BakeContext();

  const Scene& scene;
  const Layout& layout;
  const TexelSet& texels;
  const Tracer& tracer;
  BakeOptions options;
  int threads = 1;
  int area_samples = 16;
  int texel_samples = 1;                   // receiver points per texel for lights without a radius
  std::vector<TexelFootprint> footprints;  // parallel to the texels; empty at 1 texel sample
  const TexelFootprint* footprint(size_t t) const {
    return footprints.empty() ? nullptr : &footprints[t];
  }
  float eps = 0.0f;     // the tracer's self-intersection offset
  float extent = 0.0f;  // longer than any segment inside the scene's bounds
  // Irradiance of one 8-bit step of the final map at the authored exposure (BakedMaps).
  float output_step = 0.0f;
  // Significance of the static group: output_step, or one step of the brightest static light's
  // own peak where that is finer (a static light far dimmer than the semi-dynamic ones keeps 8
  // bits of its own when they are off).
  float static_step = 0.0f;
  EmissiveLights emissive;
  std::vector<LightPlan> lights;  // parallel to Scene::lights
  // Bounce light (null with options.indirect off); set by the session once its rays are traced.
  std::unique_ptr<IndirectIntegrator> indirect;

  uint64_t texel_rng(size_t texel, int slot) const;
  // Shadow samples of scene light `li` (intensity 1, white) at texel t. `posed`, if not null, is
  // that light moved (a moving light at a state's pose): the same random numbers, its position.
  void light_samples(int li, size_t t, std::vector<LightSample>& out,
                     const Light* posed = nullptr) const;
  // For a texel in a penumbra of light `li` (is_penumbra of its light_samples): a set
  // kPenumbraFactor times denser, in directions and in points of the texel's patch, with random
  // numbers of its own, that replaces them. False (nothing written) where there is nothing denser
  // to draw: one point per texel and a light without a size.
  bool penumbra_light_samples(int li, size_t t, std::vector<LightSample>& out,
                              const Light* posed = nullptr) const;
  void emissive_samples(size_t t, std::vector<LightSample>& out) const;
  // The same for point i of the integrator's DirectPoints `pts`: a point, not a texel's patch,
  // and one shadow ray per light (a sphere light: to its centre, with its exact unshadowed
  // irradiance) and one emissive sample: each point stands for a few gather rays, which average
  // them.
  void point_light_samples(const DirectPoints& pts, int li, size_t i, std::vector<LightSample>& out,
                           const Light* posed = nullptr) const;
  void point_emissive_samples(const DirectPoints& pts, size_t i,
                              std::vector<LightSample>& out) const;
  std::string light_name(int li) const;
};

// Axis-aligned bounds of an object's meshes.
struct Bounds {
  glm::vec3 lo{3.4e38f};
  glm::vec3 hi{-3.4e38f};
  bool empty() const { return lo.x > hi.x; }
};
Bounds object_bounds(const Scene& scene, const Object& o);

// Geometric pair culling: can the object stand between the light and a texel the light reaches
// above its early-out cutoff? Exact with respect to the baker's early outs: a shadow ray through
// the object starts beyond it, so if the object is beyond the light's reach so is the texel; a
// spot's samples outside its cone carry no light. Returns "" when the pair must be traced.
std::string precull_pair(const Light& light, const LightPlan& plan, const Bounds& b);

float max3(const glm::vec3& v);

}  // namespace lightpatch::cooker
