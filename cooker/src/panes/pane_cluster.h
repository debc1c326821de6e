// The moving lights' panes (docs/moving_lights.md; Szecsi & Szirmay-Kalos, precomputed radiance
// maps, section 3): the static surfaces' texels clustered into patches that are close and alike
// in orientation, each with the entry points and the depth map the runtime weighs it by
// (pack_format.h, PaneRecord).
#pragma once

#include <cstdint>
#include <vector>

#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/texels.h"
#include "lightpatch/cooker/tracer.h"

namespace lightpatch::cooker {

struct PaneClusterOptions {
  int panes = 32;  // panes before the line-of-sight refinement (at most four times this after it)
  int threads = 1;
  // Per light-map texel, 0 for a texel to leave out of every pane (IndirectIntegrator::
  // read_texels(): no gather ray reads its light, so irradiance on it bounces nowhere); null:
  // every texel the clustering takes.
  const std::vector<uint8_t>* senders = nullptr;
};

// Clusters the valid texels of static meshes that stop rays (not a flame, not an object; only
// options.senders where given) into panes: by the dominant axis of their normal, then split at
// the median of the longest side of the widest pane until there are options.panes; then, up to
// four times as many, the pane a light in front of it lights most unevenly (its entry points'
// irradiance from lights standing in front of them, with visibility, spread about their mean;
// times its texels) is split again, as is a pane whose entry points do not all see its eye (a
// pane must not reach round a wall). Deterministic. Returns the panes with record (light 0) and
// texels set, maps empty.
std::vector<PaneMap> cluster_panes(const Scene& scene, const TexelSet& texels, const Tracer& tracer,
                                   const PaneClusterOptions& options);

// A depth map texel (pack_format.h, PaneRecord): the distance from `eye` along unit `dir` to the
// first static surface within `depth_range` in 65535ths of it, rounded up (a light exactly at the
// first surface counts as seen), 65535 for none.
uint16_t depth_code(const Tracer& tracer, const glm::vec3& eye, const float dir[3], float eps,
                    float depth_range);

// Each of `texel_count` texels' pane (index into `panes`), -1 for none. Throws CookError when a
// texel is out of range or in two panes (cluster_panes() partitions them).
std::vector<int32_t> pane_of_texels(const std::vector<PaneMap>& panes, size_t texel_count);

// A pane map's significance (irradiance per unit irradiance on the pane): it keeps what shows as
// half an 8-bit step (`step`: the output step, or half of it for patches) with the brightest
// moving light 1 m from the pane, where its weight is that light's intensity; nearer, the weight
// and the step grow together. The bake's series and the pack's patches use this one rule.
float pane_significance(const Scene& scene, float step);
// The brightest moving light's max(colour) * intensity (1 when there is none or it is 0): the
// weight a pane map is significant at, as pane_significance() and the pack's colour rule use it.
float strongest_moving_light(const Scene& scene);

}  // namespace lightpatch::cooker
