#include "pack_writer.h"

#include <cstring>

#include "lightpatch/cooker/error.h"
#include "lightpatch/pack_view.h"

namespace lightpatch::cooker {

using namespace pack;

void PackContents::add_name(const std::string& name, uint32_t* offset, uint32_t* length) {
  *offset = static_cast<uint32_t>(strings.size());
  *length = static_cast<uint32_t>(name.size());
  strings += name;
}

namespace {
uint64_t align_up(uint64_t v) {
  return (v + kSectionAlignment - 1) / kSectionAlignment * kSectionAlignment;
}
}  // namespace

std::vector<uint8_t> write_pack(const PackContents& c) {
  struct Pending {
    uint32_t type;
    uint64_t length;
    uint64_t offset = 0;
  };
  // Table sections first, then the bulk data (not covered by the checksum).
  uint64_t atlas_bytes = 0;
  for (const auto& a : c.atlases)
    atlas_bytes = align_up(atlas_bytes) + uint64_t(a.width) * a.height * 4;
  uint64_t mesh_bytes = 0;
  for (const auto& m : c.meshes)
    mesh_bytes += m.vertices.size() * sizeof(MeshVertex) + m.indices.size() * 4;
  std::vector<Pending> sections = {
      {kSectionLights, c.lights.size() * sizeof(LightRecord)},
      {kSectionObjects, c.objects.size() * sizeof(ObjectRecord)},
      {kSectionGroups, c.groups.size() * sizeof(GroupRecord)},
      {kSectionPatches, c.patches.size() * sizeof(PatchRecord)},
      {kSectionAtlases, c.atlases.size() * sizeof(AtlasRecord)},
      {kSectionStrings, c.strings.size()},
  };
  if (!c.meshes.empty()) sections.push_back({kSectionMeshes, c.meshes.size() * sizeof(MeshRecord)});
  const bool probes = !c.probes.empty();
  const bool grid = probes && c.has_probe_grid;
  if (probes) {
    sections.push_back({kSectionProbes, c.probes.size() * sizeof(ProbeRecord)});
    if (grid) {
      sections.push_back(
          {kSectionProbeGrid, sizeof(ProbeGridRecord) + c.probe_grid_indices.size() * 4});
    }
    sections.push_back({kSectionProbeSets, c.probe_sets.size() * sizeof(ProbeSetRecord)});
    sections.push_back({kSectionProbeEntries, c.probe_entries.size() * sizeof(ProbeEntry)});
  }
  const bool moving = !c.moving_lights.empty();
  if (moving) {
    sections.push_back({kSectionMovingLights, c.moving_lights.size() * sizeof(MovingLightRecord)});
    sections.push_back({kSectionPanes, c.panes.size() * sizeof(PaneRecord)});
  }
  sections.push_back({kSectionAtlasData, atlas_bytes});
  if (!c.meshes.empty()) sections.push_back({kSectionMeshData, mesh_bytes});

  uint64_t offset = sizeof(Header) + sections.size() * sizeof(SectionEntry);
  for (Pending& s : sections) {
    offset = align_up(offset);
    s.offset = offset;
    offset += s.length;
  }
  const uint64_t file_size = offset;
  std::vector<uint8_t> out(file_size, 0);
  auto find = [&](uint32_t type) -> const Pending& {
    for (const Pending& s : sections) {
      if (s.type == type) return s;
    }
    throw CookError("internal: pack section missing");
  };
  auto put = [&](uint64_t at, const void* data, size_t n) {
    if (n > 0) std::memcpy(out.data() + at, data, n);
  };

  Header h{};
  h.magic = kMagic;
  h.version = kVersion;
  h.file_size = file_size;
  h.section_count = static_cast<uint32_t>(sections.size());
  h.lightmap_width = c.lightmap_width;
  h.lightmap_height = c.lightmap_height;
  h.indirect_scale = c.indirect_scale;
  h.light_count = static_cast<uint32_t>(c.lights.size());
  h.object_count = static_cast<uint32_t>(c.objects.size());
  h.group_count = static_cast<uint32_t>(c.groups.size());
  h.patch_count = static_cast<uint32_t>(c.patches.size());
  h.atlas_count = static_cast<uint32_t>(c.atlases.size());
  h.mesh_count = static_cast<uint32_t>(c.meshes.size());

  for (size_t i = 0; i < sections.size(); ++i) {
    SectionEntry e{};
    e.type = sections[i].type;
    e.offset = sections[i].offset;
    e.length = sections[i].length;
    put(sizeof(Header) + i * sizeof(SectionEntry), &e, sizeof(e));
  }
  put(find(kSectionLights).offset, c.lights.data(), c.lights.size() * sizeof(LightRecord));
  put(find(kSectionObjects).offset, c.objects.data(), c.objects.size() * sizeof(ObjectRecord));
  put(find(kSectionGroups).offset, c.groups.data(), c.groups.size() * sizeof(GroupRecord));
  put(find(kSectionPatches).offset, c.patches.data(), c.patches.size() * sizeof(PatchRecord));
  put(find(kSectionStrings).offset, c.strings.data(), c.strings.size());
  if (probes) {
    put(find(kSectionProbes).offset, c.probes.data(), c.probes.size() * sizeof(ProbeRecord));
    if (grid) {
      const uint64_t at = find(kSectionProbeGrid).offset;
      put(at, &c.probe_grid, sizeof(ProbeGridRecord));
      put(at + sizeof(ProbeGridRecord), c.probe_grid_indices.data(),
          c.probe_grid_indices.size() * 4);
    }
    put(find(kSectionProbeSets).offset, c.probe_sets.data(),
        c.probe_sets.size() * sizeof(ProbeSetRecord));
    put(find(kSectionProbeEntries).offset, c.probe_entries.data(),
        c.probe_entries.size() * sizeof(ProbeEntry));
  }
  if (moving) {
    put(find(kSectionMovingLights).offset, c.moving_lights.data(),
        c.moving_lights.size() * sizeof(MovingLightRecord));
    put(find(kSectionPanes).offset, c.panes.data(), c.panes.size() * sizeof(PaneRecord));
  }

  const Pending& atlas_data = find(kSectionAtlasData);
  uint64_t at = atlas_data.offset;
  for (size_t i = 0; i < c.atlases.size(); ++i) {
    const auto& a = c.atlases[i];
    at = align_up(at);
    AtlasRecord r{};
    r.width = a.width;
    r.height = a.height;
    r.data_offset = at;
    if (a.rgba.size() != uint64_t(a.width) * a.height * 4)
      throw CookError("internal: atlas pixel count");
    put(find(kSectionAtlases).offset + i * sizeof(AtlasRecord), &r, sizeof(r));
    put(at, a.rgba.data(), a.rgba.size());
    at += a.rgba.size();
  }
  if (!c.meshes.empty()) {
    uint64_t md = find(kSectionMeshData).offset;
    const uint64_t records = find(kSectionMeshes).offset;
    for (size_t i = 0; i < c.meshes.size(); ++i) {
      const auto& m = c.meshes[i];
      MeshRecord r = m.record;
      r.vertex_offset = md;
      r.vertex_count = static_cast<uint32_t>(m.vertices.size());
      put(md, m.vertices.data(), m.vertices.size() * sizeof(MeshVertex));
      md += m.vertices.size() * sizeof(MeshVertex);
      r.index_offset = md;
      r.index_count = static_cast<uint32_t>(m.indices.size());
      put(md, m.indices.data(), m.indices.size() * 4);
      md += m.indices.size() * 4;
      put(records + i * sizeof(MeshRecord), &r, sizeof(r));
    }
  }

  uint32_t crc = crc32(out.data() + sizeof(Header), sections.size() * sizeof(SectionEntry));
  for (const Pending& s : sections) {
    if (s.type == kSectionAtlasData || s.type == kSectionMeshData) continue;
    crc = crc32(out.data() + s.offset, s.length, crc);
  }
  h.table_checksum = crc;
  put(0, &h, sizeof(h));
  return out;
}

}  // namespace lightpatch::cooker
