// Player: the first-person walker (feet position, view angles) moved through a CollisionGrid.
#pragma once

#include <glm/glm.hpp>

namespace lightpatch::inn {

class CollisionGrid;

struct PlayerInput {
  float forward = 0.0f;  // -1..1 (W/S)
  float right = 0.0f;    // -1..1 (D/A)
  float turn = 0.0f;     // radians to add to yaw (mouse, arrow keys)
  float look = 0.0f;     // radians to add to pitch
  bool run = false;
};

class Player {
 public:
  static constexpr float kEyeHeight = 1.6f;
  static constexpr float kRadius = 0.22f;
  static constexpr float kStep = 0.35f;  // highest ledge walked up without jumping
  static constexpr float kHeight = 1.75f;

  // Places the eye at `eye`, looking towards `target`.
  void place(glm::vec3 eye, glm::vec3 target);
  // Moves by `dt` seconds of input, sliding along walls and following floors and stairs.
  void update(float dt, const PlayerInput& input, const CollisionGrid& grid);

  glm::vec3 eye() const { return feet_ + glm::vec3(0.0f, kEyeHeight, 0.0f); }
  glm::vec3 forward() const;  // unit view direction
  glm::mat4 view() const;

 private:
  glm::vec3 feet_{0.0f};
  float yaw_ = 0.0f;    // radians; 0 looks along -Z
  float pitch_ = 0.0f;  // radians; positive looks up
  float fall_speed_ = 0.0f;
};

}  // namespace lightpatch::inn
