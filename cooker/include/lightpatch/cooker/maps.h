// Float light maps (linear irradiance, the lights' units) and the set the cooker bakes.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/pack_format.h"

namespace lightpatch::cooker {

// Row-major float image, row 0 = top (glTF v = 0). channels is 1 or 3.
struct FloatImage {
  int width = 0, height = 0, channels = 0;
  std::vector<float> data;
  FloatImage() = default;
  FloatImage(int w, int h, int c)
      : width(w), height(h), channels(c), data(size_t(w) * h * c, 0.0f) {}
  float& at(int x, int y, int c) { return data[(size_t(y) * width + x) * channels + c]; }
  float at(int x, int y, int c) const { return data[(size_t(y) * width + x) * channels + c]; }
};

// DESIGN.md, "The method in one screen". Contribution and shadow maps are for colour (1,1,1)
// and intensity 1; one channel where the light's transport is grey, three where bounce tints it.
//
// A map's `direct` part: the map less its bounce light, finalized like it, so that the pack can
// store the two apart (pack_builder.h, "Direct and bounce parts"). Kept with bounce light on a
// layout without blocks (Layout::align 1); empty otherwise. One channel for light groups (a white
// light's direct light is grey), three for the static lights' maps (authored colours); zero for a
// map that is bounce light alone.
struct ShadowMap {
  int light = 0;        // index into BakedMaps::lights (semi-dynamic lights)
  int object = 0;       // Scene::objects index
  FloatImage map;       // S_ol = C_l - T_ol (may be negative)
  FloatImage indirect;  // its bounce part's block image (BakedMaps), or empty
  FloatImage direct;    // its direct part (above), or empty
};

// What object o changes in the static lights' light: B − B_o, B_o being the static lights with o
// present (its shadow, positive; bounce it adds, negative). 3 channels, absolute irradiance.
struct StaticShadowMap {
  int object = 0;  // Scene::objects index
  FloatImage map;
  FloatImage indirect;  // its bounce part's block image (BakedMaps), or empty
  FloatImage direct;    // its direct part (ShadowMap), or empty
};

// Light that both objects block from light l, which S_al + S_bl removes twice: added back with
// the light's factor while both are visible (inclusion-exclusion for pairs).
struct PairCorrectionMap {
  int light = 0;     // index into BakedMaps::lights
  int object_a = 0;  // Scene::objects, object_a < object_b
  int object_b = 0;
  FloatImage map;
  FloatImage indirect;  // its bounce part's block image (BakedMaps), or empty
  FloatImage direct;    // its direct part (ShadowMap), or empty
};

// A float image kept in square tiles of kSide x kSide texels, only the tiles holding some value
// whose bits are not all zero: a moving light's pane or anchor lights a part of the page (its
// room and what it sees of the next), and the page's texels outside every chart are never lit.
// The full inn's 1,263 anchors held 8.9 GB of dense block images until the pack was written.
// dense() gives back the image bit for bit (-0.0 and NaN included).
class TiledImage {
 public:
  static constexpr int kSide = 16;
  TiledImage() = default;
  explicit TiledImage(const FloatImage& image);
  FloatImage dense() const;
  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return channels_; }
  bool empty() const { return width_ == 0 || height_ == 0 || channels_ == 0; }
  // Texel (x, y)'s channels (0 <= x < width, 0 <= y < height), or null where its tile holds
  // only zeros.
  const float* texel(int x, int y) const;
  // The largest finite value, and 0 where none is larger (as a scan of dense() from 0 finds it).
  float peak() const;
  // The floats kept (the tiles held), against width x height x channels dense.
  size_t stored_floats() const { return data_.size(); }

 private:
  static constexpr uint32_t kNoTile = ~0u;
  int width_ = 0, height_ = 0, channels_ = 0, tiles_x_ = 0;
  std::vector<uint32_t> slot_;  // per tile (row-major): its index among the tiles held, or kNoTile
  std::vector<float> data_;     // the tiles held, kSide x kSide x channels each, row-major
};

// One pane of the moving lights (pack_format.h, "Moving lights"; docs/moving_lights.md): the
// bounce light everywhere when its texels receive irradiance 1 (grey), and where the runtime's
// weights read it from. record.light is set by the pack builder.
struct PaneMap {
  pack::PaneRecord record{};
  std::vector<uint32_t> texels;  // its light-map texels (row-major indices)
  // The bounce light, 3 channels: the block image where the layout has blocks that divide the
  // page (the pack stores a pane on the indirect map alone, so the cook keeps no full-size map:
  // 128 of them were most of the full inn's peak memory), else the light-map-sized map. In tiles
  // (TiledImage): hundreds of them are held until the pack is written.
  TiledImage map;       // light-map size, or empty when `indirect` holds the pane
  TiledImage indirect;  // its block image (BakedMaps), or empty
  // With `indirect` alone: the largest finite value its light-map-sized map would hold (its
  // significance; add_blocks()). With `map`, map.peak() of the finalized map is.
  float peak = 0.0f;
};

// Pane `p`'s bounce light at light-map texel `t` of a `width`-texel-wide page, into out[3]: its
// map's, else its block image's block holding t (zero without either).
inline void pane_bounce_at(const PaneMap& p, uint32_t width, uint32_t t, float out[3]) {
  out[0] = out[1] = out[2] = 0.0f;
  const float* v = nullptr;
  if (!p.map.empty() && width == uint32_t(p.map.width())) {
    v = p.map.texel(int(t % width), int(t / width));
  } else if (!p.indirect.empty() && width >= uint32_t(p.indirect.width())) {
    const uint32_t w = uint32_t(p.indirect.width()), h = uint32_t(p.indirect.height());
    const uint32_t s = width / w;
    const uint32_t bx = std::min((t % width) / s, w - 1), by = std::min((t / width) / s, h - 1);
    v = p.indirect.texel(int(bx), int(by));
  }
  if (v)
    for (int c = 0; c < 3; ++c) out[c] = v[c];
}

struct BakedMaps {
  // Irradiance of one 8-bit step of the final light map at the authored exposure (the
  // significance threshold for early outs, pair culling and patch extraction). For a light's
  // C_l/S_ol (baked at intensity 1) the threshold is output_step / (authored max(colour) *
  // intensity), floored so that a light authored off or at 0 still keeps its patches, and at
  // most one 8-bit step of the light's own peak (so a very dim light recomposes alone to 8 bits).
  // The base map and the static shadows take output_step, or one step of the static light's own
  // peak where that is finer (static light far dimmer than the semi-dynamic lights survives them
  // being switched off).
  float output_step = 0.0f;
  FloatImage base;                       // B, 3 channels
  std::vector<int> lights;               // Scene::lights index of each semi-dynamic light
  std::vector<FloatImage> contribution;  // C_l, parallel to lights
  // Bounce light on blocks (Layout::align > 1, pack_format.h "Two target maps"): the block image
  // of every map's bounce part, (width / align) x (height / align) x 3, which the pack stores as
  // the map's indirect part; its light-map part is the rest, the map less the block image's
  // magnification (signed: the maps' bounce light follows each surface, the magnification blends
  // across creases inside a chart). Empty images where a map has no bounce part or the layout has
  // no blocks.
  FloatImage base_indirect;
  std::vector<FloatImage> contribution_indirect;  // parallel to contribution
  // Each map's direct part (ShadowMap), or empty images.
  FloatImage base_direct;
  std::vector<FloatImage> contribution_direct;      // parallel to contribution
  std::vector<ShadowMap> shadows;                   // kept pairs only
  std::vector<PairCorrectionMap> pair_corrections;  // overlapping shadows that matter
  std::vector<StaticShadowMap> static_shadows;      // what objects change in the static light
  // Moving lights (Scene::lights indices; no maps of their own) and the panes their bounce light
  // is made of, shared by all of them. Panes are empty without bounce light.
  std::vector<int> moving_lights;
  std::vector<PaneMap> panes;
};

}  // namespace lightpatch::cooker
