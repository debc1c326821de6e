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

}  // namespace lightpatch::test
