#include "state_apply.h"

#include <algorithm>
#include <string>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/printable.h"

namespace lightpatch::tool {

namespace {

// The pack's names for a message: each cut, and no more than 20 of them.
std::string names_of(const PackView& pack, bool lights) {
  constexpr uint32_t kShown = 20;
  std::string s;
  const uint32_t n = lights ? pack.light_count() : pack.object_count();
  uint32_t shown = 0, listed = 0;
  for (uint32_t i = 0; i < n; ++i) {
    if (lights && pack.light_is_pane(i)) continue;  // a pane is no light of the scene
    ++listed;
    if (shown == kShown) continue;
    ++shown;
    const Name name = lights ? pack.light_name(i) : pack.object_name(i);
    if (!s.empty()) s += ", ";
    s += cooker::printable(std::string_view(name.data, name.length));
  }
  if (listed > shown) s += " and " + std::to_string(listed - shown) + " more";
  return s.empty() ? "none" : s;
}

}  // namespace

void apply_state(const cooker::StateSpec& spec, const PackView& pack, SceneState* state) {
  for (const auto& [name, o] : spec.lights) {
    const int32_t i = pack.find_light(name.data(), static_cast<uint32_t>(name.size()));
    if (i < 0) {
      throw cooker::CookError(
          "state names light " + cooker::quote(name) +
          ", which the pack does not have (its lights: " + names_of(pack, true) + ")");
    }
    const uint32_t li = static_cast<uint32_t>(i);
    if ((o.has_on && state->set_light_on(li, o.on) != Status::kOk) ||
        (o.has_color && state->set_light_color(li, o.color) != Status::kOk) ||
        (o.has_intensity && state->set_light_intensity(li, o.intensity) != Status::kOk)) {
      throw cooker::CookError("light " + cooker::quote(name) +
                              ": colour and intensity must be finite and >= 0");
    }
    if (o.has_position || o.has_direction) {
      if (!pack.light_moves(li)) {
        throw cooker::CookError("light " + cooker::quote(name) +
                                ": a position or direction is for a moving light (extras.moving); "
                                "this one is not");
      }
      LightPose pose = state->light_pose(li);
      if (o.has_position) std::copy(o.position, o.position + 3, pose.position);
      if (o.has_direction) std::copy(o.direction, o.direction + 3, pose.direction);
      if (state->set_light_pose(li, pose) != Status::kOk) {
        throw cooker::CookError("light " + cooker::quote(name) +
                                ": the position must be finite and within 1e6 m of the origin, "
                                "the direction a unit vector");
      }
    }
  }
  for (const auto& [name, visible] : spec.objects) {
    const int32_t i = pack.find_object(name.data(), static_cast<uint32_t>(name.size()));
    if (i < 0) {
      throw cooker::CookError("state names object " + cooker::quote(name) +
                              ", which the pack does not have (its semi-dynamic objects: " +
                              names_of(pack, false) + ")");
    }
    state->set_object_visible(static_cast<uint32_t>(i), visible);
  }
}

}  // namespace lightpatch::tool
