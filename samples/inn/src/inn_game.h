// InnGame: the rules of the inn (paper §6) on top of the runtime. The player lights and snuffs
// candles, torches and fireplaces, takes the spell book and the ingredients, and places each
// ingredient at its spot in front of the main fireplace (the baked, hidden `placed_<item>` copy
// is shown and the carried original stays hidden). When every ingredient is placed the spell
// completes: the main fire flares up in the colour and intensity of the scenario's `spell_done`
// step.
//
// Every change goes through the runtime's wanted state (set_light / set_object_visible) and
// becomes visible when the runtime has recomposed it. Lit flames flicker: animate() changes the
// intensity and colour of lit lights every frame through the incremental path, scheduled so that
// flicker never delays a gameplay change (see animate()).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "lightpatch/runtime.h"
#include "world.h"

namespace lightpatch::inn {

class InnGame {
 public:
  // `scenario`: the generator's OUT.scenario.json (items, placed copies, steps). Throws
  // std::runtime_error when it names lights or objects the pack does not have.
  InnGame(Runtime& runtime, const World& world, const nlohmann::json& scenario);

  // Applies a scene state in DESIGN.md's format (the initial state, a scripted step) to the
  // lights' and objects' base state and to the runtime's wanted state, a moving light's position
  // included. Throws on unknown names and on a position the runtime refuses.
  void apply_state(const nlohmann::json& state);

  // Gameplay actions; false (and nothing changes) when the action does not apply.
  bool set_light_on(uint32_t light, bool on);
  bool take(uint32_t object);  // a visible ingredient or the spell book
  bool place(uint32_t item);   // a carried ingredient (index into items())
  void complete_spell();

  // The lantern (the scenario's "lantern": a light the pack flags moving). The player takes it
  // from its hook; carried, the game moves it (move_lantern(), once a frame before
  // Runtime::update()): the runtime's panes bring its bounce light, the renderer draws its direct
  // light (SceneRenderer::Frame::lantern_*). lantern() is -1 when the pack has none.
  int32_t lantern() const { return lantern_; }
  bool lantern_carried() const { return lantern_carried_; }
  bool take_lantern();
  // Moves the carried lantern to `position` (world space, metres); false when it is not carried
  // or the runtime refuses the pose.
  bool move_lantern(glm::vec3 position);
  glm::vec3 lantern_position() const { return lantern_position_; }
  // Its direct light's factor (colour * intensity, 0 when out): what the light map would hold for
  // it per unit of its baked (intensity 1) light.
  glm::vec3 lantern_factor() const;
  // Every pane the lantern drives shows its target (the runtime has recomposed the last move).
  bool lantern_landed() const;

  // What the interaction key would do for a player at `eye` looking along `forward`.
  struct Target {
    enum Kind { kNone, kLight, kTake, kPlace, kLantern } kind = kNone;
    uint32_t index = 0;  // light, object, or item index
    std::string label;   // e.g. "light candle_dining_0"
  };
  Target target(glm::vec3 eye, glm::vec3 forward) const;
  // Does it; returns a line for the player ("You place the wand.") or "" when nothing applies.
  // Completes the spell when the last ingredient is placed.
  std::string interact(glm::vec3 eye, glm::vec3 forward);
  std::string objective() const;

  // Flicker, once per frame before Runtime::update(budget): lit lights get a new intensity and
  // colour (a smooth function of `time_s`) when that costs no latency: nothing while a rebuild
  // runs, never a light whose last change has not landed, and only as many as fit in the frame's
  // budget after the pending gameplay changes (whose costs the planner knows in advance). Returns
  // how many lights were updated.
  uint32_t animate(double time_s, uint64_t budget);

  // Glow of each light's flame as the light map shows it (0 when out), for SceneRenderer.
  void flame_glow(float* out) const;
  // Objects the light map shows (1) or not (0), for SceneRenderer.
  void shown_objects(uint8_t* out) const;

  // True when the light map shows the light's or object's wanted state (a change has landed).
  bool light_landed(uint32_t light) const;
  bool object_landed(uint32_t object) const;

  struct Item {
    std::string name;
    uint32_t object = 0;  // the ingredient
    uint32_t placed = 0;  // its hidden copy at the altar
    bool carried = false;
    bool is_placed = false;
  };
  const std::vector<Item>& items() const { return items_; }
  bool spell_done() const { return spell_done_; }
  bool base_light_on(uint32_t light) const { return lights_[light].on; }
  const LightState& base_light(uint32_t light) const { return lights_[light]; }
  uint32_t placed_count() const;

 private:
  void push_light(uint32_t light);  // base state -> runtime
  float flicker(uint32_t light, double t, float* tint) const;

  Runtime& rt_;
  const World& world_;
  std::vector<LightState> lights_;      // base (unflickered) state per light
  std::vector<float> authored_factor_;  // max channel of authored colour * intensity
  std::vector<Item> items_;
  int32_t book_ = -1;
  bool book_taken_ = false;
  int32_t spell_light_ = -1;
  LightState spell_state_{true, {0.7f, 0.3f, 1.0f}, 60.0f};
  bool spell_done_ = false;
  int32_t lantern_ = -1;
  bool lantern_carried_ = false;
  glm::vec3 lantern_position_{0.0f};
  std::string book_room_, altar_room_;
  std::vector<std::string> item_rooms_;
  uint32_t flicker_cursor_ = 0;
};

}  // namespace lightpatch::inn
