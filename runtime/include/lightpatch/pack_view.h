// Read-only, validated view of a pack held in memory (usually a file mapping).
//
// PackView::open validates everything once (header, section index, every record, every rectangle,
// every index, the table checksum) with 64-bit overflow-safe bounds checks; after a successful
// open every accessor is safe to call with indices below the matching count.
//
// Limits a valid pack keeps (besides pack_format.h's): light map 1..kMaxLightmapSize texels per
// axis; an indirect map (indirect_scale 2, 4 or 8 dividing both sides) of at most a quarter of
// the light map's texels, so both maps together hold at most 1.25 * 16384^2 texels (the runtime's
// memory is proportional: RuntimeMemory); each indirect patch inside the indirect map; within a
// group the light-map patches before the indirect-map ones.
//
// The maps, laid out one after the other ("map set": what add_patches and the CPU sinks use):
// the light map's width * height texels, row 0 at the top, then the indirect map's
// indirect_width * indirect_height texels (none without an indirect map); map_offset(target) is
// where a target's first texel lies, map_texels() the total.
//
// Light probes (optional sections, pack_format.h "Light probes"): kProbes comes with kProbeSets
// and kProbeEntries (all three or none; kProbeGrid only with them); at most kMaxProbes probes and
// kMaxProbeGridPoints grid points; every probe set keyed like a group (never a pair correction),
// sorted, its entries contiguous and ascending by probe, every SH coefficient finite. The view
// Moving lights (optional sections, pack_format.h "Moving lights"): kMovingLights comes with
// kPanes (both or none; the panes section may be empty); every light flagged kLightFlagMoving (a
// point or spot light) has exactly one MovingLightRecord and every kLightPane light exactly one
// PaneRecord, both sorted by light; a pane light has no name, no flags, intensity 1 and at most
// its one contribution group (none: it draws nothing); moving lights have no group; neither has
// a probe set. Unit vectors are within 1e-3 of length 1; unused entry points are zero. The view
// never copies or owns the bytes: the caller keeps the memory alive and unchanged while the view is
// used. No exceptions, no allocation.
#pragma once

#include <cstdint>

#include "lightpatch/pack_format.h"
#include "lightpatch/status.h"

namespace lightpatch {

// What a pack may ask of a recomposer beyond the format's own ranges (pack_format.h).
// PackView::open refuses (Status::kOverLimit) a pack over them before anything is allocated for it,
// so that `lightpatch verify` accepts what the recomposers can hold; a game on a device with more
// memory passes larger ones. (How bright a pack may be is the planner's check_authored_map_bound.)
struct RecomposeLimits {
  // Light-map texels. The GLES runtime holds the sampled RGBA16F map and an accumulator (RGBA32F
  // or RGBA16F, or double RGB on its CPU path): 16 to 32 bytes a texel, 256 to 512 MiB at the
  // default; the CPU recomposer two float RGB maps, 384 MiB. An indirect map adds at most a
  // quarter of that (scale >= 2), which this limit leaves to the light map's margin.
  uint64_t max_lightmap_texels = uint64_t(4096) * 4096;

  // No limit beyond the format's own ranges (the cooker's check of what it wrote).
  static RecomposeLimits format_only() {
    RecomposeLimits l;
    l.max_lightmap_texels = uint64_t(pack::kMaxLightmapSize) * pack::kMaxLightmapSize;
    return l;
  }
};

// A name inside the pack's string section; not NUL-terminated, valid UTF-8.
struct Name {
  const char* data;
  uint32_t length;
  bool equals(const char* s, uint32_t n) const;
};

class PackView {
 public:
  PackView() = default;

  // Validates `size` bytes at `data` (must be 8-byte aligned, as mmap and malloc give; for bytes
  // that may not be, e.g. an APK asset's 4-byte alignment, use PackMemory) and on
  // success fills *out. On failure returns the error and fills *error (if non-null) with a
  // message naming the problem; *out is left empty. A valid pack over `limits` gives kOverLimit
  // with a message naming the RecomposeLimits field.
  static Status open(const void* data, uint64_t size, const RecomposeLimits& limits, PackView* out,
                     Error* error);
  // The same with the default RecomposeLimits.
  static Status open(const void* data, uint64_t size, PackView* out, Error* error) {
    return open(data, size, RecomposeLimits(), out, error);
  }

  bool valid() const { return header_ != nullptr; }
  const pack::Header& header() const { return *header_; }
  uint32_t lightmap_width() const { return header_->lightmap_width; }
  uint32_t lightmap_height() const { return header_->lightmap_height; }

  // The indirect map (pack_format.h, "Two target maps"): light-map texels per indirect texel along
  // each axis (0: none), and its size in texels (0 x 0 without one).
  bool has_indirect_map() const { return header_->indirect_scale != 0; }
  uint32_t indirect_scale() const { return header_->indirect_scale; }
  // Whether the presented maps keep their sign (pack_format.h, "Two target maps": with an
  // indirect map the light map corrects it, so only L + I is clamped at zero, by the game).
  bool presents_signed() const { return has_indirect_map(); }
  uint32_t indirect_width() const {
    return has_indirect_map() ? header_->lightmap_width / header_->indirect_scale : 0;
  }
  uint32_t indirect_height() const {
    return has_indirect_map() ? header_->lightmap_height / header_->indirect_scale : 0;
  }
  // Size of a PatchTarget's map in texels.
  uint32_t map_width(uint8_t target) const {
    return target == pack::kTargetIndirectMap ? indirect_width() : lightmap_width();
  }
  uint32_t map_height(uint8_t target) const {
    return target == pack::kTargetIndirectMap ? indirect_height() : lightmap_height();
  }
  // Texel index of a target's first texel in the map set (see above), and the set's texels.
  uint64_t map_offset(uint8_t target) const {
    return target == pack::kTargetIndirectMap ? uint64_t(lightmap_width()) * lightmap_height() : 0;
  }
  uint64_t map_texels() const {
    return uint64_t(lightmap_width()) * lightmap_height() +
           uint64_t(indirect_width()) * indirect_height();
  }

  uint32_t light_count() const { return header_->light_count; }
  uint32_t object_count() const { return header_->object_count; }
  uint32_t group_count() const { return header_->group_count; }
  uint32_t patch_count() const { return header_->patch_count; }
  uint32_t atlas_count() const { return header_->atlas_count; }
  uint32_t mesh_count() const { return header_->mesh_count; }

  const pack::LightRecord& light(uint32_t i) const { return lights_[i]; }
  const pack::ObjectRecord& object(uint32_t i) const { return objects_[i]; }
  const pack::GroupRecord& group(uint32_t i) const { return groups_[i]; }
  const pack::PatchRecord& patch(uint32_t i) const { return patches_[i]; }
  const pack::AtlasRecord& atlas(uint32_t i) const { return atlases_[i]; }
  const pack::MeshRecord& mesh(uint32_t i) const { return meshes_[i]; }
  const pack::GroupRecord* groups() const { return groups_; }
  const pack::PatchRecord* patches() const { return patches_; }

  Name light_name(uint32_t i) const;
  Name object_name(uint32_t i) const;
  Name mesh_name(uint32_t i) const;

  // RGBA8 rows, top to bottom, width*height*4 bytes.
  const uint8_t* atlas_pixels(uint32_t i) const;
  const pack::MeshVertex* mesh_vertices(uint32_t i) const;
  const uint32_t* mesh_indices(uint32_t i) const;

  // Index of the light/object with this name, or -1 (a pane, unnamed, is never found).
  int32_t find_light(const char* name, uint32_t length) const;
  int32_t find_object(const char* name, uint32_t length) const;

  // Light probes (0 / false / null without them). Grid indices: probe_grid_point_count() uint32
  // values, x fastest, each a probe index or pack::kNone32.
  uint32_t probe_count() const { return probe_count_; }
  const pack::ProbeRecord& probe(uint32_t i) const { return probes_[i]; }
  Name probe_name(uint32_t i) const;  // length 0 for a grid probe
  bool has_probe_grid() const { return probe_grid_ != nullptr; }
  const pack::ProbeGridRecord& probe_grid() const { return *probe_grid_; }
  const uint32_t* probe_grid_indices() const { return probe_grid_indices_; }
  uint32_t probe_grid_point_count() const { return probe_grid_points_; }
  uint32_t probe_set_count() const { return probe_set_count_; }
  const pack::ProbeSetRecord& probe_set(uint32_t i) const { return probe_sets_[i]; }
  const pack::ProbeSetRecord* probe_sets() const { return probe_sets_; }
  uint32_t probe_entry_count() const { return probe_entry_count_; }
  const pack::ProbeEntry& probe_entry(uint32_t i) const { return probe_entries_[i]; }
  const pack::ProbeEntry* probe_entries() const { return probe_entries_; }
  // Bytes of the four probe sections together (0 without probes).
  uint64_t probe_bytes() const { return probe_bytes_; }
  // Index of the named probe, or -1 (grid probes have no name).
  int32_t find_probe(const char* name, uint32_t length) const;

  // Moving lights and panes (0 / null without them). moving_light(k) and pane(k) are sorted by
  // their light index; moving_index(light) / pane_index(light) give k for a light index (binary
  // search), or -1 when the light is not moving / not a pane.
  uint32_t moving_light_count() const { return moving_light_count_; }
  const pack::MovingLightRecord& moving_light(uint32_t k) const { return moving_lights_[k]; }
  uint32_t pane_count() const { return pane_count_; }
  const pack::PaneRecord& pane(uint32_t k) const { return panes_[k]; }
  int32_t moving_index(uint32_t light) const;
  int32_t pane_index(uint32_t light) const;
  bool light_moves(uint32_t light) const {
    return (lights_[light].flags & pack::kLightFlagMoving) != 0;
  }
  bool light_is_pane(uint32_t light) const { return lights_[light].type == pack::kLightPane; }
  // Bytes of the panes section (what the panes' depth maps and entry points take).
  uint64_t pane_bytes() const { return uint64_t(pane_count_) * sizeof(pack::PaneRecord); }

  // Group lookups; -1 when the pack holds no such group (nothing to draw).
  int32_t base_group() const;
  int32_t contribution_group(uint32_t light) const;
  int32_t shadow_group(uint32_t light, uint32_t object) const;

  const uint8_t* bytes() const { return bytes_; }
  uint64_t size() const { return size_; }

 private:
  const uint8_t* bytes_ = nullptr;
  uint64_t size_ = 0;
  const pack::Header* header_ = nullptr;
  const pack::LightRecord* lights_ = nullptr;
  const pack::ObjectRecord* objects_ = nullptr;
  const pack::GroupRecord* groups_ = nullptr;
  const pack::PatchRecord* patches_ = nullptr;
  const pack::AtlasRecord* atlases_ = nullptr;
  const pack::MeshRecord* meshes_ = nullptr;
  const char* strings_ = nullptr;
  uint64_t strings_length_ = 0;
  const pack::ProbeRecord* probes_ = nullptr;
  const pack::ProbeGridRecord* probe_grid_ = nullptr;
  const uint32_t* probe_grid_indices_ = nullptr;
  const pack::ProbeSetRecord* probe_sets_ = nullptr;
  const pack::ProbeEntry* probe_entries_ = nullptr;
  uint32_t probe_count_ = 0;
  uint32_t probe_grid_points_ = 0;
  uint32_t probe_set_count_ = 0;
  uint32_t probe_entry_count_ = 0;
  uint64_t probe_bytes_ = 0;
  const pack::MovingLightRecord* moving_lights_ = nullptr;
  const pack::PaneRecord* panes_ = nullptr;
  uint32_t moving_light_count_ = 0;
  uint32_t pane_count_ = 0;
};

// CRC-32 (IEEE, reflected), the pack's table checksum. `crc` chains calls; start with 0.
uint32_t crc32(const void* data, uint64_t size, uint32_t crc = 0);

}  // namespace lightpatch
