// Serialising pack records into the bytes of pack_format.h: header, section index, sections
// aligned to kSectionAlignment (zero padding), atlas pixels each aligned too, table checksum.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/pack_format.h"

namespace lightpatch::cooker {

struct PackContents {
  uint32_t lightmap_width = 0, lightmap_height = 0;
  uint32_t indirect_scale = 0;  // Header::indirect_scale (0: no indirect map)
  std::vector<pack::LightRecord> lights;
  std::vector<pack::ObjectRecord> objects;
  std::vector<pack::GroupRecord> groups;
  std::vector<pack::PatchRecord> patches;
  struct Atlas {
    uint32_t width = 0, height = 0;
    std::vector<uint8_t> rgba;  // width * height * 4
  };
  std::vector<Atlas> atlases;  // AtlasRecord::data_offset is assigned by the writer
  std::string strings;
  struct Mesh {
    pack::MeshRecord record{};  // vertex_offset / index_offset / counts assigned by the writer
    std::vector<pack::MeshVertex> vertices;
    std::vector<uint32_t> indices;
  };
  std::vector<Mesh> meshes;
  // Light probes (pack_format.h, "Light probes"): written only when `probes` is not empty; the
  // grid only with has_probe_grid (probe_grid_indices: one per grid point, x fastest).
  std::vector<pack::ProbeRecord> probes;
  bool has_probe_grid = false;
  pack::ProbeGridRecord probe_grid{};
  std::vector<uint32_t> probe_grid_indices;
  std::vector<pack::ProbeSetRecord> probe_sets;
  std::vector<pack::ProbeEntry> probe_entries;
  // Moving lights and their panes (pack_format.h, "Moving lights"): written only when
  // `moving_lights` is not empty.
  std::vector<pack::MovingLightRecord> moving_lights;
  std::vector<pack::PaneRecord> panes;

  // Appends a name to `strings`; returns {offset, length}.
  void add_name(const std::string& name, uint32_t* offset, uint32_t* length);
};

std::vector<uint8_t> write_pack(const PackContents& contents);

}  // namespace lightpatch::cooker
