// Scene state files (DESIGN.md, Scene state): overrides by glTF node name. Parsed by the tool for
// bake-state and recompose; names the scene or pack lacks are an error naming them.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "lightpatch/cooker/scene.h"

namespace lightpatch::cooker {

// A scene state as DESIGN.md's state JSON gives it: overrides by glTF node name.
struct LightOverride {
  bool has_on = false, on = true;
  bool has_color = false;
  float color[3] = {1, 1, 1};
  bool has_intensity = false;
  float intensity = 1;
  // A moving light's pose (world space, metres; direction: unit after parsing).
  bool has_position = false;
  float position[3] = {0, 0, 0};
  bool has_direction = false;
  float direction[3] = {0, 0, -1};
};
struct StateSpec {
  std::map<std::string, LightOverride> lights;
  std::map<std::string, bool> objects;  // name -> visible
};
StateSpec parse_state_json(const std::string& text, const std::string& what);  // throws CookError
StateSpec load_state_file(const std::string& path);                            // throws CookError
// --states: one JSON state per non-empty line.
std::vector<StateSpec> load_states_jsonl(const std::string& path);  // throws CookError
// The same from text; `what` (the file's name) prefixes every error with the line number.
std::vector<StateSpec> parse_states_jsonl(const std::string& text, const std::string& what);

// A state resolved against a scene: what every integrator that bakes a state lights with.
struct ResolvedState {
  std::vector<glm::vec3> radiant;  // per Scene::lights: colour * intensity, (0,0,0) when off
  std::vector<uint8_t> visible;    // per Scene::objects: 1 = present
  // per Scene::lights: the pose (the authored one unless the state moves a moving light)
  std::vector<glm::vec3> position, direction;
};
// Static lights keep their authored colour and intensity; throws CookError when the state changes
// a static light, moves a light not marked moving, or names a light or object the scene lacks (or
// has not marked semiDynamic).
ResolvedState resolve_state(const Scene& scene, const StateSpec& state);

}  // namespace lightpatch::cooker
