// The light-map layout: where every baked triangle lands in the one light-map page.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/cooker/scene.h"

namespace lightpatch::cooker {

struct Rect {
  int x = 0, y = 0, w = 0, h = 0;  // texels; origin top-left (image row 0 = glTF v 0)
  bool contains(int px, int py) const { return px >= x && py >= y && px < x + w && py < y + h; }
};

// Light-map UVs of one MeshInstance. Vertices are split where charts are cut, so each layout
// vertex refers back to a source vertex of the MeshInstance.
// Empty for a mesh kept out of the light map (lightmapExclude).
struct MeshLayout {
  std::vector<uint32_t> source_vertex;  // layout vertex -> MeshInstance vertex
  std::vector<glm::vec2> uv;            // light-map UV in [0,1], glTF convention
  std::vector<uint32_t> indices;        // one triangle per source triangle, same order
  // Laid out by its own TEXCOORD_1: uv = TEXCOORD_1 * (x, y) + (z, w) (Unity's
  // lightmapScaleOffset, in glTF's v-down convention); the layout vertices are the mesh's.
  bool from_uv1 = false;
  glm::vec4 uv1_scale_offset{0.0f};
};

// A baked object: one glTF node's meshes, owning one rectangle of the light map that no other
// baked object overlaps. Patches are cut per region.
struct Region {
  std::string name;         // node name
  int object = -1;          // semi-dynamic object index or -1
  std::vector<int> meshes;  // MeshInstance indices
  Rect rect;
  // The charts' rectangles inside `rect`, each with its border (LayoutOptions::border_texels) of
  // empty texels: one per unwrapped chart, one for a node's whole TEXCOORD_1 layout; empty for a
  // whole-scene TEXCOORD_1 layout.
  std::vector<Rect> charts;
};

// An edge of a smooth surface (its two triangles share both source vertices, so both normals)
// that the unwrap cut: it appears in two charts, and finalize_map() makes the light map agree on
// both sides. Light-map UVs in [0,1].
struct SeamEdge {
  glm::vec2 a0, a1;  // the edge in the first chart
  glm::vec2 b0, b1;  // the same edge in the second chart (b0 is the same point as a0)
  glm::vec2 a2, b2;  // the opposite corner of the edge's triangle in each chart (its inside)
};

// Where light-map UVs come from (--unwrap): kAuto uses each node's TEXCOORD_1 when all its
// meshes have one and unwraps the others; kAlways ignores TEXCOORD_1; kNever requires it.
enum class UnwrapMode { kAuto, kAlways, kNever };

struct LayoutOptions {
  int lightmap_size = 0;         // > 0: fixed page size (texels, square); 0 = derive from density
  float texels_per_unit = 0.0f;  // > 0: texels per metre; 0 = default for a room-sized scene
  int border_texels = 2;         // empty texels around each chart
  // Blocks of align x align texels (the pack's indirect scale: 1, 2, 4 or 8): every chart's and
  // every node's rectangle starts and ends on a block boundary with at least one block of border
  // of its own, and the page is a whole number of blocks, so the indirect map's bilinear
  // interpolation never mixes two charts (pack_format.h, "Two target maps"). A fixed
  // lightmap_size must be a multiple of it when align_required; otherwise (--indirect-scale auto)
  // the alignment halves until the charts fit the page, and Layout::align says what it became.
  int align = 1;
  bool align_required = false;
  int max_lightmap_size = 4096;
  UnwrapMode unwrap = UnwrapMode::kAuto;
};

struct Layout {
  int width = 0, height = 0;  // texels
  float texels_per_unit = 0;  // the density actually used (may be lowered to fit)
  bool verbatim_uv1 = false;  // one TEXCOORD_1 layout over the whole scene, used as it is
  int uv1_regions = 0;        // nodes placed by their own TEXCOORD_1 (scale and offset)
  int unwrapped_regions = 0;  // nodes the cooker unwrapped
  // Texels per block the charts are laid out on (LayoutOptions::align, after any lowering): the
  // scale of the pack's indirect map (1: none). The page is a whole number of blocks.
  int align = 1;
  // Texels of border around each chart's content in Region::charts (LayoutOptions::border_texels,
  // at least one block; 0 where charts are not laid out here). Bilinear filtering at a chart's
  // edge reads the first ring only.
  int border = 0;
  std::vector<MeshLayout> meshes;  // parallel to Scene::meshes
  std::vector<Region> regions;
  std::vector<SeamEdge> seams;
  std::vector<std::string> notes;  // decisions worth telling the user (density lowered, ...)
};

}  // namespace lightpatch::cooker
