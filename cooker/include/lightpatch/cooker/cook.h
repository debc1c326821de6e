// The cook as a library pipeline (DESIGN.md, Architecture): import -> layout -> texels -> bake
// (the plan's light groups) -> finalize (seams, dilation) -> pack. The tool's verbs, the
// accuracy sweep and the benchmarks call these; each stage reports its time to `report`.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/pack_builder.h"
#include "lightpatch/cooker/probes.h"
#include "lightpatch/cooker/progress.h"
#include "lightpatch/cooker/reference_integrator.h"
#include "lightpatch/cooker/report.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/state_spec.h"
#include "lightpatch/cooker/texels.h"
#include "lightpatch/cooker/tracer.h"

namespace lightpatch::cooker {

// What baking needs: the scene, its light-map layout, the tracer and the texels. The same scene
// and layout options give the same layout in `cook` and `bake-state`.
struct PreparedScene {
  Scene scene;
  Layout layout;
  std::unique_ptr<Tracer> tracer;
  TexelSet texels;
};

// The layout alignment a bake's options call for (LayoutOptions::align, the pack's indirect
// scale): BakeOptions::indirect_scale when given, 1 (no indirect map) otherwise.
int layout_align(const BakeOptions& bake);

// Layout, tracer and texels for an imported scene; scene and layout statistics into `report`.
PreparedScene prepare_scene(Scene scene, const LayoutOptions& options, Progress& progress,
                            Report& report);
// Imports `path` (glTF, within `limits`) first. Throws CookError.
PreparedScene prepare_scene(const std::string& path, const LayoutOptions& options,
                            Progress& progress, Report& report, const ImportLimits& limits = {});

// Makes both sides of every chart cut agree and fills unused texels, in every map.
void finalize_maps(BakedMaps& maps, const PreparedScene& p, Progress& progress, Report& report);

// The pack options a bake's options call for (with the plan off, tinted patches stay 3-channel).
PackOptions pack_options(const BakeOptions& bake);

// The probe options a bake's options call for: its seed and threads, the preset's gather rays.
ProbeOptions probe_options(const BakeOptions& bake);

// Places the light probes and lights them from the cook's finalized maps (probes.h); empty when
// the bake's options turn probes off.
ProbeBake cook_probes(const PreparedScene& p, const BakedMaps& maps, const BakeOptions& bake,
                      Progress& progress, Report& report);

// Bakes every light group, finalizes and packs: the pack's bytes. `maps_out`, if not null,
// receives the finalized maps.
std::vector<uint8_t> cook_pack(const PreparedScene& p, const BakeOptions& bake, Progress& progress,
                               Report& report, BakedMaps* maps_out = nullptr);

// Bakes one state directly and finalizes it: the map `bake-state` writes.
FloatImage cook_state(const PreparedScene& p, const StateSpec& state, const BakeOptions& bake,
                      Progress& progress, Report& report);
// The same by the reference path tracer: its map and standard-error map, both finalized.
ReferenceBake cook_reference_state(const PreparedScene& p, const StateSpec& state,
                                   const ReferenceOptions& options, Progress& progress,
                                   Report& report);

}  // namespace lightpatch::cooker
