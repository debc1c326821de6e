#include "play_session.h"

#include <algorithm>
#include <fstream>
#include <stdexcept>

namespace lightpatch::inn {
namespace {

nlohmann::json read_json(const std::string& path) {
  std::ifstream f(path);
  if (!f)
    throw std::runtime_error("cannot read " + path +
                             " (written by `lightpatch-inn generate` beside the scene)");
  try {
    return nlohmann::json::parse(f);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

// The sidecar files the generator writes beside OUT.glb (inn_generator.h).
std::string sidecar(const std::string& scene, const char* suffix) {
  const size_t slash = scene.find_last_of('/');
  const size_t dot = scene.find_last_of('.');
  const std::string stem = dot != std::string::npos && (slash == std::string::npos || dot > slash)
                               ? scene.substr(0, dot)
                               : scene;
  return stem + suffix;
}

}  // namespace

std::unique_ptr<PlaySession> open_session(const PlayOptions& options) {
  auto s = std::make_unique<PlaySession>();
  char message[256] = {};
  s->scenario = read_json(sidecar(options.scene, ".scenario.json"));
  s->initial_state = read_json(sidecar(options.scene, ".state.json"));

  if (options.headless) {
    if (!s->context.create_headless(message, sizeof message)) throw std::runtime_error(message);
  } else {
    if (!s->context.create_window(options.width, options.height, "lightpatch: the inn", message,
                                  sizeof message)) {
      throw std::runtime_error(std::string(message) + " (use --headless without a display)");
    }
  }

  s->scene = std::make_unique<GltfScene>(options.scene);
  if (!s->mapping.open(options.pack.c_str(), message, sizeof message))
    throw std::runtime_error(message);
  Error error;
  if (PackView::open(s->mapping.data(), s->mapping.size(), &s->pack, &error) != Status::kOk) {
    throw std::runtime_error(options.pack + ": " + error.message);
  }
  RuntimeLimits limits;
  limits.planner.drift_tolerance = options.drift_ulps / 2048.0f;
  limits.force_cpu_fallback = options.force_cpu;
  if (s->runtime.open(s->pack, limits, &error) != Status::kOk) {
    throw std::runtime_error(options.pack + ": " + error.message);
  }
  if (s->probes.init(s->pack, &error) != Status::kOk) {
    throw std::runtime_error(options.pack + ": light probes: " + error.message);
  }
  // Default budget: half the light map's area headless (every scripted change lands in one
  // frame); in a window at most 2^18 texels, about 8 ms of llvmpipe on two cores, which with the
  // drawing of the inn at 960x540 keeps a frame near 27 ms of CPU time (README, the demo).
  const uint64_t half_map = static_cast<uint64_t>(s->runtime.width()) * s->runtime.height() / 2;
  s->budget = options.budget     ? options.budget
              : options.headless ? half_map
                                 : std::min<uint64_t>(half_map, kWindowBudgetTexels);

  s->world = build_world(*s->scene, s->pack);
  s->grid = std::make_unique<CollisionGrid>(s->world, 0.1f);
  if (!s->renderer.init(s->world, message, sizeof message)) throw std::runtime_error(message);
  if (!s->overlay.init(1024, message, sizeof message))
    throw std::runtime_error(std::string("text overlay: ") + message);
  s->game = std::make_unique<InnGame>(s->runtime, s->world, s->scenario);
  s->game->apply_state(s->initial_state);
  return s;
}

}  // namespace lightpatch::inn
