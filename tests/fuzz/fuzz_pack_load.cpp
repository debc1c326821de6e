// libFuzzer target: the runtime's pack loader (PackView::open validates everything once) and, for
// packs it accepts, every accessor and a CPU recomposition of two states, which must stay within
// what open() validated, and the light probes evaluated for two states and sampled.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/light_probes.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/scene_state.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace lightpatch;
  // open() wants 8-byte aligned memory, as mmap and malloc give; libFuzzer's data is not.
  std::vector<uint64_t> aligned((size + 7) / 8 + 1);
  if (size > 0) std::memcpy(aligned.data(), data, size);
  PackView view;
  Error error;
  Status status = PackView::open(aligned.data(), size, &view, &error);
  if (status == Status::kChecksumMismatch) {
    // Every structural check before the checksum passed, so the section index is in bounds. Make
    // the checksum right and open again: otherwise the CRC turns away nearly every mutation of
    // the records, and the record validation behind it would go unfuzzed.
    auto* bytes = reinterpret_cast<uint8_t*>(aligned.data());
    pack::Header h;
    std::memcpy(&h, bytes, sizeof(h));
    const auto* entries = reinterpret_cast<const pack::SectionEntry*>(bytes + sizeof(pack::Header));
    uint32_t crc = crc32(entries, uint64_t(h.section_count) * sizeof(pack::SectionEntry));
    for (uint32_t i = 0; i < h.section_count; ++i) {
      if (entries[i].type == pack::kSectionAtlasData || entries[i].type == pack::kSectionMeshData)
        continue;
      crc = crc32(bytes + entries[i].offset, entries[i].length, crc);
    }
    std::memcpy(bytes + offsetof(pack::Header, table_checksum), &crc, 4);
    status = PackView::open(aligned.data(), size, &view, &error);
  }
  if (status != Status::kOk) return 0;

  uint64_t sum = 0;
  for (uint32_t i = 0; i < view.light_count(); ++i) {
    const Name n = view.light_name(i);
    for (uint32_t k = 0; k < n.length; ++k) sum += uint8_t(n.data[k]);
    sum += uint32_t(view.find_light(n.data, n.length));
    sum += uint32_t(view.contribution_group(i));
    for (uint32_t o = 0; o < view.object_count(); ++o) sum += uint32_t(view.shadow_group(i, o));
  }
  for (uint32_t i = 0; i < view.object_count(); ++i) {
    const Name n = view.object_name(i);
    sum += uint32_t(view.find_object(n.data, n.length));
  }
  for (uint32_t i = 0; i < view.atlas_count(); ++i) {
    const uint8_t* p = view.atlas_pixels(i);
    const uint64_t bytes = uint64_t(view.atlas(i).width) * view.atlas(i).height * 4;
    if (bytes > 0) sum += p[0] + p[bytes - 1];
  }
  for (uint32_t i = 0; i < view.mesh_count(); ++i) {
    const Name n = view.mesh_name(i);
    sum += n.length;
    const pack::MeshRecord& m = view.mesh(i);
    (void)m;
    sum += reinterpret_cast<uintptr_t>(view.mesh_vertices(i)) & 1;
    sum += reinterpret_cast<uintptr_t>(view.mesh_indices(i)) & 1;
  }
  sum += uint32_t(view.base_group());

  // Recompose (bounded so that the fuzzer does not spend its memory on huge declared maps).
  if (uint64_t(view.lightmap_width()) * view.lightmap_height() <= (1u << 20)) {
    SceneState state;
    CpuRecomposer recomposer;
    if (state.init(view, &error) == Status::kOk && recomposer.init(view, &error) == Status::kOk) {
      recomposer.rebuild(state);
      for (uint32_t i = 0; i < state.object_count(); i += 2) state.set_object_visible(i, false);
      for (uint32_t i = 0; i < state.light_count(); i += 2) state.set_light_intensity(i, 2.0f);
      recomposer.apply(state);
      const uint64_t n = uint64_t(recomposer.width()) * recomposer.height() * 3;
      if (n > 0) sum += recomposer.rgb()[n - 1] > 0.0f ? 1 : 0;
      if (view.has_indirect_map()) {  // its last texel, in the map set after the light map
        const uint64_t i = (view.map_texels() - view.map_offset(pack::kTargetIndirectMap)) * 3;
        sum += recomposer.indirect_map()[i - 1] > 0.0f ? 1 : 0;
      }
    }
  }
  // Light probes: every probe, and the grid sampled around and beyond its box.
  {
    SceneState state;
    LightProbes probes;
    if (state.init(view, &error) == Status::kOk && probes.init(view, &error) == Status::kOk) {
      probes.update(state);
      for (uint32_t i = 0; i < state.light_count(); i += 2) state.set_light_on(i, false);
      probes.update(state);
      float sh[kProbeShFloats] = {};
      for (uint32_t i = 0; i < probes.probe_count(); ++i) {
        probes.probe_sh(i, sh);
        sum += sh[0] > 0.0f ? 1 : 0;
        sum += view.probe_name(i).length;
      }
      if (view.has_probe_grid()) {
        const pack::ProbeGridRecord& g = view.probe_grid();
        for (int k = -1; k <= 8; ++k) {
          float pos[3];
          for (int a = 0; a < 3; ++a)
            pos[a] = g.origin[a] + g.spacing * float(g.size[a]) * (float(k) / 7.0f);
          sum += probes.sample(pos, sh) ? 1 : 0;
        }
      }
      sum += uint32_t(probes.find_probe("probe_0"));
    }
  }
  volatile uint64_t sink = sum;
  (void)sink;
  return 0;
}
