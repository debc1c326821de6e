// LanternShadow: the shadow of the carried lantern's direct light (a moving light's direct light
// is the game's; the light map holds only its bounce light, runtime.h "Moving lights"). A depth
// cube map rendered from the lantern: six 90-degree views of the world's triangles (the static
// range and the visible objects), drawn again only when the lantern moved or an object appeared
// or vanished. SceneRenderer samples it with depth comparison (samplerCubeShadow, bilinear PCF).
//
// Cost: six draws of the world's triangles into kFaceSize² depth texels when it is drawn again;
// nothing otherwise. Every GL object is created in init(); update() creates none.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace lightpatch::inn {

struct World;

class LanternShadow {
 public:
  static constexpr int kFaceSize = 256;
  static constexpr float kNear = 0.05f;  // metres: the lantern's glass

  LanternShadow() = default;
  ~LanternShadow();
  LanternShadow(const LanternShadow&) = delete;
  LanternShadow& operator=(const LanternShadow&) = delete;

  // Builds the depth program, the cube texture and its six framebuffers. False with a message.
  bool init(const World& world, char* message, unsigned message_size);

  // Draws the six faces from `position` (world space) out to `far` metres when the position, the
  // far plane or `object_visible` ([object count]) changed since the last call. `vao`: the
  // world's vertex array (SceneRenderer's: attribute 0 the position). Restores the bound
  // framebuffer and viewport it found.
  void update(uint32_t vao, glm::vec3 position, float far, const uint8_t* object_visible);

  uint32_t texture() const { return texture_; }
  float far_plane() const { return far_; }
  // Times the faces were drawn since init() (the scripted run reports it).
  uint64_t redraws() const { return redraws_; }

 private:
  const World* world_ = nullptr;
  uint32_t program_ = 0, texture_ = 0;
  uint32_t framebuffers_[6] = {};
  int face_matrix_location_ = -1;
  bool drawn_ = false;
  glm::vec3 position_{0.0f};
  float far_ = 0.0f;
  std::vector<uint8_t> visible_;  // object visibility at the last draw (sized in init())
  uint64_t redraws_ = 0;
};

}  // namespace lightpatch::inn
