// The run-time state of a pack's semi-dynamic lights and objects, sized once at load.
//
// A light's factor is f_l = on ? color * intensity : 0 (linear RGB, the light's units); its
// contribution patches were baked for colour (1,1,1), intensity 1. Defaults are the authored
// colour and intensity from the pack, on, and every object visible (DESIGN.md, Scene state).
//
// Moving lights (pack_format.h, "Moving lights"): a light flagged moving also has a pose
// (light_pose(), authored from its MovingLightRecord; set_light_pose()). It has no group: its
// colour, intensity, on and pose set the factors of the pack's panes. A pane (type kLightPane)
// takes no setter (kInvalidArgument: a pane's factor follows the moving lights); its
// light_factor() is f_pane computed from this state's moving lights (moving_lights.h).
#pragma once

#include <cstdint>

#include "lightpatch/moving_lights.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/status.h"

namespace lightpatch {

struct LightState {
  bool on;
  float color[3];   // linear RGB, finite, >= 0
  float intensity;  // finite, >= 0
};

class SceneState {
 public:
  SceneState() = default;
  ~SceneState();
  SceneState(const SceneState&) = delete;
  SceneState& operator=(const SceneState&) = delete;

  // Allocates storage for the pack's lights and objects and resets to the authored defaults.
  // Keeps a copy of the view (its pointers): the pack's bytes must outlive the state.
  Status init(const PackView& pack, Error* error);
  // Authored defaults: every light on with its authored colour/intensity, every object visible.
  void reset_to_authored(const PackView& pack);
  // Copies another state of the same pack (same counts; no allocation).
  Status assign(const SceneState& other);

  uint32_t light_count() const { return light_count_; }
  uint32_t object_count() const { return object_count_; }

  const LightState& light(uint32_t i) const { return lights_[i]; }
  bool object_visible(uint32_t i) const { return visible_[i] != 0; }

  // Setters validate: index in range, values finite and >= 0, not a pane (kInvalidArgument).
  Status set_light(uint32_t i, const LightState& state);
  Status set_light_on(uint32_t i, bool on);
  Status set_light_color(uint32_t i, const float rgb[3]);
  Status set_light_intensity(uint32_t i, float intensity);
  Status set_object_visible(uint32_t i, bool visible);

  // A moving light's pose: position in world space (metres, finite, at most 1e6 from the origin)
  // and direction (finite, unit within 1e-3; stored normalised). kInvalidArgument (state
  // unchanged) for a light not flagged moving or a value outside those ranges.
  Status set_light_pose(uint32_t i, const LightPose& pose);
  // The light's pose: authored or set for a moving light, all zero for any other light.
  const LightPose& light_pose(uint32_t i) const { return poses_[i]; }
  bool light_moves(uint32_t i) const { return pack_.light_moves(i); }
  bool light_is_pane(uint32_t i) const { return pack_.light_is_pane(i); }

  // f_l as linear RGB; for a pane, f_pane from the moving lights' factors and poses (O(moving
  // lights * entry points)).
  void light_factor(uint32_t i, float out_rgb[3]) const;

 private:
  PackView pack_;
  LightPose* poses_ = nullptr;  // [light]
  LightState* lights_ = nullptr;
  uint8_t* visible_ = nullptr;
  uint32_t light_count_ = 0;
  uint32_t object_count_ = 0;
};

}  // namespace lightpatch
