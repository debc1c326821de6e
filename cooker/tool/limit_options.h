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

// --max-lightmap-texels N, --max-texel-value V: the verbs that open a pack.
RecomposeLimits parse_recompose_limits(Args& args);
extern const char* const kRecomposeLimitsHelp;

// A pack's validation message; for Status::kOverLimit with the option that raises the limit.
std::string pack_error_text(const Error& error);

// For a pack just cooked: empty when the runtime takes it with its default limits, else what
// exceeds them (a warning: the user asked for a large light map or bright lights).
std::string default_limits_warning(const std::vector<uint8_t>& pack);

}  // namespace lightpatch::tool
