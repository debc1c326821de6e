#include "player.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "collision_grid.h"

namespace lightpatch::inn {

void Player::place(glm::vec3 eye, glm::vec3 target) {
  feet_ = eye - glm::vec3(0.0f, kEyeHeight, 0.0f);
  const glm::vec3 d = target - eye;
  yaw_ = std::atan2(-d.x, -d.z);
  pitch_ = std::atan2(d.y, std::sqrt(d.x * d.x + d.z * d.z));
  fall_speed_ = 0.0f;
}

glm::vec3 Player::forward() const {
  return glm::vec3(-std::sin(yaw_) * std::cos(pitch_), std::sin(pitch_),
                   -std::cos(yaw_) * std::cos(pitch_));
}

glm::mat4 Player::view() const {
  return glm::lookAt(eye(), eye() + forward(), glm::vec3(0.0f, 1.0f, 0.0f));
}

void Player::update(float dt, const PlayerInput& input, const CollisionGrid& grid) {
  yaw_ += input.turn;
  pitch_ = std::clamp(pitch_ + input.look, -1.45f, 1.45f);
  const glm::vec3 fwd(-std::sin(yaw_), 0.0f, -std::cos(yaw_));
  const glm::vec3 right(-fwd.z, 0.0f, fwd.x);
  glm::vec3 move = fwd * input.forward + right * input.right;
  if (glm::length(move) > 1.0f) move = glm::normalize(move);
  const float speed = input.run ? 4.0f : 2.0f;
  move *= speed * dt;
  // Sub-steps no longer than a quarter of the radius, so nothing thin is walked through.
  const int steps = std::max(1, static_cast<int>(std::ceil(glm::length(move) / (0.25f * kRadius))));
  const glm::vec3 d = move / static_cast<float>(steps);
  for (int i = 0; i < steps; ++i) {
    // Slide: the whole step, else its x part, else its z part.
    for (const glm::vec3 attempt : {d, glm::vec3(d.x, 0.0f, 0.0f), glm::vec3(0.0f, 0.0f, d.z)}) {
      glm::vec3 next = feet_ + attempt;
      const auto floor = grid.floor_at(next, 0.5f * kRadius, kStep, kStep);
      if (floor) next.y = std::max(next.y, *floor);  // step up onto the ledge before testing
      if (!grid.blocked(next, kRadius, kStep, kHeight)) {
        feet_ = next;
        break;
      }
    }
  }
  // Stand on the floor, or fall towards the next one below.
  const auto floor = grid.floor_at(feet_, 0.5f * kRadius, kStep, 50.0f);
  if (floor && *floor >= feet_.y - 1e-3f) {
    feet_.y = *floor;
    fall_speed_ = 0.0f;
  } else if (floor) {
    fall_speed_ += 9.81f * dt;
    feet_.y = std::max(*floor, feet_.y - fall_speed_ * dt);
    if (feet_.y == *floor) fall_speed_ = 0.0f;
  }
}

}  // namespace lightpatch::inn
