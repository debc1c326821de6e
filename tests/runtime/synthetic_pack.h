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

#include "lightpatch/moving_lights.h"
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
  // Magnified patches (pack_format.h, "Magnified patches"): each patch (but a bounce_covers_map
  // one) is of level 1 or 2 with this probability, its atlas rectangle shelf-packed against its
  // neighbours' like any other. 0 draws nothing more: packs without are unchanged.
  float magnified_probability = 0.0f;
  // Tints (PatchRecord::tint): each patch gets a random tint (any bytes) with this probability,
  // else 255, 255, 255, from a random stream of its own: the rest of the pack is the same.
  float tinted_probability = 0.0f;
  // Of the tinted patches with one channel and no destination channel, those that become 2-channel
  // patches (a second random tint, PatchRecord::tint_b), from the tints' stream.
  float two_channel_probability = 0.0f;
  // Edits the header and the patch records (not their count) before the table checksum is
  // computed: corrupt packs that only the record validation can refuse.
  std::function<void(pack::Header&, std::vector<pack::PatchRecord>&)> mutate;
  // Atlas content by texel (x, y) and channel, the same in every atlas (default: random bytes):
  // known values for closed-form expectations.
  std::function<uint8_t(uint32_t x, uint32_t y, uint32_t channel)> atlas_byte;

  // Light probes (pack_format.h, "Light probes"): a grid of probe_grid[0] x [1] x [2] points
  // (any 0: no probes) at probe_spacing metres from probe_origin, a point without a probe with
  // probe_hole_probability, plus named_probes named probes off the grid. Sets: the base (every
  // probe), each light's contribution, and the shadow and static-shadow sets of the map's groups
  // of those kinds; each non-base set reaches a probe with probe_reach_probability. Drawn after
  // everything else, so the rest of the pack is the same with and without probes.
  uint32_t probe_grid[3] = {0, 0, 0};
  float probe_origin[3] = {-1.0f, 0.25f, -2.0f};
  float probe_spacing = 0.5f;
  float probe_hole_probability = 0.1f;
  uint32_t named_probes = 2;
  float probe_reach_probability = 0.6f;
  // Reach of every probe in every direction (metres; default: random in [0.5, 1] * spacing, a
  // sixth of them shorter, 0.2 * spacing).
  float probe_reach = -1.0f;
  // Overrides an entry's SH (default: random in [-1, 1], the base's DC term in [1, 2]).
  std::function<void(const pack::ProbeRecord& probe, const pack::ProbeSetRecord& set,
                     float sh[pack::kProbeShCount * 3])>
      probe_sh;
  // Moving lights (pack_format.h, "Moving lights"): moving_lights lights flagged moving after the
  // `lights` ones (spots where moving_spot; named moving_<k>, colour (1, 0.8, 0.6), intensity
  // 2 + k, at (0.3 k, 1.5, 0.2) shining down), then `panes` pane lights, each with one
  // contribution group (random patches like the lights'). Pane k lies on the floor (y = 0, normal
  // +Y; even k) or the wall x = -2 (normal +X; odd k), its eye on a grid, 1 + k % 8 entry points
  // around it, radius 0.25, depth range 8, depth texels from pane_depth (default 65535: nothing).
  // The panes' authored colours are their factors for the authored poses (moving_lights.h).
  uint32_t moving_lights = 0;
  uint32_t panes = 0;
  bool moving_spot = false;
  float moving_range = 0.0f;
  std::function<uint16_t(uint32_t pane, uint32_t x, uint32_t y)> pane_depth;
  // The panes' contribution groups get probe sets too, drawn like a light's (moving lights get
  // none; off by default, so that the committed packs stay as they are).
  bool pane_probe_sets = false;
  // Refusal tests: a contribution group for moving light 0; a shadow group of pane 0 by object 0.
  bool moving_light_group = false;
  bool pane_shadow_group = false;
  // Edits the light, moving-light and pane records before the table checksum is computed.
  std::function<void(std::vector<pack::LightRecord>&, std::vector<pack::MovingLightRecord>&,
                     std::vector<pack::PaneRecord>&)>
      mutate_moving;
  // Leaves this section type out of the index (0: none), for refusal tests.
  uint32_t drop_section = 0;
  // Edits the probe records before the table checksum is computed.
  std::function<void(std::vector<pack::ProbeRecord>&, pack::ProbeGridRecord&,
                     std::vector<uint32_t>& grid, std::vector<pack::ProbeSetRecord>&,
                     std::vector<pack::ProbeEntry>&)>
      mutate_probes;
};

// `o` with a probe grid of nx x ny x nz points and the seed.
inline SyntheticOptions with_probe_grid(SyntheticOptions o, uint32_t nx, uint32_t ny, uint32_t nz,
                                        uint32_t seed) {
  o.probe_grid[0] = nx;
  o.probe_grid[1] = ny;
  o.probe_grid[2] = nz;
  o.seed = seed;
  return o;
}

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
  // Tints draw from a stream of their own: the rest of the pack is the same with and without.
  std::mt19937 tint_rng(o.seed * 7919u + 17u);
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
  // Appends a name to the string section; where a record finds it.
  auto add_name = [&strings](const std::string& name, uint32_t* offset, uint32_t* length) {
    *offset = uint32_t(strings.size());
    *length = uint32_t(name.size());
    strings += name;
  };
  std::vector<LightRecord> lights;
  std::vector<ObjectRecord> objects;
  for (uint32_t l = 0; l < o.lights; ++l) {
    const std::string name = "light_" + std::to_string(l);
    LightRecord r{};
    add_name(name, &r.name_offset, &r.name_length);
    for (float& c : r.color) c = uniform(0.2f, 1.0f);
    r.intensity = uniform(0.5f, 4.0f) * o.intensity;
    r.type = kLightPoint;
    lights.push_back(r);
  }
  for (uint32_t i = 0; i < o.objects; ++i) {
    const std::string name = "object_" + std::to_string(i);
    ObjectRecord r{};
    add_name(name, &r.name_offset, &r.name_length);
    objects.push_back(r);
  }
  // Moving lights and panes after the others (no random draws: packs without them are unchanged).
  std::vector<MovingLightRecord> moving;
  std::vector<PaneRecord> panes;
  const uint32_t first_moving = o.lights, first_pane = o.lights + o.moving_lights;
  for (uint32_t k = 0; k < o.moving_lights; ++k) {
    const std::string name = "moving_" + std::to_string(k);
    LightRecord r{};
    add_name(name, &r.name_offset, &r.name_length);
    r.color[0] = 1.0f;
    r.color[1] = 0.8f;
    r.color[2] = 0.6f;
    r.intensity = 2.0f + float(k);
    r.type = o.moving_spot ? kLightSpot : kLightPoint;
    r.flags = kLightFlagMoving;
    lights.push_back(r);
    MovingLightRecord m{};
    m.light = first_moving + k;
    m.position[0] = 0.3f * float(k);
    m.position[1] = 1.5f;
    m.position[2] = 0.2f;
    m.direction[1] = -1.0f;
    m.range = o.moving_range;
    m.inner_cone = 0.3f;
    m.outer_cone = 0.7f;
    m.radius = 0.05f;
    moving.push_back(m);
  }
  for (uint32_t k = 0; k < o.panes; ++k) {
    PaneRecord p{};
    p.light = first_pane + k;
    const bool floor = k % 2 == 0;
    const float a = float(k % 5) * 0.8f - 1.6f, b = float(k / 5) * 0.8f - 1.0f;
    p.eye[0] = floor ? a : -2.0f;
    p.eye[1] = floor ? 0.0f : 0.5f + 0.3f * float(k % 3);
    p.eye[2] = b;
    p.normal[floor ? 1 : 0] = 1.0f;
    p.radius = 0.25f;
    p.depth_range = 8.0f;
    p.point_count = 1 + k % kMaxPanePoints;
    for (uint32_t i = 0; i < p.point_count; ++i) {
      PanePoint& pt = p.points[i];
      const float du = 0.3f * float(int(i % 3) - 1), dv = 0.3f * float(int(i / 3) - 1);
      pt.position[0] = p.eye[0] + (floor ? du : 0.0f);
      pt.position[1] = p.eye[1] + (floor ? 0.0f : du);
      pt.position[2] = p.eye[2] + dv;
      std::memcpy(pt.normal, p.normal, sizeof pt.normal);
    }
    for (uint32_t y = 0; y < kPaneDepthSize; ++y)
      for (uint32_t x = 0; x < kPaneDepthSize; ++x)
        p.depth[y * kPaneDepthSize + x] = o.pane_depth ? o.pane_depth(k, x, y) : 0xFFFFu;
    panes.push_back(p);
  }
  for (uint32_t k = 0; k < o.panes; ++k) {
    LightRecord r{};
    r.intensity = 1.0f;
    r.type = kLightPane;
    for (uint32_t m = 0; m < o.moving_lights; ++m) {  // the authored factor, as the runtime's
      const float w =
          pane_weight(moving[m], lights[first_moving + m].type, authored_pose(moving[m]), panes[k]);
      for (int c = 0; c < 3; ++c)
        r.color[c] += lights[first_moving + m].color[c] * lights[first_moving + m].intensity * w;
    }
    lights.push_back(r);
  }
  const uint32_t light_total = o.lights + o.moving_lights + o.panes;

  // Groups in sorted order: base, contributions, shadows, pairs.
  std::vector<GroupRecord> groups;
  auto add_group = [&](uint16_t kind, uint16_t light, uint16_t a, uint16_t b) {
    groups.push_back(GroupRecord{kind, light, a, b, 0, 0});
  };
  add_group(kGroupBase, kNone16, kNone16, kNone16);
  for (uint32_t l = 0; l < o.lights; ++l)
    add_group(kGroupContribution, uint16_t(l), kNone16, kNone16);
  if (o.moving_light_group && o.moving_lights > 0)
    add_group(kGroupContribution, uint16_t(first_moving), kNone16, kNone16);
  for (uint32_t k = 0; k < o.panes; ++k)
    add_group(kGroupContribution, uint16_t(first_pane + k), kNone16, kNone16);
  for (uint32_t l = 0; l < o.lights; ++l) {
    for (uint32_t a = 0; a < o.objects; ++a) {
      if (uniform(0, 1) < o.shadow_probability)
        add_group(kGroupShadow, uint16_t(l), uint16_t(a), kNone16);
    }
  }
  if (o.pane_shadow_group && o.panes > 0 && o.objects > 0)
    add_group(kGroupShadow, uint16_t(first_pane), 0, kNone16);
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
      uint32_t level = 0;
      if (o.magnified_probability > 0.0f && !(cover && k + 1 == groups[g].patch_count) &&
          uniform(0, 1) < o.magnified_probability)
        level = integer(1, 2);
      const uint32_t aw = patch_atlas_side(p.width, level);
      const uint32_t ah = patch_atlas_side(p.height, level);
      if (cx + aw > as) cx = 0, cy += shelf, shelf = 0;
      if (cy + ah > as) atlases.emplace_back(), cx = cy = shelf = 0;
      p.atlas = uint8_t(atlases.size() - 1);
      p.atlas_x = uint16_t(cx);
      p.atlas_y = uint16_t(cy);
      cx += aw;
      if (ah > shelf) shelf = ah;
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
      p.flags = uint8_t(p.flags | (level << kFlagLevelShift));
      p.tint[0] = p.tint[1] = p.tint[2] = 255;
      if (o.tinted_probability > 0.0f &&
          std::uniform_real_distribution<float>(0.0f, 1.0f)(tint_rng) < o.tinted_probability) {
        for (uint8_t& t : p.tint)
          t = uint8_t(std::uniform_int_distribution<uint32_t>(0, 255)(tint_rng));
        if (p.channel_count == 1 && patch_destination(p.flags) < 0 &&
            std::uniform_real_distribution<float>(0.0f, 1.0f)(tint_rng) <
                o.two_channel_probability) {
          p.channel_count = 2;
          p.channel = uint8_t(std::min<uint32_t>(p.channel, 2));
          for (uint8_t& t : p.tint_b)
            t = uint8_t(std::uniform_int_distribution<uint32_t>(0, 255)(tint_rng));
        }
      }
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

  // Light probes.
  std::vector<ProbeRecord> probes;
  ProbeGridRecord grid{};
  std::vector<uint32_t> grid_index;
  std::vector<ProbeSetRecord> sets;
  std::vector<ProbeEntry> entries;
  const bool with_probes = o.probe_grid[0] && o.probe_grid[1] && o.probe_grid[2];
  if (with_probes) {
    for (int a = 0; a < 3; ++a) {
      grid.origin[a] = o.probe_origin[a];
      grid.size[a] = o.probe_grid[a];
    }
    grid.spacing = o.probe_spacing;
    auto reach = [&](ProbeRecord& r) {
      for (float& v : r.reach) {
        v = o.probe_reach >= 0.0f         ? o.probe_reach
            : uniform(0, 1) < 1.0f / 6.0f ? 0.2f * o.probe_spacing
                                          : uniform(0.5f, 1.0f) * o.probe_spacing;
      }
    };
    for (uint32_t k = 0; k < o.probe_grid[2]; ++k)
      for (uint32_t j = 0; j < o.probe_grid[1]; ++j)
        for (uint32_t i = 0; i < o.probe_grid[0]; ++i) {
          if (uniform(0, 1) < o.probe_hole_probability) {
            grid_index.push_back(kNone32);
            continue;
          }
          ProbeRecord r{};
          const uint32_t ijk[3] = {i, j, k};
          for (int a = 0; a < 3; ++a) r.position[a] = o.probe_origin[a] + o.probe_spacing * ijk[a];
          reach(r);
          grid_index.push_back(uint32_t(probes.size()));
          probes.push_back(r);
        }
    for (uint32_t n = 0; n < o.named_probes; ++n) {
      ProbeRecord r{};
      for (int a = 0; a < 3; ++a)
        r.position[a] = o.probe_origin[a] + uniform(0.0f, float(o.probe_grid[a])) * o.probe_spacing;
      reach(r);
      add_name("probe_" + std::to_string(n), &r.name_offset, &r.name_length);
      probes.push_back(r);
    }
    // Sets in sorted order, from the map's groups (pair corrections have none).
    for (const GroupRecord& g : groups) {
      if (g.kind == kGroupPairCorrection) continue;
      const bool pane_set = o.pane_probe_sets && g.kind == kGroupContribution &&
                            g.light != kNone16 && g.light >= first_pane;
      // Moving lights: none; panes: only where asked.
      if (g.light != kNone16 && g.light >= o.lights && !pane_set) continue;
      ProbeSetRecord set{g.kind, g.light, g.object_a, g.object_b, uint32_t(entries.size()), 0};
      for (uint32_t p = 0; p < probes.size(); ++p) {
        if (g.kind != kGroupBase && uniform(0, 1) >= o.probe_reach_probability) continue;
        ProbeEntry e{};
        e.probe = p;
        for (float& v : e.sh) v = uniform(-1.0f, 1.0f);
        if (g.kind == kGroupBase) e.sh[0] = e.sh[1] = e.sh[2] = uniform(1.0f, 2.0f);
        if (o.probe_sh) o.probe_sh(probes[p], set, e.sh);
        entries.push_back(e);
      }
      set.entry_count = uint32_t(entries.size()) - set.first_entry;
      if (set.entry_count > 0) sets.push_back(set);
    }
    if (o.mutate_probes) o.mutate_probes(probes, grid, grid_index, sets, entries);
  }

  // Layout: header, index, then 256-aligned sections.
  if (o.mutate_moving) o.mutate_moving(lights, moving, panes);
  const bool with_moving = o.moving_lights > 0;
  const uint32_t section_count =
      7 + (with_probes ? 4 : 0) + (with_moving ? 2 : 0) - (o.drop_section != 0 ? 1 : 0);
  auto align = [](uint64_t v) {
    return (v + kSectionAlignment - 1) / kSectionAlignment * kSectionAlignment;
  };
  uint64_t cursor = align(sizeof(Header) + section_count * sizeof(SectionEntry));
  std::vector<SectionEntry> index;
  constexpr uint64_t kDropped = ~uint64_t(0);  // a dropped section's offset: nothing written
  auto place = [&](uint32_t type, uint64_t length) {
    if (type == o.drop_section) return kDropped;
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
  uint64_t probes_at = 0, grid_at = 0, sets_at = 0, entries_at = 0;
  if (with_probes) {
    probes_at = place(kSectionProbes, probes.size() * sizeof(ProbeRecord));
    grid_at = place(kSectionProbeGrid, sizeof(ProbeGridRecord) + grid_index.size() * 4);
    sets_at = place(kSectionProbeSets, sets.size() * sizeof(ProbeSetRecord));
    entries_at = place(kSectionProbeEntries, entries.size() * sizeof(ProbeEntry));
  }
  uint64_t moving_at = 0, panes_at = 0;
  if (with_moving) {
    moving_at = place(kSectionMovingLights, moving.size() * sizeof(MovingLightRecord));
    panes_at = place(kSectionPanes, panes.size() * sizeof(PaneRecord));
  }
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
  h.light_count = light_total;
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
    if (n && at < cursor) std::memcpy(b + at, src, n);
  };
  put(lights_at, lights.data(), lights.size() * sizeof(LightRecord));
  put(objects_at, objects.data(), objects.size() * sizeof(ObjectRecord));
  put(groups_at, groups.data(), groups.size() * sizeof(GroupRecord));
  put(patches_at, patches.data(), patches.size() * sizeof(PatchRecord));
  put(atlases_at, atlas_records.data(), atlas_records.size() * sizeof(AtlasRecord));
  for (size_t a = 0; a < atlases.size(); ++a)
    put(data_at + a * atlas_bytes, atlases[a].data(), atlases[a].size());
  put(strings_at, strings.data(), strings.size());
  if (with_probes) {
    put(probes_at, probes.data(), probes.size() * sizeof(ProbeRecord));
    if (grid_at != kDropped) {
      put(grid_at, &grid, sizeof grid);
      put(grid_at + sizeof grid, grid_index.data(), grid_index.size() * 4);
    }
    put(sets_at, sets.data(), sets.size() * sizeof(ProbeSetRecord));
    put(entries_at, entries.data(), entries.size() * sizeof(ProbeEntry));
  }
  if (with_moving) {
    put(moving_at, moving.data(), moving.size() * sizeof(MovingLightRecord));
    put(panes_at, panes.data(), panes.size() * sizeof(PaneRecord));
  }
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
