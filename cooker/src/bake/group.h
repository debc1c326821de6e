// Baking one light group of the plan: its direct pass, its bounce light and every object's change
// to it, and the keep-or-drop decision of each map by its measured peak.
#pragma once

#include "bake/context.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/bake_plan.h"

namespace lightpatch::cooker {

GroupBake bake_light_group(const BakeContext& b, const BakePlan& plan, size_t group,
                           Progress& progress, Report& report);

}  // namespace lightpatch::cooker
