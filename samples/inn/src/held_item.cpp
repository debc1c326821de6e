#include "held_item.h"

#include <glm/gtc/matrix_transform.hpp>

#include "inn_game.h"
#include "light_meter.h"
#include "lightpatch/spherical_harmonics.h"
#include "world.h"

namespace lightpatch::inn {
glm::vec3 hand_position(const glm::mat4& view) {
  const glm::vec4 in_view(0.14f, -0.16f, -0.45f, 1.0f);
  return glm::vec3(glm::inverse(view) * in_view);
}

glm::vec3 lantern_hand_position(const glm::mat4& view) {
  const glm::vec4 in_view(-0.25f, -0.12f, -0.5f, 1.0f);
  return glm::vec3(glm::inverse(view) * in_view);
}

void light_lantern(const InnGame& game, const World& world, float light_map_scale,
                   SceneRenderer::Frame* frame) {
  if (game.lantern() < 0) return;
  frame->lantern_position = game.lantern_position();
  frame->lantern_factor = game.lantern_factor() / light_map_scale;
  frame->lantern_range = world.lights[static_cast<size_t>(game.lantern())].range;
}

HeldItem hold_item(const InnGame& game, const World& world, const LightProbes& probes,
                   const glm::mat4& view) {
  HeldItem held;
  for (const InnGame::Item& item : game.items()) {
    if (!item.carried || item.object >= world.objects.size()) continue;
    held.position = hand_position(view);
    const float p[3] = {held.position.x, held.position.y, held.position.z};
    if (probes.sample(p, held.sh)) {
      held.object = static_cast<int32_t>(item.object);
      held.model =
          glm::translate(glm::mat4(1.0f), held.position - world.objects[item.object].center);
    }
    break;
  }
  return held;
}

ItemIrradiance item_irradiance(const float sh[kProbeShFloats], glm::vec3 facing) {
  ItemIrradiance r;
  float rgb[3];
  const float n[3] = {facing.x, facing.y, facing.z};
  LightProbes::irradiance(sh, n, rgb);
  r.facing = LightMeter::luminance(rgb);
  // Every Y_k but the constant one averages to 0 over the sphere.
  float y[pack::kProbeShCount];
  sh_basis(0.0f, 0.0f, 1.0f, y);
  const float mean_rgb[3] = {sh[0] * y[0], sh[1] * y[0], sh[2] * y[0]};
  r.mean = LightMeter::luminance(mean_rgb);
  return r;
}

}  // namespace lightpatch::inn
