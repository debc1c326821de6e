#include "cooked_pack.h"

#include <gtest/gtest.h>

#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/pack_builder.h"
#include "lightpatch/cooker/progress.h"
#include "lightpatch/cooker/report.h"
#include "lightpatch/cooker/texel_builder.h"
#include "lightpatch/cooker/unwrap.h"

namespace lightpatch::testing {

using namespace cooker;

void cook_draft(CookedPack& c, float texels_per_unit, int indirect_scale) {
  LayoutOptions lo;
  lo.texels_per_unit = texels_per_unit;
  lo.align = indirect_scale;
  lo.align_required = indirect_scale > 1;
  c.layout = build_layout(c.scene, lo);
  c.tracer = make_embree_tracer(c.scene);
  c.texels = build_texels(c.scene, c.layout, c.tracer.get());
  Progress progress(true);
  Report report;
  BakeOptions options;
  options.quality = Quality::kDraft;
  if (indirect_scale > 1) options.indirect_scale = indirect_scale;  // else the preset's level
  BakedMaps maps = bake_maps(c.scene, c.layout, c.texels, *c.tracer, options, progress, report);
  finalize_maps(maps, c.scene, c.layout, c.texels);
  PackOptions po;
  po.always_split = indirect_scale > 1;
  c.bytes = build_pack(c.scene, c.layout, maps, po, report);
  Error error;
  ASSERT_EQ(PackView::open(c.bytes.data(), c.bytes.size(), &c.pack, &error), Status::kOk)
      << error.message;
}

void open_recomposers(const PackView& pack, const RuntimeLimits& limits, Recomposers* r) {
  char message[256] = {};
  ASSERT_TRUE(r->context.create_headless(message, sizeof message)) << message;
  Error error;
  ASSERT_EQ(r->runtime.open(pack, limits, &error), Status::kOk) << error.message;
  ASSERT_EQ(r->cpu.init(pack, &error), Status::kOk) << error.message;
}

}  // namespace lightpatch::testing
