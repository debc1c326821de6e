// PlaySession: everything `lightpatch-inn play` loads before its first frame, in dependency
// order: the GLES context, the scene (glTF), the mapped and validated pack, the runtime on it,
// the world built from both, the collision grid, the renderers and the game rules.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "collision_grid.h"
#include "gltf_scene.h"
#include "inn_game.h"
#include "lightpatch/light_probes.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/platform/egl_context.h"
#include "lightpatch/platform/file_mapping.h"
#include "lightpatch/runtime.h"
#include "scene_renderer.h"
#include "text_overlay.h"
#include "world.h"

namespace lightpatch::inn {

constexpr uint64_t kWindowBudgetTexels = 1u << 18;

struct PlayOptions {
  std::string scene = "demo-out/inn.glb";
  std::string pack = "demo-out/inn.lpk";
  bool headless = false;
  std::string script;         // "default": the scenario beside the scene
  std::string out;            // headless: output folder
  int width = 0, height = 0;  // 0: 960x540
  // Texels recomposed per frame; 0: half the light map's area headless, at most
  // kWindowBudgetTexels in a window (on llvmpipe a full-area frame of recomposition costs about
  // as much as drawing the inn twice).
  uint64_t budget = 0;
  float exposure = 1.5f;
  // The planner's drift tolerance (planner.h) in half-float ulps (2^-11) of each texel's
  // magnitude; the runtime's default, 2. The scripted run measures the real drift against a
  // rebuild (summary.json "drift").
  float drift_ulps = 2.0f;
  bool force_cpu = false;  // the runtime's CPU path (devices without renderable float targets)
  // Windowed: quit after this many frames and print the frame times (0: play until Esc).
  int frames = 0;
};

struct PlaySession {
  platform::EglContext context;
  std::unique_ptr<GltfScene> scene;
  platform::FileMapping mapping;
  PackView pack;
  Runtime runtime;
  // The pack's light probes, for the carried item (HeldItem); each frame, after runtime.update():
  // probes.update(runtime.planner()), the state the light map shows. Empty for a pack without
  // probes.
  LightProbes probes;
  World world;
  std::unique_ptr<CollisionGrid> grid;
  SceneRenderer renderer;
  TextOverlay overlay;
  std::unique_ptr<InnGame> game;
  nlohmann::json scenario;
  nlohmann::json initial_state;
  uint64_t budget = 0;
};

// Creates the context (a window unless options.headless) and loads everything; the game's
// initial state is applied (not yet recomposed). Throws std::runtime_error with a message.
std::unique_ptr<PlaySession> open_session(const PlayOptions& options);

}  // namespace lightpatch::inn
