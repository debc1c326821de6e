// Making the bake plan (bake_plan.h) from a bake's context.
#pragma once

#include "bake/context.h"
#include "lightpatch/cooker/bake_plan.h"

namespace lightpatch::cooker {

// The light groups (static lights first, then each semi-dynamic light in scene order), their
// candidates (objects that can block their direct light: geometric culling by reach and cone)
// and bounce-only objects (the rest, when bounce light is on), and the decisions made before
// tracing: soft shadows, emissive surfaces, bounce light, pairs culled by geometry.
BakePlan make_plan(const BakeContext& b);

// The reason of every decision forced with the plan off (BakeOptions::plan_effects).
constexpr const char* kForced = "forced on (--no-plan)";

}  // namespace lightpatch::cooker
