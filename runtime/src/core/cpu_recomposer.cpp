#include "lightpatch/cpu_recomposer.h"

#include <cstring>
#include <new>

#include "lightpatch/indirect_map.h"

namespace lightpatch {

CpuRecomposer::~CpuRecomposer() {
  delete[] accumulator_;
  delete[] rgb_;
  delete[] combined_;
}

Status CpuRecomposer::init(const PackView& pack, Error* error) {
  if (!pack.valid()) return set_error(error, Status::kInvalidArgument, "recomposer: pack not open");
  if (accumulator_ != nullptr)
    return set_error(error, Status::kInvalidArgument, "recomposer: already initialised");
  pack_ = pack;
  width_ = pack.lightmap_width();
  height_ = pack.lightmap_height();
  const size_t n = size_t(pack.map_texels()) * 3;
  accumulator_ = new (std::nothrow) double[n]();
  rgb_ = new (std::nothrow) float[n]();
  if (pack.has_indirect_map()) combined_ = new (std::nothrow) float[size_t(width_) * height_ * 3]();
  if (!accumulator_ || !rgb_ || (pack.has_indirect_map() && !combined_)) {
    return set_error(error, Status::kOutOfMemory, "recomposer: cannot allocate a %ux%u light map",
                     width_, height_);
  }
  if (Status s = planner_.init(pack_, PlannerLimits(), error); s != Status::kOk) return s;
  // Double accumulation: u = 2^-53, so the incremental path never drifts out of tolerance; the
  // presented floats must stay finite.
  planner_.set_precision(TargetPrecision{1.1102230e-16f, false});
  planner_.set_value_limit(1.0e38f);
  sink_.bind(&pack_, accumulator_, rgb_, nullptr, 1.0f);
  stats_ = Stats();
  return Status::kOk;
}

Status CpuRecomposer::push(const SceneState& state) {
  if (accumulator_ == nullptr || state.light_count() != pack_.light_count() ||
      state.object_count() != pack_.object_count()) {
    return Status::kInvalidArgument;
  }
  for (uint32_t l = 0; l < state.light_count(); ++l) {
    if (state.light_is_pane(l)) {
      // A pane's factor follows the state's moving lights (f_pane, moving_lights.h), exact: the
      // planner multiplies it by intensity 1.
      float f[3];
      state.light_factor(l, f);
      if (Status st = planner_.set_light(l, true, f, 1.0f); st != Status::kOk) return st;
      continue;
    }
    const LightState& s = state.light(l);
    if (Status st = planner_.set_light(l, s.on, s.color, s.intensity); st != Status::kOk) return st;
  }
  for (uint32_t o = 0; o < state.object_count(); ++o) {
    planner_.set_object_visible(o, state.object_visible(o));
  }
  return Status::kOk;
}

Status CpuRecomposer::settle() {
  stats_ = Stats();
  // An unlimited budget finishes a rebuild or every pending change in one update.
  for (int i = 0; i < 4 && !planner_.idle(); ++i) {
    planner_.update(~0ull >> 1, sink_);
    stats_.rebuilt |= planner_.stats().presented;
    stats_.texels_drawn += planner_.stats().texels;
    stats_.indirect_texels_drawn += planner_.stats().indirect_texels;
  }
  if (combined_) {
    std::memcpy(combined_, rgb_, sizeof(float) * width_ * height_ * 3);
    add_magnified_indirect(indirect_map(), 3, pack_.indirect_width(), pack_.indirect_height(),
                           pack_.indirect_scale(), combined_, 3);
    // What a game lights with: max(L + I, 0) (pack_format.h, "Two target maps").
    for (size_t i = 0; i < size_t(width_) * height_ * 3; ++i)
      combined_[i] = combined_[i] > 0.0f ? combined_[i] : 0.0f;
  }
  return planner_.idle() ? Status::kOk : Status::kInvalidArgument;
}

Status CpuRecomposer::rebuild(const SceneState& state) {
  if (Status s = push(state); s != Status::kOk) return s;
  planner_.request_rebuild();
  return settle();
}

Status CpuRecomposer::apply(const SceneState& state) {
  if (Status s = push(state); s != Status::kOk) return s;
  return settle();
}

}  // namespace lightpatch
