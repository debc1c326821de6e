// Packing patches into the channels of RGBA8 atlases (thesis §4.1.5): patches sorted by channel
// count then max(width, height), descending; a 3-channel patch takes channels 0-2 of one
// rectangle, a 1-channel patch one channel, trying R, G, B, A in turn so that a channel fills
// before the next opens; when a patch fits nowhere the atlas doubles (width and height) if
// 2 * S_a < S_l (S_a: the atlas's channel-texels, S_l: the channel-texels of the patches still to
// place in this pass) and it is below the maximum size, otherwise the patch waits for the next
// atlas. Each patch is surrounded by a one-texel gutter (edge texels replicated) in its channels.
#pragma once

#include <cstdint>
#include <vector>

namespace lightpatch::cooker {

struct PackItem {
  int width = 0, height = 0;  // patch texels (without gutter)
  int channels = 1;           // 1 or 3
};

struct Placement {
  int atlas = 0;
  int x = 0, y = 0;  // top-left texel of the patch itself (the gutter is at x-1, y-1)
  int channel = 0;   // first channel
};

struct AtlasSize {
  int width = 0, height = 0;
};

constexpr int kMinAtlasSize = 16;

struct AtlasLayout {
  std::vector<Placement> placements;  // parallel to the items
  std::vector<AtlasSize> atlases;
};

// Throws CookError if a patch (plus gutter) is larger than max_size or more than 256 atlases
// would be needed.
AtlasLayout pack_atlases(const std::vector<PackItem>& items, int max_size);

}  // namespace lightpatch::cooker
