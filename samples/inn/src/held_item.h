// HeldItem: the ingredient the player carries, shown in front of the camera (lower right, like a
// hand holding it) and lit by the pack's light probes: LightProbes::sample() at the item's centre
// gives the irradiance SH that SceneRenderer shades its triangles with. A moving thing lit by the
// semi-dynamic lights: it brightens when a candle beside it is lit and darkens when it is snuffed.
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

#include "lightpatch/light_probes.h"
#include "scene_renderer.h"

namespace lightpatch::inn {

class InnGame;
struct World;

struct HeldItem {
  int32_t object = -1;       // world object index of the carried item; -1: none (or no probes)
  glm::vec3 position{0.0f};  // its centre, world space (metres)
  glm::mat4 model{1.0f};     // moves its baked triangles there
  float sh[kProbeShFloats] = {};
};

// Where the hand holds an item for a camera with this view matrix (world to view): 0.45 m ahead,
// 0.14 m right and 0.16 m down in view space.
glm::vec3 hand_position(const glm::mat4& view);
// Where the other hand holds the lantern: 0.5 m ahead, 0.25 m left and 0.12 m down.
glm::vec3 lantern_hand_position(const glm::mat4& view);
// The lantern's direct light (on its hook or carried) into the frame: its position, range and
// factor in the light map texture's units (`light_map_scale`: Runtime::light_map_scale()), as the
// maps it is added to. Nothing when the game has no lantern.
void light_lantern(const InnGame& game, const World& world, float light_map_scale,
                   SceneRenderer::Frame* frame);

// The first carried item of `game` at the hand of a camera with this view, with the probes' SH
// there. object -1 when nothing is carried or the pack has no probes there. Allocates nothing.
HeldItem hold_item(const InnGame& game, const World& world, const LightProbes& probes,
                   const glm::mat4& view);

// What the probes' SH gives a point (irradiance luminance, the light map's units): facing the
// unit direction `facing` (clamped at 0) and the mean over all directions (the SH's constant term).
struct ItemIrradiance {
  float facing = 0.0f;
  float mean = 0.0f;
};
ItemIrradiance item_irradiance(const float sh[kProbeShFloats], glm::vec3 facing);

}  // namespace lightpatch::inn
