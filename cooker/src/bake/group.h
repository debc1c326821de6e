// Baking one light group of the plan: its direct pass, its bounce light and every object's change
// to it, and the keep-or-drop decision of each map by its measured peak.
#pragma once

#include <vector>

#include "bake/context.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/bake_plan.h"

namespace lightpatch::cooker {

// The groups of `groups` (plan indices), each the same result as baked alone; their bounce light,
// their objects' changes and their overlaps' joint changes are solved together, so that lights of
// one room share each pass over the integrator's rays. Memory grows with the groups' direct
// passes, all held until the last is done.
std::vector<GroupBake> bake_light_groups(const BakeContext& b, const BakePlan& plan,
                                         const std::vector<size_t>& groups, Progress& progress,
                                         Report& report);

}  // namespace lightpatch::cooker
