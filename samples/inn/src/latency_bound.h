// The latency bound of a gameplay change, in frames, derived before it runs from the planner's
// known costs and the budget rule (planner.h): the number a scripted run checks each change
// against.
//
//  * Incremental: with no rebuild running, a change whose cost (texels, against the presented
//    map) fits in one frame's budget and is below a rebuild's cost is drawn whole in the next
//    update: latency 1. InnGame::animate() reserves the budget of pending gameplay changes before
//    it schedules any flicker, so flicker never pushes one to a later frame.
//  * A light turned off (or dimmed) may instead start a rebuild: the drift rule (planner.h)
//    counts the draws made while it was brighter against its new factor. It is then bounded as
//    below.
//  * Otherwise it waits for the running rebuild (if any) and then for at most one full rebuild
//    (its own, or one the drift bound started while it waited), plus the frame that applies it.
//    A rebuild of T texels takes at most 2 + ceil(T / (budget - largest patch)) frames: each
//    frame but the clear's and the last does at least budget minus one patch of work.
#pragma once

#include <cstdint>

#include "lightpatch/runtime.h"

namespace lightpatch::inn {

// Frames a rebuild of `texels` texels needs at most under `budget`.
uint32_t rebuild_frames_bound(const PackView& pack, uint64_t texels, uint64_t budget);

// Bound for a change of `light` (or `object`, when light < 0) made now, before the next
// update(budget); `dims`: the change turns the light off or lowers its factor.
uint32_t change_latency_bound(const Runtime& runtime, const PackView& pack, uint64_t budget,
                              int32_t light, int32_t object, bool dims);

// Bound for a move of a moving light made now (runtime.h, "Moving lights"): its pane pushes take
// at most ceil(panes / max_pane_changes) updates; the last one then waits as a change that dims
// does (a running rebuild, then at most one full rebuild, plus the frame that applies it).
uint32_t moving_light_bound(const Runtime& runtime, const PackView& pack, uint64_t budget);

}  // namespace lightpatch::inn
