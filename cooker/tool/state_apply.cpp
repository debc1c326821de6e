#include "state_apply.h"

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
  for (uint32_t i = 0; i < n && i < kShown; ++i) {
    const Name name = lights ? pack.light_name(i) : pack.object_name(i);
    if (!s.empty()) s += ", ";
    s += cooker::printable(std::string_view(name.data, name.length));
  }
  if (n > kShown) s += " and " + std::to_string(n - kShown) + " more";
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
