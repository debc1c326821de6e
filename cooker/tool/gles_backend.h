// `recompose --backend gles`: the GLES runtime on an EGL surfaceless context (gles_backend.cpp).
#pragma once

#include <vector>

#include "lightpatch/cooker/state_spec.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/planner.h"

namespace lightpatch::tool {

// Applies `states` in order through the runtime's incremental path (the first one after the
// initial full build from the authored state) and reads back the final light map as linear RGB
// floats, row 0 = top, width*height*3 into *rgb; with an indirect map, the light map plus the
// indirect map magnified (indirect_map.h): what a game samples, the CPU recomposer's rgb(). Throws
// CookError with a clear message (no EGL, no GLES 3, unknown names in a state). `costs` (optional)
// receives the texels written by target: the first build, then each state's change.
void recompose_gles(const PackView& pack, const std::vector<cooker::StateSpec>& states,
                    std::vector<float>* rgb, std::vector<TargetTexels>* costs = nullptr);

}  // namespace lightpatch::tool
