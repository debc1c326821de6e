// Applies a state file's name-based overrides to a pack's SceneState (state_apply.cpp).
#pragma once

#include "lightpatch/cooker/state_spec.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/scene_state.h"

namespace lightpatch::tool {

// Overrides on top of the current values of *state. Throws CookError naming any light or object
// the pack does not have, or a value out of range.
void apply_state(const cooker::StateSpec& spec, const PackView& pack, SceneState* state);

}  // namespace lightpatch::tool
