// SceneRenderer: draws the inn as albedo x light map (plus the glow of emissive flames) into the
// bound framebuffer. Every GL object is created in init(); draw() creates none. The light map is
// the runtime's light map plus its indirect map where the pack has one (runtime.h), both sampled
// bilinearly at the same light-map UV.
//
// Shading: the light map holds irradiance E (linear, the lights' units); a Lambertian surface of
// albedo a has radiance a * E / pi. Radiance is exposed, tone mapped (1 - exp(-exposure * L)) and
// encoded with the sRGB curve for an ordinary 8-bit framebuffer.
//
// The carried lantern (a moving light) adds its direct light, which the light map leaves to the
// game: the cooker's punctual irradiance from its position, shadowed by LanternShadow's depth cube
// map, and a round glow at the flame.
//
// The carried item (HeldItem) is drawn the same way, with the irradiance of the light probes
// where it is instead of the light map: E(n) from the 9 SH coefficients per channel evaluated per
// fragment for the triangle's normal, clamped at 0.
#pragma once

#include <cstddef>
#include <cstdint>

#include <glm/glm.hpp>

#include "lantern_shadow.h"

namespace lightpatch::inn {

struct World;

class SceneRenderer {
 public:
  static constexpr uint32_t kMaxLights = 128;  // flame glow slots (uniform vec4[32])

  SceneRenderer() = default;
  ~SceneRenderer();
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;

  // Uploads the world's geometry and builds the program. False with a message on failure.
  bool init(const World& world, char* message, unsigned message_size);

  struct Frame {
    glm::mat4 view_projection{1.0f};
    uint32_t light_map = 0;     // RGBA16F irradiance texture (Runtime::light_map_texture())
    uint32_t indirect_map = 0;  // Runtime::indirect_map_texture(), 0 when the pack has none
    const uint8_t* object_visible = nullptr;  // [object count]: draw the object?
    const float* flame = nullptr;             // [light count]: glow of the light's flame (0 = out)
    float exposure = 1.0f;
    // The carried item: world object `held_object` (-1: none) moved by `held_model` and lit by
    // the irradiance SH `held_sh` (27 floats, LightProbes::sample()'s layout).
    int32_t held_object = -1;
    glm::mat4 held_model{1.0f};
    const float* held_sh = nullptr;
    // The lantern: world position (metres), factor (colour * intensity divided by
    // Runtime::light_map_scale(): the light map texture's units; zero: no lantern light), range
    // (metres: its glTF range, 0: unlimited; the shadow's far plane within LanternShadow::kReach).
    // lantern_hidden: no glow sprite (the camera is at the lantern).
    glm::vec3 lantern_position{0.0f};
    glm::vec3 lantern_factor{0.0f};
    float lantern_range = 0.0f;
    bool lantern_hidden = false;
    int viewport_width = 0, viewport_height = 0;
  };
  // What a draw() sent to the GPU, in triangles: the same for a frame on every run, unlike its
  // time.
  struct DrawStats {
    uint64_t scene_triangles = 0;   // the camera's pass: the chunks and objects it can see
    uint64_t shadow_triangles = 0;  // the lantern's cube faces, when they were drawn again
  };
  // Draws into the currently bound framebuffer; clears it first. The camera's pass draws only the
  // static chunks and objects whose bounds meet its view (view_culling.h).
  DrawStats draw(const Frame& frame);

 private:
  const World* world_ = nullptr;
  size_t flame_lights_ = 0;  // lights that may have a flame: the pack's lights before its panes
  uint32_t program_ = 0, vao_ = 0, vbo_ = 0, ibo_ = 0;
  uint32_t black_ = 0;  // 1x1 zero texture sampled as the indirect map of packs without one
  int view_projection_location_ = -1, light_map_location_ = -1, exposure_location_ = -1,
      flames_location_ = -1, indirect_map_location_ = -1;
  LanternShadow shadow_;
  uint32_t glow_program_ = 0;
  int lantern_position_location_ = -1, lantern_factor_location_ = -1, lantern_origin_location_ = -1,
      lantern_planes_location_ = -1, lantern_shadow_location_ = -1;
  int glow_view_projection_location_ = -1, glow_position_location_ = -1,
      glow_exposure_location_ = -1;
  uint32_t held_program_ = 0;
  int held_view_projection_location_ = -1, held_model_location_ = -1, held_sh_location_ = -1,
      held_exposure_location_ = -1;
};

}  // namespace lightpatch::inn
