// BakeSession's state, shared by its source files.
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>

#include "bake/context.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/bake_plan.h"

namespace lightpatch::cooker {

struct BakeSession::Impl {
  Impl(const Scene& scene, const Layout& layout, const TexelSet& texels, const Tracer& tracer,
       const BakeOptions& options, GatherStore* store)
      : ctx(scene, layout, texels, tracer, options), gather_store(store) {}
  BakeContext ctx;
  BakePlan plan;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  uint64_t rays0 = 0;
  // The gather rays are traced by the first bake that needs them, so that planning and
  // assembling (a cook's plan and assemble jobs) trace nothing.
  std::once_flag traced;
  GatherStore* gather_store = nullptr;
  void trace_shared(Progress& progress, Report& report);
};

// The report's "bake" and "indirect" objects: steps, settings, rays and seconds since `impl`
// started (added to what the report holds, so a cook and its --measure-plan reruns add up).
void report_bake(const BakeSession::Impl& impl, Report& report);

}  // namespace lightpatch::cooker
