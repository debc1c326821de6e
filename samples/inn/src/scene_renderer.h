// SceneRenderer: draws the inn as albedo x light map (plus the glow of emissive flames) into the
// bound framebuffer. Every GL object is created in init(); draw() creates none. The light map is
// the runtime's light map plus its indirect map where the pack has one (runtime.h), both sampled
// bilinearly at the same light-map UV.
//
// Shading: the light map holds irradiance E (linear, the lights' units); a Lambertian surface of
// albedo a has radiance a * E / pi. Radiance is exposed, tone mapped (1 - exp(-exposure * L)) and
// encoded with the sRGB curve for an ordinary 8-bit framebuffer.
//
// The carried item (HeldItem) is drawn the same way, with the irradiance of the light probes
// where it is instead of the light map: E(n) from the 9 SH coefficients per channel evaluated per
// fragment for the triangle's normal, clamped at 0.
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

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
    int viewport_width = 0, viewport_height = 0;
  };
  // Draws into the currently bound framebuffer; clears it first.
  void draw(const Frame& frame);

 private:
  const World* world_ = nullptr;
  uint32_t program_ = 0, vao_ = 0, vbo_ = 0, ibo_ = 0;
  uint32_t black_ = 0;  // 1x1 zero texture sampled as the indirect map of packs without one
  int view_projection_location_ = -1, light_map_location_ = -1, exposure_location_ = -1,
      flames_location_ = -1, indirect_map_location_ = -1;
  uint32_t held_program_ = 0;
  int held_view_projection_location_ = -1, held_model_location_ = -1, held_sh_location_ = -1,
      held_exposure_location_ = -1;
};

}  // namespace lightpatch::inn
