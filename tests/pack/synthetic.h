// Synthetic cooker inputs for the pack tests: a Scene, a Layout and BakedMaps built in code
// (no glTF, no baking), with smooth light blobs, shadow discs and bounce (negative) rims.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/scene.h"

namespace lightpatch::test {

struct SyntheticOptions {
  int width = 48, height = 40;
  int lights = 3;
  int objects = 2;
  bool three_channel_light = true;  // light 0's C_l and S_0l have 3 channels (tinted bounce)
  int tinted_lights = 1;  // with three_channel_light: lights 0 .. tinted_lights - 1 are tinted
  bool with_meshes = true;
  uint32_t seed = 1;
};

struct Synthetic {
  cooker::Scene scene;
  cooker::Layout layout;
  cooker::BakedMaps maps;
};

Synthetic make_synthetic(const SyntheticOptions& options);

// The two packs committed in tests/data/packs (the runtime tests' inputs).
std::vector<uint8_t> build_small_pack();  // small.lpk: 3 lights, 2 objects, 48x40
std::vector<uint8_t> build_tiny_pack();   // tiny.lpk: 1 light, 1 object, 16x8, no meshes

}  // namespace lightpatch::test
