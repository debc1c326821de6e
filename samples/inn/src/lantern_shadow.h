// LanternShadow: the shadow of the carried lantern's direct light (a moving light's direct light
// is the game's; the light map holds only its bounce light, runtime.h "Moving lights"). A depth
// cube map rendered from the lantern: six 90-degree views of the world's triangles (the static
// range and the visible objects), drawn again only when the lantern moved or an object appeared
// or vanished. SceneRenderer samples it with depth comparison (samplerCubeShadow, bilinear PCF).
//
// Cost, when it is drawn again: per face the camera may look up (view_culling.h), the world's
// static chunks (World::chunks) and visible objects that face can see within the far plane, into
// kFaceSize² depth texels; nothing otherwise. Every GL object is created in init(); update()
// creates none.
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
  // A lantern that moved less than this since the faces were drawn keeps them, looked up from
  // where they were drawn (origin()): a carried lantern then redraws them every second frame
  // at a walk (1.4 m/s, 30 frames/s), and its shadows trail it by at most this much.
  static constexpr float kRedrawDistance = 0.08f;  // metres
  // Occluders farther than this from the lantern are not drawn (its light there is under 1/36 of
  // what it is at 1 m); a surface beyond it is still shadowed by nearer occluders.
  static constexpr float kReach = 6.0f;  // metres
  // Which faces the camera may look up is decided with each face's pyramid widened by this many
  // texels (the lookup's bilinear filter reads across a face's edge) and reaching this far (a
  // fragment beyond the far plane still reads its face: only occluders stop at kReach).
  static constexpr int kFaceMargin = 4;
  static constexpr float kTestReach = 1000.0f;  // metres

  LanternShadow() = default;
  ~LanternShadow();
  LanternShadow(const LanternShadow&) = delete;
  LanternShadow& operator=(const LanternShadow&) = delete;

  // Builds the depth program, the cube texture and its six framebuffers. False with a message.
  bool init(const World& world, char* message, unsigned message_size);

  // Draws the faces again from `position` (world space) out to `far` metres when the position
  // moved by kRedrawDistance or more, or the far plane or `object_visible` ([object count])
  // changed, since they were last drawn; then draws only the faces the camera
  // (`camera`: its view-projection) may look up, and later, from the same origin, any other face
  // on the first frame the camera may look it up. `vao`: the world's vertex array
  // (SceneRenderer's: attribute 0 the position). Restores the bound framebuffer and viewport.
  void update(uint32_t vao, glm::vec3 position, float far, const uint8_t* object_visible,
              const glm::mat4& camera);

  uint32_t texture() const { return texture_; }
  // Where the faces were drawn from (world space, metres): the lookups' origin.
  glm::vec3 origin() const { return position_; }
  float far_plane() const { return far_; }
  // Triangles the last update() drew (0 when it kept every face).
  uint64_t triangles_drawn() const { return triangles_; }

 private:
  const World* world_ = nullptr;
  uint32_t program_ = 0, texture_ = 0;
  uint32_t framebuffers_[6] = {};
  int face_matrix_location_ = -1;
  bool drawn_ = false;
  glm::vec3 position_{0.0f};
  float far_ = 0.0f;
  std::vector<uint8_t> visible_;  // object visibility at the last draw (sized in init())
  uint64_t triangles_ = 0;
  bool fresh_[6] = {};  // the face holds the depths seen from position_
};

}  // namespace lightpatch::inn
