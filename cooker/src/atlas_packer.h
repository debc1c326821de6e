// Packing patches into the channels of RGBA8 atlases (thesis §4.1.5, without its power-of-two
// sizes and gutters): patches sorted by channel count (2, then 3, then 1), then height, then
// width, descending; a 2-channel patch takes the lowest place of channels 0-1 or 2-3 (so they pair
// up), a 3-channel patch channels 0-2 of one rectangle, a 1-channel patch the lowest place of any
// channel (so grey patches fill the alpha plane under tinted ones before they raise the atlas);
// each at the lowest, then leftmost, place of its channels' skylines. Atlas sides are multiples of
// pack::kAtlasAlign up to the maximum size: while the patches left need more than one atlas of
// the maximum size, the atlas is that size (what does not fit waits for the next); the last one
// takes the width and order, among those tried, that hold all the patches left in the fewest
// texels: the orders by height, longest side, area and width (each after the channel count), at
// widths a fifth apart, then every few texels around the best, then every width while a budget of
// placements lasts (all of them for a pack of a few hundred patches).
// Patches touch: the runtime reads only a patch's own texels (texelFetch at texel centres), so
// no gutter is needed.
#pragma once

#include <cstdint>
#include <vector>

namespace lightpatch::cooker {

struct PackItem {
  int width = 0, height = 0;  // patch texels
  int channels = 1;           // 1, 2 or 3
};

struct Placement {
  int atlas = 0;
  int x = 0, y = 0;  // top-left texel of the patch
  int channel = 0;   // first channel
};

struct AtlasSize {
  int width = 0, height = 0;
};

// The smallest maximum atlas size accepted.
constexpr int kMinAtlasSize = 16;

struct AtlasLayout {
  std::vector<Placement> placements;  // parallel to the items
  std::vector<AtlasSize> atlases;
};

// `max_size`: the largest atlas side, a multiple of pack::kAtlasAlign >= kMinAtlasSize. Throws
// CookError if it is not, if a patch is larger than max_size, or if more than 256 atlases would
// be needed. `threads` (>= 1) share the search for the last atlas's shape; the layout does not
// depend on their number.
AtlasLayout pack_atlases(const std::vector<PackItem>& items, int max_size, int threads = 1);

}  // namespace lightpatch::cooker
