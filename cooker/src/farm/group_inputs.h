// What each light group of a bake reads, as one SHA-256 digest per group (cook_jobs.h says what
// goes in and why). Two bakes whose group g has the same digest give group g the same maps, bit
// for bit, on the same build of the tool.
#pragma once

#include <string>
#include <vector>

#include "bake/context.h"
#include "farm/content_hash.h"
#include "lightpatch/cooker/bake_plan.h"
#include "lightpatch/cooker/cook.h"

namespace lightpatch::cooker {

// Bump when what a job's output depends on changes in a way the inputs below do not show.
constexpr uint32_t kJobInputsVersion = 3;

struct JobDigests {
  std::vector<Digest> groups;  // one per plan.groups entry
  bool has_gather = false;     // bounce light on: the gather rays are a job of their own
  Digest gather{};             // what the gather operator depends on
};

// `tool`: the build's identity (tool_identity()).
JobDigests job_input_digests(const PreparedScene& p, const BakeContext& b, const BakePlan& plan,
                             const std::string& tool);

}  // namespace lightpatch::cooker
