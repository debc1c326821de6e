// The inn: a procedurally built scene for the demo (issue 6, paper §4 and §6).
//
// Rooms (metres, +Y up, floor at y = 0, ceilings at 3 m): a dining room, a corridor, two bedrooms,
// two living rooms with fireplaces (the main one holds the spell's altar), a bathing room, and a
// cellar below the dining room reached by stairs. Rooms are closed boxes (walls, floor, ceiling)
// joined by door tunnels; windows open to the night with moonlight outside.
//
// Outputs of generate_inn():
// - the scene (SceneBuilder): static room meshes, semi-dynamic lights (extras.semiDynamic,
//   extras.lightRadius), a lantern the player carries (a moving light: extras.moving, lit on its
//   hook in the dining room) and semi-dynamic objects (the spell book, the ingredients and tools,
//   and their `placed_<item>` copies in front of the main fireplace);
// - `state`: the initial scene state in DESIGN.md's format (lights that start off, placed items
//   hidden);
// - `scenario`: the scripted steps for the game (see write_inn()): after the dark start, the
//   player takes the lantern ("carry") and walks it through the door to the altar ("move" steps
//   whose state gives the lantern's position), then lights the lights, takes the book, ....
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lightpatch/scenegen/scene_builder.h"

namespace lightpatch::inn {

enum class InnScale {
  kFull,   // the paper's inn: about 225,000 triangles, ≥ 12 semi-dynamic lights
  kSmall,  // two rooms, a few thousand triangles, for fast tests
};

struct InnOptions {
  InnScale scale = InnScale::kFull;
  std::uint32_t seed = 1;  // varies colours, clutter and book sizes, not the layout
  bool lantern = true;     // the carried lantern (a moving light) and its walk in the scenario
};

struct InnStats {
  std::size_t triangles = 0;
  std::size_t semi_dynamic_lights = 0;
  std::size_t static_lights = 0;
  std::size_t moving_lights = 0;  // the lantern (extras.moving)
  std::size_t semi_dynamic_objects = 0;
  std::size_t items = 0;  // ingredients and tools (each also has a placed_ copy)
};

struct Inn {
  scenegen::SceneBuilder scene;
  nlohmann::ordered_json state;     // {"lights": {...}, "objects": {...}}
  nlohmann::ordered_json scenario;  // {"steps": [...]}
  InnStats stats;
};

Inn generate_inn(const InnOptions& options);

// Writes the scene to `path` (.glb or .gltf) and, beside it, `<stem>.state.json` and
// `<stem>.scenario.json`. Throws std::runtime_error on I/O errors.
void write_inn(const Inn& inn, const std::string& path, bool draco);

// Paths of the sidecar files for a scene path.
std::string state_path_for(const std::string& scene_path);
std::string scenario_path_for(const std::string& scene_path);

}  // namespace lightpatch::inn
