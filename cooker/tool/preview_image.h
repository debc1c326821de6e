// Pictures of what was baked, for `lightpatch preview` and `bake-state --png` (what Unity's baked
// light-map view and Godot's bake preview show, without writing code): the light map tone-mapped
// to sRGB, the pack's atlases channel by channel, the charts coloured by object over the light,
// and a texel checker (applied to a model through its light-map UVs, it shows the texel density).
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/pack_view.h"

namespace lightpatch::tool {

struct RgbImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // rows top to bottom (image row 0 = glTF v 0)
};

enum class PreviewView { kLightmap, kAtlases, kCharts, kChecker };

// "lightmap", "atlases", "charts", "checker"; throws CookError on anything else.
PreviewView parse_preview_view(const std::string& name);

// The light-map triangles of the baked meshes (UVs in [0,1], 3 per triangle), each with its mesh
// instance and its semi-dynamic object (-1: static).
struct ChartTriangles {
  std::vector<glm::vec2> uv;
  std::vector<int> instance;
  std::vector<int> object;
};
ChartTriangles pack_charts(const PackView& pack);
ChartTriangles layout_charts(const cooker::Scene& scene, const cooker::Layout& layout);

// Linear irradiance to sRGB: the 99th percentile of the lit texels' largest channel maps to
// white, times `exposure`; brighter texels clip. Negative texels (never valid irradiance) show
// magenta so that a defect is seen.
RgbImage tonemap(const cooker::FloatImage& map, float exposure);

// Each instance's triangles in a colour of its own (semi-dynamic objects saturated, static
// meshes pale), shaded by the tone-mapped light; with `checker`, alternate texels darkened.
RgbImage chart_image(const cooker::FloatImage& map, const ChartTriangles& charts, bool checker,
                     float exposure);

// Every atlas as four grey planes (R, G, B, A) side by side, atlases one under another.
RgbImage atlas_image(const PackView& pack);

// Each pixel repeated zoom x zoom times.
RgbImage zoomed(const RgbImage& image, int zoom);

// The picture options of `preview` and `bake-state --png`.
struct PreviewOptions {
  std::string png;  // output path; empty: no picture
  PreviewView view = PreviewView::kLightmap;
  float exposure = 1.0f;  // factor on the automatic exposure
  int zoom = 1;           // pixels per texel
};

// Reads --view, --exposure and --zoom (and `png_option` into png, if not empty) from `args`.
struct Args;
PreviewOptions parse_preview_options(Args& args, const char* png_option);

// The picture of `view` for `map` (the light map; charts and checker use `charts`; atlases use
// `pack`, which may be null for the others), zoomed and written as PNG to options.png
// atomically.
void write_preview(const PreviewOptions& options, const cooker::FloatImage& map,
                   const ChartTriangles& charts, const PackView* pack);

}  // namespace lightpatch::tool
