// Random but valid packs for runtime tests, written byte by byte per pack_format.h (no cooker
// needed, so the runtime's tests also run cross-compiled). Deterministic for a seed.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "lightpatch/pack_format.h"
#include "lightpatch/pack_view.h"

namespace lightpatch::testing {

struct SyntheticOptions {
  uint32_t width = 48, height = 40;  // light map
  uint32_t lights = 3, objects = 3;
  uint32_t atlas_size = 64;
  uint32_t max_patch = 10;         // patch side in texels
  uint32_t patches_per_group = 4;  // up to
  float shadow_probability = 0.6f;
  float pair_probability = 0.4f;
  float static_shadow_probability = 0.5f;  // an object shadowing the static lights
  float intensity = 1.0f;  // multiplies the authored intensities (0.5..4); 1e5: sunlight
  uint32_t seed = 1;
  // An indirect map at 1/indirect_scale of the light map per axis (0: none; 2, 4 or 8 dividing
  // width and height): each group also gets 0..indirect_patches_per_group patches into it (after
  // its light-map ones), of sides up to max_patch indirect texels (at most the map's).
  uint32_t indirect_scale = 0;
  uint32_t indirect_patches_per_group = 3;
  // Bounce light that covers the whole room: every contribution group gets one more patch that
  // covers its whole indirect map (or, without one, the whole light map). For cost comparisons.
  bool bounce_covers_map = false;
  // Edits the header and the patch records (not their count) before the table checksum is
  // computed: corrupt packs that only the record validation can refuse.
  std::function<void(pack::Header&, std::vector<pack::PatchRecord>&)> mutate;
  // Atlas content by texel (x, y) and channel, the same in every atlas (default: random bytes):
  // known values for closed-form expectations.
  std::function<uint8_t(uint32_t x, uint32_t y, uint32_t channel)> atlas_byte;
};

// Pack bytes in 8-byte aligned storage.
struct SyntheticPack {
  std::vector<uint64_t> storage;
  uint64_t size = 0;
  const void* data() const { return storage.data(); }
  bool open(PackView* view, Error* error) const {
    return PackView::open(storage.data(), size, view, error) == Status::kOk;
  }
};

inline SyntheticPack make_synthetic_pack(const SyntheticOptions& o) {
  using namespace pack;
  std::mt19937 rng(o.seed);
  // The same bytes on every target (the golden pack is checked under qemu too): an integer draw
  // whose product with b - a is exact in double, so that no fused multiply-add can change it.
  auto uniform = [&](float a, float b) {
    const uint32_t k = std::uniform_int_distribution<uint32_t>(0, 1u << 20)(rng);
    return float(double(a) + double(b - a) * (double(k) / 1048576.0));
  };
  auto integer = [&](uint32_t a, uint32_t b) {
    return std::uniform_int_distribution<uint32_t>(a, b)(rng);
  };
  std::string strings;
  std::vector<LightRecord> lights;
  std::vector<ObjectRecord> objects;
  for (uint32_t l = 0; l < o.lights; ++l) {
    const std::string name = "light_" + std::to_string(l);
    LightRecord r{};
    r.name_offset = uint32_t(strings.size());
    r.name_length = uint32_t(name.size());
    strings += name;
    for (float& c : r.color) c = uniform(0.2f, 1.0f);
    r.intensity = uniform(0.5f, 4.0f) * o.intensity;
    r.type = kLightPoint;
    lights.push_back(r);
  }
  for (uint32_t i = 0; i < o.objects; ++i) {
    const std::string name = "object_" + std::to_string(i);
    ObjectRecord r{};
    r.name_offset = uint32_t(strings.size());
    r.name_length = uint32_t(name.size());
    strings += name;
    objects.push_back(r);
  }
  // Groups in sorted order: base, contributions, shadows, pairs.
  std::vector<GroupRecord> groups;
  auto add_group = [&](uint16_t kind, uint16_t light, uint16_t a, uint16_t b) {
    groups.push_back(GroupRecord{kind, light, a, b, 0, 0});
  };
  add_group(kGroupBase, kNone16, kNone16, kNone16);
  for (uint32_t l = 0; l < o.lights; ++l)
    add_group(kGroupContribution, uint16_t(l), kNone16, kNone16);
  for (uint32_t l = 0; l < o.lights; ++l) {
    for (uint32_t a = 0; a < o.objects; ++a) {
      if (uniform(0, 1) < o.shadow_probability)
        add_group(kGroupShadow, uint16_t(l), uint16_t(a), kNone16);
    }
  }
  for (uint32_t l = 0; l < o.lights; ++l) {
    for (uint32_t a = 0; a < o.objects; ++a) {
      for (uint32_t b = a + 1; b < o.objects; ++b) {
        if (uniform(0, 1) < o.pair_probability) {
          add_group(kGroupPairCorrection, uint16_t(l), uint16_t(a), uint16_t(b));
        }
      }
    }
  }
  for (uint32_t a = 0; a < o.objects; ++a) {
    if (uniform(0, 1) < o.static_shadow_probability)
      add_group(kGroupStaticShadow, kNone16, uint16_t(a), kNone16);
  }
  // Patches, shelf-packed into as many atlases as needed (random bytes in all channels).
  std::vector<PatchRecord> patches;
  std::vector<std::vector<uint8_t>> atlases(1);
  const uint32_t as = o.atlas_size;
  uint32_t cx = 0, cy = 0, shelf = 0;
  const uint32_t iw = o.indirect_scale ? o.width / o.indirect_scale : 0;
  const uint32_t ih = o.indirect_scale ? o.height / o.indirect_scale : 0;
  for (size_t g = 0; g < groups.size(); ++g) {
    groups[g].first_patch = uint32_t(patches.size());
    const uint32_t n = integer(1, o.patches_per_group);
    const uint32_t m = o.indirect_scale ? integer(0, o.indirect_patches_per_group) : 0;
    const bool cover = o.bounce_covers_map && groups[g].kind == kGroupContribution;
    groups[g].patch_count = n + m + (cover ? 1 : 0);
    for (uint32_t k = 0; k < groups[g].patch_count; ++k) {
      PatchRecord p{};
      const bool coarse = k >= n && o.indirect_scale != 0;
      const uint32_t map_w = coarse ? iw : o.width, map_h = coarse ? ih : o.height;
      if (cover && k + 1 == groups[g].patch_count) {
        p.width = uint16_t(map_w);
        p.height = uint16_t(map_h);
      } else {
        p.width = uint16_t(integer(1, std::min(o.max_patch, map_w)));
        p.height = uint16_t(integer(1, std::min(o.max_patch, map_h)));
      }
      if (coarse) p.target = kTargetIndirectMap;
      if (cx + p.width > as) cx = 0, cy += shelf, shelf = 0;
      if (cy + p.height > as) atlases.emplace_back(), cx = cy = shelf = 0;
      p.atlas = uint8_t(atlases.size() - 1);
      p.atlas_x = uint16_t(cx);
      p.atlas_y = uint16_t(cy);
      cx += p.width;
      if (p.height > shelf) shelf = p.height;
      p.dest_x = uint16_t(integer(0, map_w - p.width));
      p.dest_y = uint16_t(integer(0, map_h - p.height));
      p.channel_count = uniform(0, 1) < 0.3f ? 3 : 1;
      p.channel = uint8_t(integer(0, p.channel_count == 3 ? 1 : 3));
      p.encoding = uniform(0, 1) < 0.5f ? kEncodingSquare : kEncodingLinear;
      p.scale = uniform(0.05f, groups[g].kind == kGroupBase ? 2.0f : 1.0f);
      p.flags = (group_subtracts(groups[g].kind) && uniform(0, 1) < 0.2f) ? kFlagNegative : 0;
      // A third of the 1-channel patches draw into one map channel only.
      if (p.channel_count == 1 && uniform(0, 1) < 0.33f)
        p.flags = uint8_t(p.flags | (integer(1, 3) << kFlagDestinationShift));
      p.group = uint16_t(g);
      patches.push_back(p);
    }
  }
  for (auto& a : atlases) {
    a.resize(size_t(as) * as * 4);
    for (size_t i = 0; i < a.size(); ++i) {
      a[i] = o.atlas_byte
                 ? o.atlas_byte(uint32_t(i / 4 % as), uint32_t(i / 4 / as), uint32_t(i % 4))
                 : uint8_t(integer(0, 255));
    }
  }

  // Layout: header, index, then 256-aligned sections.
  const uint32_t section_count = 7;
  auto align = [](uint64_t v) {
    return (v + kSectionAlignment - 1) / kSectionAlignment * kSectionAlignment;
  };
  uint64_t cursor = align(sizeof(Header) + section_count * sizeof(SectionEntry));
  std::vector<SectionEntry> index;
  auto place = [&](uint32_t type, uint64_t length) {
    index.push_back(SectionEntry{type, 0, cursor, length});
    cursor = align(cursor + length);
    return index.back().offset;
  };
  const uint64_t lights_at = place(kSectionLights, lights.size() * sizeof(LightRecord));
  const uint64_t objects_at = place(kSectionObjects, objects.size() * sizeof(ObjectRecord));
  const uint64_t groups_at = place(kSectionGroups, groups.size() * sizeof(GroupRecord));
  const uint64_t patches_at = place(kSectionPatches, patches.size() * sizeof(PatchRecord));
  const uint64_t atlases_at = place(kSectionAtlases, atlases.size() * sizeof(AtlasRecord));
  const uint64_t atlas_bytes = align(uint64_t(as) * as * 4);
  const uint64_t data_at = place(kSectionAtlasData, atlas_bytes * atlases.size());
  const uint64_t strings_at = place(kSectionStrings, strings.size());
  std::vector<AtlasRecord> atlas_records;
  for (size_t a = 0; a < atlases.size(); ++a) {
    atlas_records.push_back(AtlasRecord{as, as, data_at + a * atlas_bytes});
  }

  Header h{};
  h.magic = kMagic;
  h.version = kVersion;
  h.file_size = cursor;
  h.section_count = section_count;
  h.lightmap_width = o.width;
  h.lightmap_height = o.height;
  h.light_count = o.lights;
  h.object_count = o.objects;
  h.group_count = uint32_t(groups.size());
  h.patch_count = uint32_t(patches.size());
  h.atlas_count = uint32_t(atlases.size());
  h.indirect_scale = o.indirect_scale;
  if (o.mutate) o.mutate(h, patches);

  SyntheticPack out;
  out.size = cursor;
  out.storage.assign((cursor + 7) / 8, 0);
  uint8_t* b = reinterpret_cast<uint8_t*>(out.storage.data());
  auto put = [&](uint64_t at, const void* src, size_t n) {
    if (n) std::memcpy(b + at, src, n);
  };
  put(lights_at, lights.data(), lights.size() * sizeof(LightRecord));
  put(objects_at, objects.data(), objects.size() * sizeof(ObjectRecord));
  put(groups_at, groups.data(), groups.size() * sizeof(GroupRecord));
  put(patches_at, patches.data(), patches.size() * sizeof(PatchRecord));
  put(atlases_at, atlas_records.data(), atlas_records.size() * sizeof(AtlasRecord));
  for (size_t a = 0; a < atlases.size(); ++a)
    put(data_at + a * atlas_bytes, atlases[a].data(), atlases[a].size());
  put(strings_at, strings.data(), strings.size());
  put(sizeof(Header), index.data(), index.size() * sizeof(SectionEntry));

  uint32_t crc = crc32(b + sizeof(Header), index.size() * sizeof(SectionEntry));
  for (const SectionEntry& e : index) {
    if (e.type != kSectionAtlasData) crc = crc32(b + e.offset, e.length, crc);
  }
  h.table_checksum = crc;
  put(0, &h, sizeof h);
  return out;
}

}  // namespace lightpatch::testing
