// `recompose --backend gles`: the runtime on an EGL surfaceless context, driven like a game would
// (state differences pushed as changes, update() until idle), then the light map read back (and
// the indirect map, added to it magnified on the CPU by indirect_map.h: the CPU recomposer's sum).
// Orientation: the runtime keeps texture row 0 = image top row (glTF v = 0), so glReadPixels'
// first row is the top row and the returned array needs no flip.
#include "gles_backend.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>

#include "lightpatch/cooker/error.h"
#include "lightpatch/half_float.h"
#include "lightpatch/indirect_map.h"
#include "lightpatch/platform/egl_context.h"
#include "lightpatch/runtime.h"
#include "lightpatch/scene_state.h"
#include "state_apply.h"

namespace lightpatch::tool {
namespace {

using cooker::CookError;

constexpr uint64_t kUnlimited = ~0ull >> 1;

// Returns the texels written, by target.
TargetTexels settle(Runtime& runtime) {
  // Each update() with an unlimited budget finishes a rebuild or applies every pending change;
  // a drift-triggered rebuild may need one more.
  TargetTexels written;
  for (int i = 0; i < 64 && !runtime.idle(); ++i) {
    if (runtime.update(kUnlimited) != Status::kOk) throw CookError("GLES backend: GL error");
    written.light_map += runtime.stats().texels - runtime.stats().indirect_texels;
    written.indirect_map += runtime.stats().indirect_texels;
  }
  if (!runtime.idle()) throw CookError("GLES backend: the runtime did not settle");
  return written;
}

void push(const PackView& pack, const SceneState& state, Runtime& runtime) {
  for (uint32_t l = 0; l < state.light_count(); ++l) {
    if (pack.light_is_pane(l)) continue;  // the runtime sets panes from the moving lights
    if (pack.light_moves(l)) {
      const LightPose pose = state.light_pose(l);
      const LightPose have = runtime.light_pose(l);
      if (std::memcmp(&pose, &have, sizeof pose) != 0 &&
          runtime.set_light_pose(l, pose) != Status::kOk) {
        throw CookError("GLES backend: light " + std::to_string(l) + ": pose out of range");
      }
    }
    const LightState want = state.light(l);
    const LightState have = runtime.light(l);
    if (want.on == have.on && want.intensity == have.intensity &&
        std::memcmp(want.color, have.color, sizeof want.color) == 0) {
      continue;
    }
    const Status s = runtime.set_light(l, want);
    if (s == Status::kOutOfRange) {
      const Name n = pack.light_name(l);
      char bound[64];
      std::snprintf(bound, sizeof bound, "%g", double(kHalfMax * runtime.light_map_scale()));
      throw CookError("GLES backend: light '" + std::string(n.data, n.length) +
                      "': the state's light map could exceed " + bound +
                      ", the largest value the runtime's light map holds for this pack (65504 "
                      "times its scale); the state is refused");
    }
    if (s != Status::kOk) {
      throw CookError("GLES backend: light " + std::to_string(l) + ": value out of range");
    }
  }
  for (uint32_t o = 0; o < state.object_count(); ++o) {
    if (state.object_visible(o) != runtime.object_visible(o)) {
      runtime.set_object_visible(o, state.object_visible(o));
    }
  }
}

}  // namespace

void recompose_gles(const PackView& pack, const std::vector<cooker::StateSpec>& states,
                    std::vector<float>* rgb, std::vector<TargetTexels>* costs) {
  char message[256] = {};
  platform::EglContext context;
  if (!context.create_headless(message, sizeof message)) {
    throw CookError(std::string("GLES backend: ") + message);
  }
  Error error;
  Runtime runtime;
  // Every pane follows its moving lights in the first update (the reference: exact factors).
  RuntimeLimits limits;
  limits.max_pane_changes = pack::kMaxPanes;
  if (runtime.open(pack, limits, &error) != Status::kOk) {
    throw CookError(std::string("GLES backend: ") + status_name(error.status) + ": " +
                    error.message);
  }
  SceneState state;
  if (state.init(pack, &error) != Status::kOk) throw CookError(error.message);
  std::vector<TargetTexels> written(1, settle(runtime));  // the authored state's full build
  for (const cooker::StateSpec& spec : states) {
    apply_state(spec, pack, &state);
    push(pack, state, runtime);
    written.push_back(settle(runtime));
  }
  if (costs) *costs = std::move(written);
  const size_t texels = size_t(runtime.width()) * runtime.height();
  std::vector<float> rgba(texels * 4);
  if (runtime.read_light_map(rgba.data(), &error) != Status::kOk) throw CookError(error.message);
  if (pack.has_indirect_map()) {  // max(L + I, 0), as the game samples it
    std::vector<float> indirect(size_t(runtime.indirect_width()) * runtime.indirect_height() * 4);
    if (runtime.read_indirect_map(indirect.data(), &error) != Status::kOk)
      throw CookError(error.message);
    add_magnified_indirect(indirect.data(), 4, runtime.indirect_width(), runtime.indirect_height(),
                           runtime.indirect_scale(), rgba.data(), 4);
  }
  rgb->resize(texels * 3);
  for (size_t i = 0; i < texels; ++i) {
    for (int c = 0; c < 3; ++c) (*rgb)[i * 3 + c] = std::max(rgba[i * 4 + c], 0.0f);
  }
}

}  // namespace lightpatch::tool
