// Per-texel surface samples of the light map: what the baker lights.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/scene.h"

namespace lightpatch::cooker {

// Row-major, row 0 = top of the light map. A texel is valid when a triangle covers its centre
// (or, for conservative coverage, any part of it); invalid texels are filled by dilation after
// baking.
struct TexelSet {
  int width = 0, height = 0;
  std::vector<glm::vec3> position;  // world space, pushed out of solid geometry
  std::vector<glm::vec3> normal;    // world space, unit (interpolated shading normal)
  std::vector<glm::vec3> albedo;    // material albedo at the texel (for bounce light)
  std::vector<uint8_t> valid;       // 1 = lit sample
  std::vector<int32_t> mesh;        // MeshInstance index or -1
  std::vector<int32_t> region;      // Layout::regions index or -1
  // Dilation plan (build_texels() makes it; finalize_map() applies it to every map): unused
  // texels of a region in fill order, each set to the mean of fill_sources[first, first+count),
  // texels that were valid or filled before it. Empty for hand-made texel sets.
  struct Fill {
    uint32_t texel, first, count;
  };
  std::vector<Fill> fill;
  std::vector<uint32_t> fill_sources;
  // Seam plan (build_texels() makes it from Layout::seams; finalize_map() applies it after the
  // dilation): texels outside their chart next to a cut edge, each set to the weighted sum
  // seam_weights[first, first+count) of texels seam_sources[...] (weights >= 0, summing to 1):
  // the other chart's filtered value at the same point of the surface.
  std::vector<Fill> seam;
  std::vector<uint32_t> seam_sources;
  std::vector<float> seam_weights;
  size_t index(int x, int y) const { return static_cast<size_t>(y) * width + x; }
};

}  // namespace lightpatch::cooker
