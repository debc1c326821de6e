// PackView::open: validation of a whole pack before anything is used (pack_format.h). Every
// offset and length is checked in 64-bit arithmetic written so that no sum can overflow.
#include "lightpatch/pack_view.h"

#include "lightpatch/utf8.h"

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <initializer_list>

namespace lightpatch {

using namespace pack;

bool Name::equals(const char* s, uint32_t n) const {
  return n == length && (n == 0 || std::memcmp(data, s, n) == 0);
}

namespace {

struct Section {
  bool present = false;
  uint64_t offset = 0;
  uint64_t length = 0;
};

const char* section_name(uint32_t type) {
  switch (type) {
    case kSectionLights:
      return "lights";
    case kSectionObjects:
      return "objects";
    case kSectionGroups:
      return "groups";
    case kSectionPatches:
      return "patches";
    case kSectionAtlases:
      return "atlases";
    case kSectionAtlasData:
      return "atlas data";
    case kSectionStrings:
      return "strings";
    case kSectionMeshes:
      return "meshes";
    case kSectionMeshData:
      return "mesh data";
    case kSectionProbes:
      return "probes";
    case kSectionProbeGrid:
      return "probe grid";
    case kSectionProbeSets:
      return "probe sets";
    case kSectionProbeEntries:
      return "probe entries";
    case kSectionMovingLights:
      return "moving lights";
    case kSectionPanes:
      return "panes";
  }
  return "unknown";
}

const char* group_kind_name(uint32_t kind) {
  switch (kind) {
    case kGroupBase:
      return "base";
    case kGroupContribution:
      return "contribution";
    case kGroupShadow:
      return "shadow";
    case kGroupPairCorrection:
      return "pair correction";
    case kGroupStaticShadow:
      return "static shadow";
  }
  return "unknown";
}

// [offset, offset + length) lies inside [begin, begin + size), without overflow.
bool range_inside(uint64_t offset, uint64_t length, uint64_t begin, uint64_t size) {
  if (offset < begin) return false;
  const uint64_t rel = offset - begin;
  return rel <= size && length <= size - rel;
}

bool atlas_side_ok(uint32_t v) {
  return v >= kAtlasAlign && v <= kMaxAtlasSize && v % kAtlasAlign == 0;
}

bool finite_non_negative(float v) {
  return std::isfinite(v) && v >= 0.0f;
}

// Lexicographic key of a group (or probe set: the same owner fields) for the sort/uniqueness
// check.
template <typename Owner>
uint64_t group_key(const Owner& g) {
  return (uint64_t(g.kind) << 48) | (uint64_t(g.light) << 32) | (uint64_t(g.object_a) << 16) |
         uint64_t(g.object_b);
}

// Whether an owner's fields are in range and kNone16 exactly where its kind says (GroupKind).
// The kind is known (<= kGroupKindMax).
bool owner_ok(uint16_t kind, uint16_t light, uint16_t object_a, uint16_t object_b,
              const Header& h) {
  const bool light_ok = light < h.light_count;
  const bool a_ok = object_a < h.object_count;
  const bool b_ok = object_b < h.object_count;
  switch (kind) {
    case kGroupBase:
      return light == kNone16 && object_a == kNone16 && object_b == kNone16;
    case kGroupContribution:
      return light_ok && object_a == kNone16 && object_b == kNone16;
    case kGroupShadow:
      return light_ok && a_ok && object_b == kNone16;
    case kGroupPairCorrection:
      return light_ok && a_ok && b_ok && object_a < object_b;
    case kGroupStaticShadow:
      return light == kNone16 && a_ok && object_b == kNone16;
  }
  return false;
}

// Whether a group or probe set of this kind names a light (contribution, shadow, pair).
bool group_has_light_owner(uint16_t kind) {
  return kind == kGroupContribution || kind == kGroupShadow || kind == kGroupPairCorrection;
}

bool all_finite(const float* v, uint32_t n) {
  for (uint32_t i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) return false;
  }
  return true;
}

// What a successful validation hands to PackView::open.
struct Parsed {
  const Header* header = nullptr;
  const LightRecord* lights = nullptr;
  const ObjectRecord* objects = nullptr;
  const GroupRecord* groups = nullptr;
  const PatchRecord* patches = nullptr;
  const AtlasRecord* atlases = nullptr;
  const MeshRecord* meshes = nullptr;
  const char* strings = nullptr;
  uint64_t strings_length = 0;
  const ProbeRecord* probes = nullptr;
  const ProbeGridRecord* probe_grid = nullptr;
  const ProbeSetRecord* probe_sets = nullptr;
  const ProbeEntry* probe_entries = nullptr;
  uint32_t probe_count = 0;
  uint32_t probe_grid_points = 0;
  uint32_t probe_set_count = 0;
  uint32_t probe_entry_count = 0;
  uint64_t probe_bytes = 0;
  const MovingLightRecord* moving_lights = nullptr;
  const PaneRecord* panes = nullptr;
  uint32_t moving_light_count = 0;
  uint32_t pane_count = 0;
};

class Validator {
 public:
  Validator(const uint8_t* bytes, uint64_t size, const RecomposeLimits& limits, Error* error)
      : b_(bytes), size_(size), limits_(limits), error_(error) {}

  Status run(Parsed* out);

 private:
  Status fail(Status s, const char* fmt, ...) __attribute__((format(printf, 3, 4)));
  Status check_name(const char* what, uint32_t index, uint32_t offset, uint32_t length,
                    bool allow_empty);
  Status check_limits(const Header& h);
  Status check_probe_sections(Parsed* out);
  Status check_probes(const Header& h, Parsed* out);
  Status check_moving_sections(Parsed* out);
  Status check_moving(const Header& h, const LightRecord* lights, const GroupRecord* groups,
                      Parsed* out);
  template <typename T>
  const T* at(uint64_t offset) const {
    return reinterpret_cast<const T*>(b_ + offset);
  }

  const uint8_t* b_;
  uint64_t size_;
  const RecomposeLimits& limits_;
  Error* error_;
  Section sections_[kSectionTypeMax + 1];
};

Status Validator::fail(Status s, const char* fmt, ...) {
  if (error_ != nullptr) {
    error_->status = s;
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(error_->message, sizeof(error_->message), fmt, args);
    va_end(args);
  }
  return s;
}

Status Validator::check_name(const char* what, uint32_t index, uint32_t offset, uint32_t length,
                             bool allow_empty) {
  if (length == 0 && !allow_empty) {
    return fail(Status::kCorrupt, "%s %u: empty name", what, index);
  }
  if (!range_inside(offset, length, 0, sections_[kSectionStrings].length)) {
    return fail(Status::kCorrupt, "%s %u: name %u+%u exceeds the string section (%llu bytes)", what,
                index, offset, length,
                static_cast<unsigned long long>(sections_[kSectionStrings].length));
  }
  // Names are printed, matched against state files and written to JSON by the tools.
  if (!utf8_valid(at<char>(sections_[kSectionStrings].offset) + offset, length)) {
    return fail(Status::kCorrupt, "%s %u: name is not valid UTF-8", what, index);
  }
  return Status::kOk;
}

Status Validator::check_limits(const Header& h) {
  const uint64_t texels = uint64_t(h.lightmap_width) * h.lightmap_height;
  if (texels > limits_.max_lightmap_texels) {
    return fail(Status::kOverLimit,
                "light map %ux%u is %llu texels, over the limit of %llu (max_lightmap_texels)",
                h.lightmap_width, h.lightmap_height, static_cast<unsigned long long>(texels),
                static_cast<unsigned long long>(limits_.max_lightmap_texels));
  }
  return Status::kOk;
}

// The probe sections' presence and sizes (before the checksum, like the other sections' sizes):
// all of probes, sets and entries or none, the grid only with them, whole records, the grid's
// point count from its record.
Status Validator::check_probe_sections(Parsed* out) {
  const Section& probes = sections_[kSectionProbes];
  const Section& grid = sections_[kSectionProbeGrid];
  const Section& sets = sections_[kSectionProbeSets];
  const Section& entries = sections_[kSectionProbeEntries];
  if (!probes.present) {
    for (uint32_t t : {kSectionProbeGrid, kSectionProbeSets, kSectionProbeEntries}) {
      if (sections_[t].present)
        return fail(Status::kCorrupt, "%s section without a probes section", section_name(t));
    }
    return Status::kOk;
  }
  for (uint32_t t : {kSectionProbeSets, kSectionProbeEntries}) {
    if (!sections_[t].present)
      return fail(Status::kCorrupt, "probes section without a %s section", section_name(t));
  }
  struct Sized {
    uint32_t type;
    uint64_t record;
  };
  const Sized sized[] = {{kSectionProbes, sizeof(ProbeRecord)},
                         {kSectionProbeSets, sizeof(ProbeSetRecord)},
                         {kSectionProbeEntries, sizeof(ProbeEntry)}};
  for (const Sized& z : sized) {
    if (sections_[z.type].length % z.record != 0) {
      return fail(Status::kCorrupt,
                  "%s section: %llu bytes, not a whole number of %llu-byte records",
                  section_name(z.type), static_cast<unsigned long long>(sections_[z.type].length),
                  static_cast<unsigned long long>(z.record));
    }
  }
  const uint64_t probe_count = probes.length / sizeof(ProbeRecord);
  if (probe_count == 0) return fail(Status::kCorrupt, "probes section: no probes");
  if (probe_count > kMaxProbes) {
    return fail(Status::kCorrupt, "probes section: %llu probes, over the limit of %u",
                static_cast<unsigned long long>(probe_count), kMaxProbes);
  }
  // Sets and entries are bounded by the file's size (and so fit 32 bits: a set is 16 bytes, an
  // entry 112, and the file is addressed by 64-bit offsets, so check).
  const uint64_t set_count = sets.length / sizeof(ProbeSetRecord);
  const uint64_t entry_count = entries.length / sizeof(ProbeEntry);
  if (set_count > 0xFFFFFFFFu || entry_count > 0xFFFFFFFFu) {
    return fail(Status::kCorrupt, "probe sets or entries: more than 2^32 records");
  }
  out->probe_count = uint32_t(probe_count);
  out->probe_set_count = uint32_t(set_count);
  out->probe_entry_count = uint32_t(entry_count);
  out->probe_bytes = probes.length + sets.length + entries.length;
  if (grid.present) {
    if (grid.length < sizeof(ProbeGridRecord)) {
      return fail(Status::kCorrupt, "probe grid section: %llu bytes, shorter than its record",
                  static_cast<unsigned long long>(grid.length));
    }
    const ProbeGridRecord& g = *at<ProbeGridRecord>(grid.offset);
    // The product grows one factor at a time and stops at the limit: no overflow (each factor
    // is 32 bits, the running product at most 2^22).
    uint64_t points = 1;
    for (int a = 0; a < 3; ++a) {
      if (g.size[a] == 0)
        return fail(Status::kCorrupt, "probe grid: size %ux%ux%u has an empty axis", g.size[0],
                    g.size[1], g.size[2]);
      points *= g.size[a];
      if (points > kMaxProbeGridPoints) {
        return fail(Status::kCorrupt, "probe grid: size %ux%ux%u over the limit of %u points",
                    g.size[0], g.size[1], g.size[2], kMaxProbeGridPoints);
      }
    }
    if (grid.length != sizeof(ProbeGridRecord) + points * 4) {
      return fail(Status::kCorrupt,
                  "probe grid section: %llu bytes, expected %llu for %llu grid points",
                  static_cast<unsigned long long>(grid.length),
                  static_cast<unsigned long long>(sizeof(ProbeGridRecord) + points * 4),
                  static_cast<unsigned long long>(points));
    }
    out->probe_grid_points = uint32_t(points);
    out->probe_bytes += grid.length;
  }
  return Status::kOk;
}

// The probe records (after the checksum; sizes checked by check_probe_sections).
Status Validator::check_probes(const Header& h, Parsed* out) {
  if (!sections_[kSectionProbes].present) return Status::kOk;
  const uint32_t n = out->probe_count;
  const ProbeRecord* probes = at<ProbeRecord>(sections_[kSectionProbes].offset);
  for (uint32_t i = 0; i < n; ++i) {
    const ProbeRecord& p = probes[i];
    if (!all_finite(p.position, 3))
      return fail(Status::kCorrupt, "probe %u: position is not finite", i);
    for (int k = 0; k < 6; ++k) {
      if (!finite_non_negative(p.reach[k]))
        return fail(Status::kCorrupt, "probe %u: reach %d is not finite and >= 0", i, k);
    }
    if (p.name_length == 0 && p.name_offset != 0)
      return fail(Status::kCorrupt, "probe %u: unnamed with a name offset %u", i, p.name_offset);
    if (Status s = check_name("probe", i, p.name_offset, p.name_length, true); s != Status::kOk)
      return s;
    if (p.reserved != 0) return fail(Status::kCorrupt, "probe %u: reserved field not zero", i);
  }
  const ProbeGridRecord* grid = nullptr;
  if (sections_[kSectionProbeGrid].present) {
    grid = at<ProbeGridRecord>(sections_[kSectionProbeGrid].offset);
    if (!all_finite(grid->origin, 3))
      return fail(Status::kCorrupt, "probe grid: origin is not finite");
    if (!std::isfinite(grid->spacing) || !(grid->spacing > 0.0f))
      return fail(Status::kCorrupt, "probe grid: spacing is not finite and > 0");
    if (grid->reserved != 0) return fail(Status::kCorrupt, "probe grid: reserved field not zero");
    const uint32_t* index = at<uint32_t>(sections_[kSectionProbeGrid].offset + sizeof(*grid));
    for (uint32_t k = 0; k < out->probe_grid_points; ++k) {
      if (index[k] != kNone32 && index[k] >= n) {
        return fail(Status::kCorrupt, "probe grid: point %u names probe %u of %u", k, index[k], n);
      }
    }
  }
  const ProbeSetRecord* sets = at<ProbeSetRecord>(sections_[kSectionProbeSets].offset);
  const ProbeEntry* entries = at<ProbeEntry>(sections_[kSectionProbeEntries].offset);
  uint32_t expected_first = 0;
  for (uint32_t i = 0; i < out->probe_set_count; ++i) {
    const ProbeSetRecord& s = sets[i];
    if (s.kind > kGroupKindMax || s.kind == kGroupPairCorrection) {
      return fail(Status::kCorrupt, "probe set %u: kind %u (%s) has no probe sets", i, s.kind,
                  group_kind_name(s.kind));
    }
    if (!owner_ok(s.kind, s.light, s.object_a, s.object_b, h)) {
      return fail(Status::kCorrupt, "probe set %u (%s): owner light %u objects %u,%u invalid", i,
                  group_kind_name(s.kind), s.light, s.object_a, s.object_b);
    }
    if (i > 0 && group_key(sets[i - 1]) >= group_key(s)) {
      return fail(Status::kCorrupt,
                  "probe set %u: not sorted after probe set %u (or a duplicate owner)", i, i - 1);
    }
    if (s.entry_count == 0) return fail(Status::kCorrupt, "probe set %u: no entries", i);
    if (s.first_entry != expected_first) {
      return fail(Status::kCorrupt,
                  "probe set %u: first entry %u, expected %u (sets must be contiguous)", i,
                  s.first_entry, expected_first);
    }
    if (!range_inside(s.first_entry, s.entry_count, 0, out->probe_entry_count)) {
      return fail(Status::kCorrupt, "probe set %u: entries %u+%u exceed the %u entries", i,
                  s.first_entry, s.entry_count, out->probe_entry_count);
    }
    for (uint32_t k = s.first_entry; k < s.first_entry + s.entry_count; ++k) {
      const ProbeEntry& e = entries[k];
      if (e.probe >= n) {
        return fail(Status::kCorrupt, "probe entry %u: probe %u out of range (%u probes)", k,
                    e.probe, n);
      }
      if (k > s.first_entry && entries[k - 1].probe >= e.probe) {
        return fail(Status::kCorrupt, "probe entry %u: probe %u not after probe %u in probe set %u",
                    k, e.probe, entries[k - 1].probe, i);
      }
      if (!all_finite(e.sh, kProbeShCount * 3))
        return fail(Status::kCorrupt, "probe entry %u: SH coefficient not finite", k);
    }
    expected_first = s.first_entry + s.entry_count;
  }
  if (expected_first != out->probe_entry_count) {
    return fail(Status::kCorrupt, "probe sets cover %u of %u probe entries", expected_first,
                out->probe_entry_count);
  }
  out->probes = probes;
  out->probe_grid = grid;
  out->probe_sets = sets;
  out->probe_entries = entries;
  return Status::kOk;
}

// Whether v is a finite unit vector within 1e-3 (double: no overflow for any finite float).
bool unit_vector(const float v[3]) {
  if (!all_finite(v, 3)) return false;
  const double len = std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]);
  return std::fabs(len - 1.0) <= 1e-3;
}

// The moving-light sections' presence and sizes (before the checksum): both or neither, whole
// records, counts within the format's limits.
Status Validator::check_moving_sections(Parsed* out) {
  const Section& moving = sections_[kSectionMovingLights];
  const Section& panes = sections_[kSectionPanes];
  if (!moving.present) {
    if (panes.present)
      return fail(Status::kCorrupt, "panes section without a moving lights section");
    return Status::kOk;
  }
  if (!panes.present)
    return fail(Status::kCorrupt, "moving lights section without a panes section");
  if (moving.length % sizeof(MovingLightRecord) != 0 || panes.length % sizeof(PaneRecord) != 0) {
    return fail(Status::kCorrupt,
                "moving lights or panes section: %llu and %llu bytes, not whole records of %llu "
                "and %llu bytes",
                static_cast<unsigned long long>(moving.length),
                static_cast<unsigned long long>(panes.length),
                static_cast<unsigned long long>(sizeof(MovingLightRecord)),
                static_cast<unsigned long long>(sizeof(PaneRecord)));
  }
  const uint64_t moving_count = moving.length / sizeof(MovingLightRecord);
  const uint64_t pane_count = panes.length / sizeof(PaneRecord);
  if (moving_count == 0) return fail(Status::kCorrupt, "moving lights section: no records");
  // Each record names a distinct light (checked below), and lights are fewer than kNone16.
  if (moving_count >= kNone16) {
    return fail(Status::kCorrupt, "moving lights section: %llu records, more than lights can be",
                static_cast<unsigned long long>(moving_count));
  }
  if (pane_count > kMaxPanes) {
    return fail(Status::kCorrupt, "panes section: %llu panes, over the limit of %u",
                static_cast<unsigned long long>(pane_count), kMaxPanes);
  }
  out->moving_light_count = uint32_t(moving_count);
  out->pane_count = uint32_t(pane_count);
  return Status::kOk;
}

// The moving lights, their panes and the owners that may not have groups or probe sets (after
// the lights, groups and probes are checked).
Status Validator::check_moving(const Header& h, const LightRecord* lights,
                               const GroupRecord* groups, Parsed* out) {
  uint32_t flagged = 0, pane_lights = 0;
  for (uint32_t i = 0; i < h.light_count; ++i) {
    if (lights[i].flags & kLightFlagMoving) ++flagged;
    if (lights[i].type == kLightPane) ++pane_lights;
  }
  auto moving_light = [&](uint32_t l) {
    return l < h.light_count && (lights[l].flags & kLightFlagMoving) != 0;
  };
  auto pane_light = [&](uint32_t l) { return l < h.light_count && lights[l].type == kLightPane; };
  if (!sections_[kSectionMovingLights].present) {
    if (flagged > 0)
      return fail(Status::kCorrupt, "%u lights flagged moving but no moving lights section",
                  flagged);
    if (pane_lights > 0)
      return fail(Status::kCorrupt, "%u pane lights but no moving lights section", pane_lights);
  }
  // Moving lights draw nothing of their own; a pane only its bounce light (a contribution).
  for (uint32_t i = 0; i < h.group_count; ++i) {
    const GroupRecord& g = groups[i];
    if (!group_has_light_owner(g.kind)) continue;
    if (moving_light(g.light)) {
      return fail(Status::kCorrupt,
                  "group %u (%s): light %u moves and has no groups (its bounce light is its "
                  "panes')",
                  i, group_kind_name(g.kind), g.light);
    }
    if (pane_light(g.light) && g.kind != kGroupContribution) {
      return fail(Status::kCorrupt, "group %u (%s): pane light %u has only a contribution group", i,
                  group_kind_name(g.kind), g.light);
    }
  }
  if (out->probe_set_count > 0) {
    for (uint32_t i = 0; i < out->probe_set_count; ++i) {
      const ProbeSetRecord& s = out->probe_sets[i];
      if (moving_light(s.light)) {
        return fail(Status::kCorrupt,
                    "probe set %u (%s): light %u moves and has no probe sets (its bounce light "
                    "is its panes')",
                    i, group_kind_name(s.kind), s.light);
      }
      if (pane_light(s.light) && s.kind != kGroupContribution) {
        return fail(Status::kCorrupt,
                    "probe set %u (%s): pane light %u has only a contribution probe set", i,
                    group_kind_name(s.kind), s.light);
      }
    }
  }
  if (!sections_[kSectionMovingLights].present) return Status::kOk;
  const uint32_t nm = out->moving_light_count, np = out->pane_count;
  if (nm != flagged) {
    return fail(Status::kCorrupt, "%u moving light records for %u lights flagged moving", nm,
                flagged);
  }
  if (np != pane_lights) {
    return fail(Status::kCorrupt, "%u pane records for %u pane lights", np, pane_lights);
  }
  const MovingLightRecord* moving = at<MovingLightRecord>(sections_[kSectionMovingLights].offset);
  for (uint32_t k = 0; k < nm; ++k) {
    const MovingLightRecord& m = moving[k];
    // Strictly increasing and as many as the flagged lights: each flagged light exactly once.
    if (!moving_light(m.light)) {
      return fail(Status::kCorrupt, "moving light %u: light %u is not a light flagged moving", k,
                  m.light);
    }
    if (k > 0 && moving[k - 1].light >= m.light) {
      return fail(Status::kCorrupt,
                  "moving light %u: light %u not after light %u (sorted by light, each once)", k,
                  m.light, moving[k - 1].light);
    }
    if (!all_finite(m.position, 3))
      return fail(Status::kCorrupt, "moving light %u: position is not finite", k);
    if (!unit_vector(m.direction))
      return fail(Status::kCorrupt, "moving light %u: direction is not a unit vector", k);
    if (!finite_non_negative(m.range))
      return fail(Status::kCorrupt, "moving light %u: range is not finite and >= 0", k);
    if (!finite_non_negative(m.radius))
      return fail(Status::kCorrupt, "moving light %u: radius is not finite and >= 0", k);
    if (!std::isfinite(m.inner_cone) || !std::isfinite(m.outer_cone))
      return fail(Status::kCorrupt, "moving light %u: cone angles are not finite", k);
    // The cone of a spot (1.5707964: pi/2 rounded up to a float, as the importer accepts).
    if (lights[m.light].type == kLightSpot &&
        !(m.inner_cone >= 0.0f && m.inner_cone <= m.outer_cone && m.outer_cone > 0.0f &&
          m.outer_cone <= 1.5707964f)) {
      return fail(Status::kCorrupt,
                  "moving light %u: spot cone %g..%g needs 0 <= inner <= outer <= pi/2, outer > 0",
                  k, double(m.inner_cone), double(m.outer_cone));
    }
    if (m.reserved != 0)
      return fail(Status::kCorrupt, "moving light %u: reserved field not zero", k);
  }
  const PaneRecord* panes = at<PaneRecord>(sections_[kSectionPanes].offset);
  for (uint32_t k = 0; k < np; ++k) {
    const PaneRecord& p = panes[k];
    if (!pane_light(p.light))
      return fail(Status::kCorrupt, "pane %u: light %u is not a pane light", k, p.light);
    if (k > 0 && panes[k - 1].light >= p.light) {
      return fail(Status::kCorrupt,
                  "pane %u: light %u not after light %u (sorted by light, each once)", k, p.light,
                  panes[k - 1].light);
    }
    if (!all_finite(p.eye, 3)) return fail(Status::kCorrupt, "pane %u: eye is not finite", k);
    if (!unit_vector(p.normal))
      return fail(Status::kCorrupt, "pane %u: normal is not a unit vector", k);
    if (!std::isfinite(p.radius) || !(p.radius > 0.0f))
      return fail(Status::kCorrupt, "pane %u: radius is not finite and > 0", k);
    if (!std::isfinite(p.depth_range) || !(p.depth_range > 0.0f))
      return fail(Status::kCorrupt, "pane %u: depth range is not finite and > 0", k);
    if (p.point_count > kMaxPanePoints) {
      return fail(Status::kCorrupt, "pane %u: %u entry points (must be 0..%u)", k, p.point_count,
                  kMaxPanePoints);
    }
    // All panes or all anchors (pack_format.h, "Anchors"), the anchors on one lattice.
    if ((p.point_count == 0) != (panes[0].point_count == 0)) {
      return fail(Status::kCorrupt, "pane %u: %s among %s", k,
                  p.point_count == 0 ? "an anchor" : "a pane",
                  panes[0].point_count == 0 ? "anchors" : "panes");
    }
    if (p.point_count == 0) {
      if (p.normal[0] != 0.0f || p.normal[1] != 0.0f || p.normal[2] != 1.0f)
        return fail(Status::kCorrupt, "anchor %u: normal is not (0, 0, 1)", k);
      if (p.radius != panes[0].radius)
        return fail(Status::kCorrupt, "anchor %u: spacing differs from anchor 0's", k);
    }
    for (uint32_t i = 0; i < kMaxPanePoints; ++i) {
      const PanePoint& pt = p.points[i];
      if (i >= p.point_count) {
        static const PanePoint kZero{};
        if (std::memcmp(&pt, &kZero, sizeof pt) != 0)
          return fail(Status::kCorrupt, "pane %u: unused entry point %u not zero", k, i);
        continue;
      }
      if (!all_finite(pt.position, 3))
        return fail(Status::kCorrupt, "pane %u: entry point %u position is not finite", k, i);
      if (!unit_vector(pt.normal))
        return fail(Status::kCorrupt, "pane %u: entry point %u normal is not a unit vector", k, i);
    }
  }
  out->moving_lights = moving;
  out->panes = panes;
  return Status::kOk;
}

Status Validator::run(Parsed* out) {
  if (b_ == nullptr && size_ > 0) return fail(Status::kInvalidArgument, "null pack data");
  if (reinterpret_cast<uintptr_t>(b_) % 8 != 0) {
    return fail(Status::kInvalidArgument, "pack data is not 8-byte aligned");
  }
  if (size_ < sizeof(Header)) {
    return fail(Status::kTruncated, "file of %llu bytes is shorter than the 64-byte header",
                static_cast<unsigned long long>(size_));
  }
  const Header& h = *at<Header>(0);
  if (h.magic != kMagic) return fail(Status::kBadMagic, "bad magic: not a lightpatch pack");
  if (h.version != kVersion) {
    return fail(Status::kUnsupportedVersion,
                "format version %u is not supported (this reader: %u); cook the scene again",
                h.version, kVersion);
  }
  if (h.file_size != size_) {
    return fail(h.file_size > size_ ? Status::kTruncated : Status::kCorrupt,
                "header says %llu bytes but the file has %llu",
                static_cast<unsigned long long>(h.file_size),
                static_cast<unsigned long long>(size_));
  }
  if (h.flags != 0) return fail(Status::kCorrupt, "header: reserved fields not zero");
  if (h.lightmap_width == 0 || h.lightmap_height == 0 || h.lightmap_width > kMaxLightmapSize ||
      h.lightmap_height > kMaxLightmapSize) {
    return fail(Status::kCorrupt, "light-map size %ux%u out of range 1..%u", h.lightmap_width,
                h.lightmap_height, kMaxLightmapSize);
  }
  // The indirect map: 1/2, 1/4 or 1/8 of the light map per axis, a whole number of texels (so it
  // holds at most a quarter of the light map's texels: pack_view.h's memory limit).
  if (h.indirect_scale != 0) {
    if (h.indirect_scale != 2 && h.indirect_scale != 4 && h.indirect_scale != 8) {
      return fail(Status::kCorrupt, "header: indirect scale %u (must be 0, 2, 4 or 8)",
                  h.indirect_scale);
    }
    if (h.lightmap_width % h.indirect_scale != 0 || h.lightmap_height % h.indirect_scale != 0) {
      return fail(Status::kCorrupt,
                  "header: indirect scale %u does not divide the light-map size %ux%u",
                  h.indirect_scale, h.lightmap_width, h.lightmap_height);
    }
  }
  // Owner indices are 16-bit with 0xFFFF meaning none; the patch's group index is 16-bit; the
  // patch's atlas index is 8-bit.
  if (h.light_count >= kNone16)
    return fail(Status::kCorrupt, "too many lights (%u)", h.light_count);
  if (h.object_count >= kNone16) {
    return fail(Status::kCorrupt, "too many objects (%u)", h.object_count);
  }
  if (h.group_count > 0x10000u)
    return fail(Status::kCorrupt, "too many groups (%u)", h.group_count);
  if (h.atlas_count > 256u) return fail(Status::kCorrupt, "too many atlases (%u)", h.atlas_count);
  if (h.section_count == 0 || h.section_count > kSectionTypeMax) {
    return fail(Status::kCorrupt, "section count %u out of range 1..%u", h.section_count,
                kSectionTypeMax);
  }
  const uint64_t index_end = sizeof(Header) + uint64_t(h.section_count) * sizeof(SectionEntry);
  if (index_end > size_)
    return fail(Status::kTruncated, "section index ends past the end of the file");

  // Section index.
  const SectionEntry* entries = at<SectionEntry>(sizeof(Header));
  for (uint32_t i = 0; i < h.section_count; ++i) {
    const SectionEntry& e = entries[i];
    if (e.type == 0 || e.type > kSectionTypeMax) {
      return fail(Status::kCorrupt, "section %u: unknown type %u", i, e.type);
    }
    if (e.reserved != 0) return fail(Status::kCorrupt, "section %u: reserved field not zero", i);
    Section& s = sections_[e.type];
    if (s.present)
      return fail(Status::kCorrupt, "section %u: second %s section", i, section_name(e.type));
    if (e.offset % kSectionAlignment != 0) {
      return fail(Status::kCorrupt, "%s section: offset %llu not a multiple of %u",
                  section_name(e.type), static_cast<unsigned long long>(e.offset),
                  kSectionAlignment);
    }
    if (!range_inside(e.offset, e.length, index_end, size_ - index_end)) {
      return fail(e.offset < index_end ? Status::kCorrupt : Status::kTruncated,
                  "%s section: bytes %llu+%llu outside the file's %llu bytes after the index",
                  section_name(e.type), static_cast<unsigned long long>(e.offset),
                  static_cast<unsigned long long>(e.length),
                  static_cast<unsigned long long>(size_));
    }
    s.present = true;
    s.offset = e.offset;
    s.length = e.length;
  }
  for (uint32_t i = 0; i < h.section_count; ++i) {
    for (uint32_t j = i + 1; j < h.section_count; ++j) {
      const SectionEntry& a = entries[i];
      const SectionEntry& c = entries[j];
      if (a.length == 0 || c.length == 0) continue;
      // Both ranges are inside the file, so these sums cannot overflow.
      if (a.offset < c.offset + c.length && c.offset < a.offset + a.length) {
        return fail(Status::kCorrupt, "%s and %s sections overlap", section_name(a.type),
                    section_name(c.type));
      }
    }
  }
  const uint32_t required[] = {kSectionLights,  kSectionObjects,   kSectionGroups, kSectionPatches,
                               kSectionAtlases, kSectionAtlasData, kSectionStrings};
  for (uint32_t t : required) {
    if (!sections_[t].present)
      return fail(Status::kCorrupt, "required %s section missing", section_name(t));
  }
  if (h.mesh_count > 0 &&
      (!sections_[kSectionMeshes].present || !sections_[kSectionMeshData].present)) {
    return fail(Status::kCorrupt, "%u meshes but no mesh or mesh-data section", h.mesh_count);
  }
  struct Counted {
    uint32_t type;
    uint64_t record;
    uint32_t count;
  };
  const Counted counted[] = {{kSectionLights, sizeof(LightRecord), h.light_count},
                             {kSectionObjects, sizeof(ObjectRecord), h.object_count},
                             {kSectionGroups, sizeof(GroupRecord), h.group_count},
                             {kSectionPatches, sizeof(PatchRecord), h.patch_count},
                             {kSectionAtlases, sizeof(AtlasRecord), h.atlas_count},
                             {kSectionMeshes, sizeof(MeshRecord), h.mesh_count}};
  for (const Counted& c : counted) {
    const Section& s = sections_[c.type];
    if (!s.present) continue;  // only kMeshes is optional, checked above
    if (s.length % c.record != 0 || s.length / c.record != c.count) {
      return fail(Status::kCorrupt, "%s section: %llu bytes, expected %u records of %llu bytes",
                  section_name(c.type), static_cast<unsigned long long>(s.length), c.count,
                  static_cast<unsigned long long>(c.record));
    }
  }

  if (Status s = check_probe_sections(out); s != Status::kOk) return s;
  if (Status s = check_moving_sections(out); s != Status::kOk) return s;

  // Checksum before the records are interpreted (a flipped byte is reported as such).
  uint32_t crc = crc32(entries, uint64_t(h.section_count) * sizeof(SectionEntry));
  for (uint32_t i = 0; i < h.section_count; ++i) {
    const SectionEntry& e = entries[i];
    if (e.type == kSectionAtlasData || e.type == kSectionMeshData) continue;
    crc = crc32(b_ + e.offset, e.length, crc);
  }
  if (crc != h.table_checksum) {
    return fail(Status::kChecksumMismatch, "table checksum %08x does not match the stored %08x",
                crc, h.table_checksum);
  }

  const LightRecord* lights = at<LightRecord>(sections_[kSectionLights].offset);
  const ObjectRecord* objects = at<ObjectRecord>(sections_[kSectionObjects].offset);
  const GroupRecord* groups = at<GroupRecord>(sections_[kSectionGroups].offset);
  const PatchRecord* patches = at<PatchRecord>(sections_[kSectionPatches].offset);
  const AtlasRecord* atlases = at<AtlasRecord>(sections_[kSectionAtlases].offset);
  const MeshRecord* meshes = sections_[kSectionMeshes].present
                                 ? at<MeshRecord>(sections_[kSectionMeshes].offset)
                                 : nullptr;

  for (uint32_t i = 0; i < h.light_count; ++i) {
    const LightRecord& l = lights[i];
    // A pane is a pseudo-light without a name (pack_format.h, "Moving lights").
    const bool pane = l.type == kLightPane;
    if (pane && (l.name_length != 0 || l.name_offset != 0))
      return fail(Status::kCorrupt, "light %u: a pane light with a name", i);
    if (Status s = check_name("light", i, l.name_offset, l.name_length, pane); s != Status::kOk)
      return s;
    for (int c = 0; c < 3; ++c) {
      if (!finite_non_negative(l.color[c])) {
        return fail(Status::kCorrupt, "light %u: colour component %d is not finite and >= 0", i, c);
      }
    }
    if (!finite_non_negative(l.intensity)) {
      return fail(Status::kCorrupt, "light %u: intensity is not finite and >= 0", i);
    }
    if (l.type > kLightPane) return fail(Status::kCorrupt, "light %u: unknown type %u", i, l.type);
    if ((l.flags & ~uint32_t(kLightFlagMoving)) != 0)
      return fail(Status::kCorrupt, "light %u: unknown flags %08x", i, l.flags);
    if (pane && l.flags != 0) return fail(Status::kCorrupt, "light %u: a pane light with flags", i);
    if ((l.flags & kLightFlagMoving) && l.type != kLightPoint && l.type != kLightSpot)
      return fail(Status::kCorrupt, "light %u: flagged moving but not a point or spot light", i);
    if (pane && l.intensity != 1.0f)
      return fail(Status::kCorrupt, "light %u: a pane light with intensity %g, not 1", i,
                  double(l.intensity));
  }
  for (uint32_t i = 0; i < h.object_count; ++i) {
    const ObjectRecord& o = objects[i];
    if (Status s = check_name("object", i, o.name_offset, o.name_length, false); s != Status::kOk)
      return s;
    if (o.reserved[0] != 0 || o.reserved[1] != 0) {
      return fail(Status::kCorrupt, "object %u: reserved field not zero", i);
    }
  }

  const Section& atlas_data = sections_[kSectionAtlasData];
  for (uint32_t i = 0; i < h.atlas_count; ++i) {
    const AtlasRecord& a = atlases[i];
    if (!atlas_side_ok(a.width) || !atlas_side_ok(a.height)) {
      return fail(Status::kCorrupt, "atlas %u: size %ux%u: sides must be multiples of %u up to %u",
                  i, a.width, a.height, kAtlasAlign, kMaxAtlasSize);
    }
    if (a.data_offset % kSectionAlignment != 0) {
      return fail(Status::kCorrupt, "atlas %u: data offset %llu not a multiple of %u", i,
                  static_cast<unsigned long long>(a.data_offset), kSectionAlignment);
    }
    const uint64_t bytes = uint64_t(a.width) * a.height * 4;
    if (!range_inside(a.data_offset, bytes, atlas_data.offset, atlas_data.length)) {
      return fail(Status::kCorrupt, "atlas %u: pixels %llu+%llu outside the atlas-data section", i,
                  static_cast<unsigned long long>(a.data_offset),
                  static_cast<unsigned long long>(bytes));
    }
  }

  uint32_t expected_first = 0;
  for (uint32_t i = 0; i < h.group_count; ++i) {
    const GroupRecord& g = groups[i];
    if (g.kind > kGroupKindMax)
      return fail(Status::kCorrupt, "group %u: unknown kind %u", i, g.kind);
    const bool ok = owner_ok(g.kind, g.light, g.object_a, g.object_b, h);
    if (!ok) {
      return fail(Status::kCorrupt, "group %u (%s): owner light %u objects %u,%u invalid", i,
                  group_kind_name(g.kind), g.light, g.object_a, g.object_b);
    }
    if (i > 0 && group_key(groups[i - 1]) >= group_key(g)) {
      return fail(Status::kCorrupt, "group %u: not sorted after group %u (or a duplicate owner)", i,
                  i - 1);
    }
    if (g.patch_count == 0) return fail(Status::kCorrupt, "group %u: no patches", i);
    if (g.first_patch != expected_first) {
      return fail(Status::kCorrupt,
                  "group %u: first patch %u, expected %u (groups must be contiguous)", i,
                  g.first_patch, expected_first);
    }
    if (!range_inside(g.first_patch, g.patch_count, 0, h.patch_count)) {
      return fail(Status::kCorrupt, "group %u: patches %u+%u exceed the %u patches", i,
                  g.first_patch, g.patch_count, h.patch_count);
    }
    expected_first = g.first_patch + g.patch_count;
  }
  if (expected_first != h.patch_count) {
    return fail(Status::kCorrupt, "groups cover %u of %u patches", expected_first, h.patch_count);
  }

  for (uint32_t i = 0; i < h.patch_count; ++i) {
    const PatchRecord& p = patches[i];
    if (p.group >= h.group_count)
      return fail(Status::kCorrupt, "patch %u: group %u out of range", i, p.group);
    const GroupRecord& g = groups[p.group];
    if (i < g.first_patch || i - g.first_patch >= g.patch_count) {
      return fail(Status::kCorrupt, "patch %u: outside the range of its group %u", i, p.group);
    }
    if (p.atlas >= h.atlas_count)
      return fail(Status::kCorrupt, "patch %u: atlas %u out of range", i, p.atlas);
    if (p.width == 0 || p.height == 0)
      return fail(Status::kCorrupt, "patch %u: empty rectangle", i);
    const AtlasRecord& a = atlases[p.atlas];
    // A magnified patch's atlas rectangle is smaller than its destination (the level is 2 bits,
    // 0..kMaxPatchLevel, and a side is 16-bit: no overflow in 32 bits).
    const uint32_t level = patch_level(p.flags);
    const uint32_t aw = patch_atlas_side(p.width, level), ah = patch_atlas_side(p.height, level);
    if (uint32_t(p.atlas_x) + aw > a.width || uint32_t(p.atlas_y) + ah > a.height) {
      return fail(Status::kCorrupt,
                  "patch %u: atlas rectangle %u+%u x %u+%u (level %u, destination %ux%u) exceeds "
                  "atlas %u (%ux%u)",
                  i, p.atlas_x, aw, p.atlas_y, ah, level, p.width, p.height, p.atlas, a.width,
                  a.height);
    }
    if (p.target != kTargetLightMap && p.target != kTargetIndirectMap) {
      return fail(Status::kCorrupt, "patch %u: unknown target %u", i, p.target);
    }
    if (p.target == kTargetIndirectMap && h.indirect_scale == 0) {
      return fail(Status::kCorrupt, "patch %u: targets the indirect map of a pack that has none",
                  i);
    }
    // A group's light-map patches come before its indirect-map ones (one draw range per target).
    if (i > g.first_patch && patches[i - 1].target > p.target) {
      return fail(Status::kCorrupt,
                  "patch %u: targets the light map after an indirect-map patch of group %u", i,
                  p.group);
    }
    const bool indirect = p.target == kTargetIndirectMap;
    const char* map = indirect ? "indirect-map" : "light-map";
    const uint32_t map_w = indirect ? h.lightmap_width / h.indirect_scale : h.lightmap_width;
    const uint32_t map_h = indirect ? h.lightmap_height / h.indirect_scale : h.lightmap_height;
    if (uint32_t(p.dest_x) + p.width > map_w) {
      return fail(Status::kCorrupt, "patch %u: destination rectangle %u+%u exceeds %s width %u", i,
                  p.dest_x, p.width, map, map_w);
    }
    if (uint32_t(p.dest_y) + p.height > map_h) {
      return fail(Status::kCorrupt, "patch %u: destination rectangle %u+%u exceeds %s height %u", i,
                  p.dest_y, p.height, map, map_h);
    }
    if (p.channel_count < 1 || p.channel_count > 3) {
      return fail(Status::kCorrupt, "patch %u: channel count %u (must be 1, 2 or 3)", i,
                  p.channel_count);
    }
    if (uint32_t(p.channel) + p.channel_count > 4) {
      return fail(Status::kCorrupt, "patch %u: channels %u+%u exceed RGBA", i, p.channel,
                  p.channel_count);
    }
    if (p.encoding != kEncodingLinear && p.encoding != kEncodingSquare) {
      return fail(Status::kCorrupt, "patch %u: unknown encoding %u", i, p.encoding);
    }
    if (!std::isfinite(p.scale) || !(p.scale > 0.0f)) {
      return fail(Status::kCorrupt, "patch %u: scale is not finite and > 0", i);
    }
    if ((p.flags & ~uint32_t(kFlagNegative | kFlagDestinationMask | kFlagLevelMask)) != 0) {
      return fail(Status::kCorrupt, "patch %u: unknown flags %02x", i, p.flags);
    }
    if (patch_destination(p.flags) >= 0 && p.channel_count != 1) {
      return fail(Status::kCorrupt, "patch %u: a destination channel on a %u-channel patch", i,
                  p.channel_count);
    }
    if (p.channel_count != 2 && (p.tint_b[0] != 0 || p.tint_b[1] != 0 || p.tint_b[2] != 0)) {
      return fail(Status::kCorrupt, "patch %u: a second tint on a %u-channel patch", i,
                  p.channel_count);
    }
    if (p.reserved != 0) return fail(Status::kCorrupt, "patch %u: reserved field not zero", i);
  }

  if (h.mesh_count > 0) {
    const Section& md = sections_[kSectionMeshData];
    for (uint32_t i = 0; i < h.mesh_count; ++i) {
      const MeshRecord& m = meshes[i];
      if (Status s = check_name("mesh", i, m.name_offset, m.name_length, true); s != Status::kOk)
        return s;
      if (m.object != kNone16 && m.object >= h.object_count) {
        return fail(Status::kCorrupt, "mesh %u: object %u out of range", i, m.object);
      }
      if ((m.flags & ~uint16_t(kMeshFlagTexcoord1)) != 0 || m.reserved1 != 0)
        return fail(Status::kCorrupt, "mesh %u: unknown flags %04x or reserved field not zero", i,
                    m.flags);
      for (float f : m.lightmap_scale_offset) {
        const bool ok = (m.flags & kMeshFlagTexcoord1) ? std::isfinite(f) : f == 0.0f;
        if (!ok)
          return fail(Status::kCorrupt, "mesh %u: light-map scale and offset %s", i,
                      (m.flags & kMeshFlagTexcoord1) ? "not finite" : "set without the flag");
      }
      if (m.vertex_offset % 4 != 0 || m.index_offset % 4 != 0) {
        return fail(Status::kCorrupt, "mesh %u: vertex or index offset not 4-byte aligned", i);
      }
      if (!range_inside(m.vertex_offset, uint64_t(m.vertex_count) * sizeof(MeshVertex), md.offset,
                        md.length)) {
        return fail(Status::kCorrupt, "mesh %u: %u vertices at %llu outside the mesh-data section",
                    i, m.vertex_count, static_cast<unsigned long long>(m.vertex_offset));
      }
      if (!range_inside(m.index_offset, uint64_t(m.index_count) * 4, md.offset, md.length)) {
        return fail(Status::kCorrupt, "mesh %u: %u indices at %llu outside the mesh-data section",
                    i, m.index_count, static_cast<unsigned long long>(m.index_offset));
      }
      if (m.index_count % 3 != 0) {
        return fail(Status::kCorrupt, "mesh %u: index count %u not a multiple of 3", i,
                    m.index_count);
      }
      const MeshVertex* v = at<MeshVertex>(m.vertex_offset);
      for (uint32_t k = 0; k < m.vertex_count; ++k) {
        if (!std::isfinite(v[k].u) || !std::isfinite(v[k].v)) {
          return fail(Status::kCorrupt, "mesh %u: vertex %u has a non-finite UV", i, k);
        }
      }
      const uint32_t* idx = at<uint32_t>(m.index_offset);
      for (uint32_t k = 0; k < m.index_count; ++k) {
        if (idx[k] >= m.vertex_count) {
          return fail(Status::kCorrupt, "mesh %u: index %u is %u, not below the vertex count %u", i,
                      k, idx[k], m.vertex_count);
        }
      }
    }
  }

  if (Status s = check_probes(h, out); s != Status::kOk) return s;
  if (Status s = check_moving(h, lights, groups, out); s != Status::kOk) return s;
  if (Status s = check_limits(h); s != Status::kOk) return s;

  out->header = &h;
  out->lights = lights;
  out->objects = objects;
  out->groups = groups;
  out->patches = patches;
  out->atlases = atlases;
  out->meshes = meshes;
  out->strings = at<char>(sections_[kSectionStrings].offset);
  out->strings_length = sections_[kSectionStrings].length;
  return Status::kOk;
}

}  // namespace

Status PackView::open(const void* data, uint64_t size, const RecomposeLimits& limits, PackView* out,
                      Error* error) {
  if (out == nullptr) return set_error(error, Status::kInvalidArgument, "null output view");
  *out = PackView();
  Parsed p;
  Validator v(static_cast<const uint8_t*>(data), size, limits, error);
  const Status s = v.run(&p);
  if (s != Status::kOk) return s;
  out->bytes_ = static_cast<const uint8_t*>(data);
  out->size_ = size;
  out->header_ = p.header;
  out->lights_ = p.lights;
  out->objects_ = p.objects;
  out->groups_ = p.groups;
  out->patches_ = p.patches;
  out->atlases_ = p.atlases;
  out->meshes_ = p.meshes;
  out->strings_ = p.strings;
  out->strings_length_ = p.strings_length;
  out->probes_ = p.probes;
  out->probe_grid_ = p.probe_grid;
  out->probe_grid_indices_ =
      p.probe_grid ? reinterpret_cast<const uint32_t*>(p.probe_grid + 1) : nullptr;
  out->probe_sets_ = p.probe_sets;
  out->probe_entries_ = p.probe_entries;
  out->probe_count_ = p.probe_count;
  out->probe_grid_points_ = p.probe_grid ? p.probe_grid_points : 0;
  out->probe_set_count_ = p.probe_set_count;
  out->probe_entry_count_ = p.probe_entry_count;
  out->probe_bytes_ = p.probe_bytes;
  out->moving_lights_ = p.moving_lights;
  out->panes_ = p.panes;
  out->moving_light_count_ = p.moving_light_count;
  out->pane_count_ = p.pane_count;
  if (error != nullptr) *error = Error();
  return Status::kOk;
}

Name PackView::light_name(uint32_t i) const {
  return Name{strings_ + lights_[i].name_offset, lights_[i].name_length};
}
Name PackView::object_name(uint32_t i) const {
  return Name{strings_ + objects_[i].name_offset, objects_[i].name_length};
}
Name PackView::mesh_name(uint32_t i) const {
  return Name{strings_ + meshes_[i].name_offset, meshes_[i].name_length};
}
Name PackView::probe_name(uint32_t i) const {
  return Name{strings_ + probes_[i].name_offset, probes_[i].name_length};
}

const uint8_t* PackView::atlas_pixels(uint32_t i) const {
  return bytes_ + atlases_[i].data_offset;
}
const MeshVertex* PackView::mesh_vertices(uint32_t i) const {
  return reinterpret_cast<const MeshVertex*>(bytes_ + meshes_[i].vertex_offset);
}
const uint32_t* PackView::mesh_indices(uint32_t i) const {
  return reinterpret_cast<const uint32_t*>(bytes_ + meshes_[i].index_offset);
}

int32_t PackView::find_light(const char* name, uint32_t length) const {
  if (length == 0) return -1;  // panes have no name
  for (uint32_t i = 0; i < light_count(); ++i) {
    if (light_name(i).equals(name, length)) return static_cast<int32_t>(i);
  }
  return -1;
}
namespace {
// Records sorted by strictly increasing `light`: binary search.
template <typename Record>
int32_t find_by_light(const Record* records, uint32_t count, uint32_t light) {
  uint32_t lo = 0, hi = count;
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo) / 2;
    if (records[mid].light == light) return static_cast<int32_t>(mid);
    if (records[mid].light < light)
      lo = mid + 1;
    else
      hi = mid;
  }
  return -1;
}
}  // namespace

int32_t PackView::moving_index(uint32_t light) const {
  return find_by_light(moving_lights_, moving_light_count_, light);
}
int32_t PackView::pane_index(uint32_t light) const {
  return find_by_light(panes_, pane_count_, light);
}

int32_t PackView::find_object(const char* name, uint32_t length) const {
  for (uint32_t i = 0; i < object_count(); ++i) {
    if (object_name(i).equals(name, length)) return static_cast<int32_t>(i);
  }
  return -1;
}
int32_t PackView::find_probe(const char* name, uint32_t length) const {
  if (length == 0) return -1;  // grid probes have no name
  for (uint32_t i = 0; i < probe_count(); ++i) {
    if (probe_name(i).equals(name, length)) return static_cast<int32_t>(i);
  }
  return -1;
}

namespace {
// Groups are sorted by key: binary search.
int32_t find_group(const GroupRecord* groups, uint32_t count, const GroupRecord& probe) {
  const uint64_t key = group_key(probe);
  uint32_t lo = 0, hi = count;
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo) / 2;
    const uint64_t k = group_key(groups[mid]);
    if (k == key) return static_cast<int32_t>(mid);
    if (k < key)
      lo = mid + 1;
    else
      hi = mid;
  }
  return -1;
}
}  // namespace

int32_t PackView::base_group() const {
  return find_group(groups_, group_count(),
                    GroupRecord{kGroupBase, kNone16, kNone16, kNone16, 0, 0});
}
int32_t PackView::contribution_group(uint32_t light) const {
  if (light >= light_count()) return -1;
  return find_group(groups_, group_count(),
                    GroupRecord{kGroupContribution, uint16_t(light), kNone16, kNone16, 0, 0});
}
int32_t PackView::shadow_group(uint32_t light, uint32_t object) const {
  if (light >= light_count() || object >= object_count()) return -1;
  return find_group(groups_, group_count(),
                    GroupRecord{kGroupShadow, uint16_t(light), uint16_t(object), kNone16, 0, 0});
}

}  // namespace lightpatch
