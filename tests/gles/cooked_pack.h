// Scenes cooked in-process for the GLES tests (layout, texels, bake at draft quality, pack), kept
// with what a direct bake of a state needs (scene, layout, tracer, texels).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/texels.h"
#include "lightpatch/cooker/tracer.h"
#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/platform/egl_context.h"
#include "lightpatch/runtime.h"

namespace lightpatch::testing {

struct CookedPack {
  cooker::Scene scene;
  cooker::Layout layout;
  std::unique_ptr<cooker::Tracer> tracer;
  cooker::TexelSet texels;
  std::vector<uint8_t> bytes;
  PackView pack;
};

// Cooks c.scene (finished) at `texels_per_unit`, draft quality, indirect light on; the pack is
// opened into c.pack (gtest assertion on failure). `indirect_scale` 2, 4 or 8: the layout on
// blocks of that many texels and every light group's bounce light stored in an indirect map
// (PackOptions::always_split: the cooker's own choice by bytes may keep it in the light map,
// whose smooth patches it stores magnified); 1: none.
void cook_draft(CookedPack& c, float texels_per_unit, int indirect_scale = 1);

// A headless GLES context with a runtime and the CPU reference recomposer on one pack.
struct Recomposers {
  platform::EglContext context;
  Runtime runtime;
  CpuRecomposer cpu;
};
// Opens them (gtest assertions on failure).
void open_recomposers(const PackView& pack, const RuntimeLimits& limits, Recomposers* r);

}  // namespace lightpatch::testing
