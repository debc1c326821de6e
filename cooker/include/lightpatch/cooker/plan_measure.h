// What the effect plan saves (`cook --measure-plan`): a cook's report against the report of the
// same cook with BakeOptions::plan_effects off and PackOptions::keep_colour on.
#pragma once

#include <nlohmann/json.hpp>

namespace lightpatch::cooker {

// Writes planned["plan"]: per run (planned, forced) the seconds of the bake, finalize and pack
// stages and their total, rays, pack and atlas bytes, patches and groups; what the plan saved;
// per category (pairs, overlap corrections, indirect groups, object bounce, static shadows,
// colour) the counts taken and skipped in each run; per light group its pass seconds in each run.
// Adds "time_saved_s" to the planned decisions whose saved time is measured on its own: an
// indirect group the plan skipped (the group's whole pass, forced minus planned) and an object
// bounce it skipped (the forced run's change for that object). Both arguments are report
// roots (Report::root()).
void add_plan_measurement(nlohmann::json& planned, const nlohmann::json& forced);

}  // namespace lightpatch::cooker
