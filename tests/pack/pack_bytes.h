// Editing pack bytes in the pack tests: an 8-byte aligned copy (as the loader requires) and the
// table checksum recomputed after an edit, so that the edit reaches the record validation.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "lightpatch/pack_format.h"
#include "lightpatch/pack_view.h"

namespace lightpatch::test {

// The first `n` bytes of `b` in 8-byte aligned storage.
struct Aligned {
  std::vector<uint64_t> words;
  uint64_t size = 0;
  explicit Aligned(const std::vector<uint8_t>& b, uint64_t n) : words((n + 7) / 8 + 1), size(n) {
    if (n > 0) std::memcpy(words.data(), b.data(), n);
  }
  uint8_t* data() { return reinterpret_cast<uint8_t*>(words.data()); }
};

// Recomputes the table checksum of a (possibly corrupt) pack; leaves it alone if the index itself
// is out of bounds.
inline void fix_checksum(uint8_t* d, uint64_t size) {
  pack::Header h;
  std::memcpy(&h, d, sizeof(h));
  if (h.section_count == 0 || h.section_count > pack::kSectionTypeMax) return;
  const uint64_t index_bytes = uint64_t(h.section_count) * sizeof(pack::SectionEntry);
  if (sizeof(h) + index_bytes > size) return;
  uint32_t crc = crc32(d + sizeof(h), index_bytes);
  for (uint32_t i = 0; i < h.section_count; ++i) {
    pack::SectionEntry e;
    std::memcpy(&e, d + sizeof(h) + i * sizeof(e), sizeof(e));
    if (e.type == pack::kSectionAtlasData || e.type == pack::kSectionMeshData) continue;
    if (e.offset > size || e.length > size - e.offset) return;
    crc = crc32(d + e.offset, e.length, crc);
  }
  std::memcpy(d + offsetof(pack::Header, table_checksum), &crc, 4);
}

// Writes pseudo-random bytes to every atlas channel-texel of `copy` (a byte copy of the pack
// `v` views) that no patch of `v` covers; returns how many it wrote. The table checksum does not
// cover atlas data, so the copy stays valid.
inline uint64_t fill_unused_atlas_texels(const PackView& v, const uint8_t* original, uint8_t* copy,
                                         uint32_t seed) {
  uint64_t written = 0;
  for (uint32_t a = 0; a < v.atlas_count(); ++a) {
    const pack::AtlasRecord& ar = v.atlas(a);
    std::vector<uint8_t> used(size_t(ar.width) * ar.height * 4, 0);
    for (uint32_t i = 0; i < v.patch_count(); ++i) {
      const pack::PatchRecord& p = v.patch(i);
      if (p.atlas != a) continue;
      // A magnified patch covers its atlas rectangle, not its destination's size.
      const uint32_t level = pack::patch_level(p.flags);
      const uint32_t w = pack::patch_atlas_side(p.width, level);
      const uint32_t h = pack::patch_atlas_side(p.height, level);
      for (uint32_t y = p.atlas_y; y < uint32_t(p.atlas_y) + h; ++y) {
        for (uint32_t x = p.atlas_x; x < uint32_t(p.atlas_x) + w; ++x) {
          for (uint32_t c = p.channel; c < uint32_t(p.channel) + p.channel_count; ++c)
            used[(size_t(y) * ar.width + x) * 4 + c] = 1;
        }
      }
    }
    uint8_t* px = copy + (v.atlas_pixels(a) - original);
    for (size_t k = 0; k < used.size(); ++k) {
      if (used[k]) continue;
      seed = seed * 1664525u + 1013904223u;
      px[k] = uint8_t(seed >> 24);
      ++written;
    }
  }
  return written;
}

}  // namespace lightpatch::test
