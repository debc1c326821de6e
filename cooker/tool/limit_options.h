// The tool's limit options (README, "Limits"): each limit the cooker and the runtime state can be
// raised from the command line, and each refusal names the option that raises it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "args.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/pack_view.h"

namespace lightpatch::tool {

// --max-input-mb N, taken by every verb: main.cpp applies it before the verb runs.
void apply_input_size_option(Args& args);
extern const char* const kInputSizeHelp;

// --max-triangles N, --max-vertices N, --max-texture-pixels N, --uri-root DIR (repeatable): the
// verbs that import a scene.
cooker::ImportLimits parse_import_limits(Args& args);
extern const char* const kImportLimitsHelp;

// --max-lightmap-texels N: the verbs that open a pack.
RecomposeLimits parse_recompose_limits(Args& args);
extern const char* const kRecomposeLimitsHelp;

// A pack's validation message; for Status::kOverLimit with the option that raises the limit.
std::string pack_error_text(const Error& error);

// PackView::open within `limits`, then check_authored_map_bound (planner.h): a pack the runtime
// opens. What `verify` checks.
Status open_pack(const void* data, uint64_t size, const RecomposeLimits& limits, PackView* view,
                 Error* error);

// For a pack just cooked: throws CookError when the runtime would refuse it whatever its limits
// (its authored light map could exceed kMaxAuthoredMapBound); returns a warning when it is over
// the default RecomposeLimits (the user asked for a large light map), else empty.
std::string check_cooked_pack(const std::vector<uint8_t>& pack);

}  // namespace lightpatch::tool
