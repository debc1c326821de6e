#include "lightpatch/scene_state.h"

#include <cfloat>
#include <cmath>
#include <new>

namespace lightpatch {

namespace {
bool finite_non_negative(float v) {
  return std::isfinite(v) && v >= 0.0f;
}
}  // namespace

SceneState::~SceneState() {
  delete[] poses_;
  delete[] lights_;
  delete[] visible_;
}

Status SceneState::init(const PackView& pack, Error* error) {
  if (!pack.valid())
    return set_error(error, Status::kInvalidArgument, "scene state: pack not open");
  delete[] poses_;
  delete[] lights_;
  delete[] visible_;
  poses_ = nullptr;
  lights_ = nullptr;
  visible_ = nullptr;
  light_count_ = object_count_ = 0;
  pack_ = PackView();
  const uint32_t nl = pack.light_count();
  const uint32_t no = pack.object_count();
  // One element at least, so that a pack without lights or objects still has valid pointers.
  lights_ = new (std::nothrow) LightState[nl > 0 ? nl : 1];
  poses_ = new (std::nothrow) LightPose[nl > 0 ? nl : 1]();
  visible_ = new (std::nothrow) uint8_t[no > 0 ? no : 1];
  if (lights_ == nullptr || poses_ == nullptr || visible_ == nullptr) {
    delete[] poses_;
    delete[] lights_;
    delete[] visible_;
    poses_ = nullptr;
    lights_ = nullptr;
    visible_ = nullptr;
    return set_error(error, Status::kOutOfMemory,
                     "scene state: cannot allocate %u lights, %u objects", nl, no);
  }
  light_count_ = nl;
  object_count_ = no;
  pack_ = pack;
  reset_to_authored(pack);
  return Status::kOk;
}

void SceneState::reset_to_authored(const PackView& pack) {
  for (uint32_t i = 0; i < light_count_ && i < pack.light_count(); ++i) {
    const pack::LightRecord& r = pack.light(i);
    lights_[i].on = true;
    for (int c = 0; c < 3; ++c) lights_[i].color[c] = r.color[c];
    lights_[i].intensity = r.intensity;
    poses_[i] = LightPose{};
  }
  for (uint32_t k = 0; k < pack.moving_light_count(); ++k) {
    const pack::MovingLightRecord& m = pack.moving_light(k);
    if (m.light < light_count_) poses_[m.light] = authored_pose(m);
  }
  for (uint32_t i = 0; i < object_count_; ++i) visible_[i] = 1;
}

Status SceneState::assign(const SceneState& other) {
  if (other.light_count_ != light_count_ || other.object_count_ != object_count_ ||
      (light_count_ + object_count_ > 0 && lights_ == nullptr)) {
    return Status::kInvalidArgument;
  }
  for (uint32_t i = 0; i < light_count_; ++i) {
    lights_[i] = other.lights_[i];
    poses_[i] = other.poses_[i];
  }
  for (uint32_t i = 0; i < object_count_; ++i) visible_[i] = other.visible_[i];
  return Status::kOk;
}

Status SceneState::set_light(uint32_t i, const LightState& state) {
  if (i >= light_count_ || pack_.light_is_pane(i) || !finite_non_negative(state.intensity) ||
      !finite_non_negative(state.color[0]) || !finite_non_negative(state.color[1]) ||
      !finite_non_negative(state.color[2])) {
    return Status::kInvalidArgument;
  }
  lights_[i] = state;
  return Status::kOk;
}

Status SceneState::set_light_on(uint32_t i, bool on) {
  if (i >= light_count_ || pack_.light_is_pane(i)) return Status::kInvalidArgument;
  lights_[i].on = on;
  return Status::kOk;
}

Status SceneState::set_light_color(uint32_t i, const float rgb[3]) {
  if (i >= light_count_ || pack_.light_is_pane(i) || rgb == nullptr ||
      !finite_non_negative(rgb[0]) || !finite_non_negative(rgb[1]) ||
      !finite_non_negative(rgb[2])) {
    return Status::kInvalidArgument;
  }
  for (int c = 0; c < 3; ++c) lights_[i].color[c] = rgb[c];
  return Status::kOk;
}

Status SceneState::set_light_intensity(uint32_t i, float intensity) {
  if (i >= light_count_ || pack_.light_is_pane(i) || !finite_non_negative(intensity))
    return Status::kInvalidArgument;
  lights_[i].intensity = intensity;
  return Status::kOk;
}

Status SceneState::set_object_visible(uint32_t i, bool visible) {
  if (i >= object_count_) return Status::kInvalidArgument;
  visible_[i] = visible ? 1 : 0;
  return Status::kOk;
}

Status SceneState::set_light_pose(uint32_t i, const LightPose& pose) {
  if (i >= light_count_ || !pack_.light_moves(i)) return Status::kInvalidArgument;
  LightPose p = pose;
  if (!normalise_pose(&p)) return Status::kInvalidArgument;
  poses_[i] = p;
  return Status::kOk;
}

void SceneState::light_factor(uint32_t i, float out_rgb[3]) const {
  if (pack_.light_is_pane(i)) {
    const int32_t k = pack_.pane_index(i);
    if (k >= 0) {
      pane_factor(pack_, uint32_t(k), *this, out_rgb);
      return;
    }
  }
  const LightState& l = lights_[i];
  for (int c = 0; c < 3; ++c) {
    const float f = l.on ? l.color[c] * l.intensity : 0.0f;
    // Two finite values can multiply to infinity; keep the factor finite so that 0 * f stays 0.
    out_rgb[c] = std::isfinite(f) ? f : FLT_MAX;
  }
}

}  // namespace lightpatch
