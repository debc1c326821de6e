#include "latency_bound.h"

#include <algorithm>

namespace lightpatch::inn {
namespace {

uint64_t patch_area(const pack::PatchRecord& p) {
  return uint64_t(p.width) * p.height;
}

uint64_t group_area(const PackView& pack, uint32_t g) {
  const pack::GroupRecord& gr = pack.group(g);
  uint64_t a = 0;
  for (uint32_t p = gr.first_patch; p < gr.first_patch + gr.patch_count; ++p)
    a += patch_area(pack.patch(p));
  return a;
}

// Everything the pack could draw: a rebuild never costs more.
uint64_t everything(const PackView& pack) {
  uint64_t all = uint64_t(pack.lightmap_width()) * pack.lightmap_height();
  for (uint32_t g = 0; g < pack.group_count(); ++g) all += group_area(pack, g);
  return all;
}

}  // namespace

uint32_t rebuild_frames_bound(const PackView& pack, uint64_t texels, uint64_t budget) {
  uint64_t largest = 0;
  for (uint32_t p = 0; p < pack.patch_count(); ++p)
    largest = std::max(largest, patch_area(pack.patch(p)));
  // With patches larger than the budget each frame still runs at least one patch alone.
  const uint64_t per_frame = budget > largest ? budget - largest : 0;
  const uint64_t frames = per_frame ? (texels + per_frame - 1) / per_frame : pack.patch_count();
  return static_cast<uint32_t>(std::min<uint64_t>(2 + frames, 0xFFFFFFFFu));
}

uint32_t change_latency_bound(const Runtime& runtime, const PackView& pack, uint64_t budget,
                              int32_t light, int32_t object, bool dims) {
  const Planner& p = runtime.planner();
  const bool rebuilding = !runtime.ready() || runtime.stats().rebuild_active;
  const uint64_t cost = light >= 0 ? p.light_change_texels(static_cast<uint32_t>(light))
                                   : p.object_change_texels(static_cast<uint32_t>(object));
  if (!rebuilding && !dims && cost <= budget && cost < p.rebuild_texels()) return 1;
  const uint64_t all = everything(pack);
  uint32_t bound = rebuild_frames_bound(pack, all, budget) + 1;
  if (rebuilding) {
    const uint64_t left = runtime.ready() ? runtime.stats().rebuild_remaining_texels : all;
    bound += rebuild_frames_bound(pack, left, budget);
  }
  return bound;
}

uint32_t moving_light_bound(const Runtime& runtime, const PackView& pack, uint64_t budget) {
  const uint32_t per_update = std::max(1u, runtime.limits().max_pane_changes);
  const uint32_t pushes = (pack.pane_count() + per_update - 1) / per_update;
  return pushes + 2 * rebuild_frames_bound(pack, everything(pack), budget) + 1;
}

}  // namespace lightpatch::inn
