// `lightpatch bench PACK [--json]`: the GLES runtime's costs on the current driver (an EGL
// surfaceless context): full rebuild, incremental light change, object toggle, frames at several
// budgets, GPU memory by texture, and the fill-rate floor measured in the same run (the rebuild's
// texel count as full-target blended quads with the same program) with the rebuild's ratio to it.
// Times are wall-clock around glFinish(); each is the median of several runs.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/platform/clock.h"
#include "lightpatch/platform/egl_context.h"
#include "lightpatch/platform/file_mapping.h"
#include "lightpatch/platform/gl.h"
#include "lightpatch/runtime.h"
#include "limit_options.h"
#include "verbs.h"

namespace lightpatch::tool {
namespace {

using cooker::CookError;
constexpr uint64_t kUnlimited = ~0ull >> 1;
constexpr int kRepeats = 7;

void check(Status s, const char* what) {
  if (s != Status::kOk) throw CookError(std::string("bench: ") + what + ": " + status_name(s));
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Texels a change wrote (FrameStats), split by target.
struct ChangeTexels {
  uint64_t total = 0, indirect = 0;
  bool operator<(const ChangeTexels& o) const { return total < o.total; }
};
ChangeTexels change_texels(const FrameStats& s) {
  return ChangeTexels{s.texels, s.indirect_texels};
}
ChangeTexels median(std::vector<ChangeTexels> v) {
  if (v.empty()) return ChangeTexels();
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
nlohmann::ordered_json change_json(double ms, const ChangeTexels& t) {
  return {{"ms", ms},
          {"texels", t.total},
          {"light_map_texels", t.total - t.indirect},
          {"indirect_map_texels", t.indirect}};
}

// Runs update(kUnlimited) until idle; returns milliseconds including glFinish.
double timed_settle(Runtime& rt) {
  glFinish();
  const uint64_t t0 = platform::monotonic_ns();
  for (int i = 0; i < 64 && !rt.idle(); ++i) check(rt.update(kUnlimited), "update");
  glFinish();
  return platform::elapsed_ms(t0, platform::monotonic_ns());
}

struct BudgetRun {
  uint64_t budget = 0;
  uint32_t rebuild_frames = 0;
  double max_frame_ms = 0, mean_frame_ms = 0;
  uint32_t light_change_frames = 0, object_toggle_frames = 0;
  uint64_t max_frame_texels = 0;
};

// Frames (each timed with glFinish) until idle; returns the frame count.
uint32_t frames_until_idle(Runtime& rt, uint64_t budget, BudgetRun* run, double* total_ms,
                           uint32_t* frames_timed) {
  uint32_t frames = 0;
  while (!rt.idle() && frames < 1000000) {
    glFinish();
    const uint64_t t0 = platform::monotonic_ns();
    check(rt.update(budget), "update");
    glFinish();
    const double ms = platform::elapsed_ms(t0, platform::monotonic_ns());
    run->max_frame_ms = std::max(run->max_frame_ms, ms);
    run->max_frame_texels = std::max(run->max_frame_texels, rt.stats().texels);
    *total_ms += ms;
    ++*frames_timed;
    ++frames;
  }
  return frames;
}

}  // namespace

int verb_bench(Args& args) {
  const RecomposeLimits limits = parse_recompose_limits(args);  // options before the positional
  const std::string path = args.positional("PACK");
  const bool json = args.flag("--json");
  args.finish();

  platform::FileMapping mapping;
  char message[256] = {};
  if (!mapping.open(path.c_str(), message, sizeof message)) throw CookError(message);
  PackView pack;
  Error error;
  if (PackView::open(mapping.data(), mapping.size(), limits, &pack, &error) != Status::kOk) {
    throw CookError(path + ": " + pack_error_text(error));
  }
  platform::EglContext context;
  if (!context.create_headless(message, sizeof message)) {
    throw CookError(std::string("bench: ") + message);
  }
  Runtime rt;
  if (rt.open(pack, RuntimeLimits(), &error) != Status::kOk) {
    throw CookError(std::string("bench: ") + error.message);
  }
  if (!rt.gpu_path()) throw CookError("bench: this driver has no renderable float target");
  timed_settle(rt);  // first build (and driver warm-up)

  // Full rebuild.
  const uint64_t rebuild_texels = rt.planner().rebuild_texels();
  std::vector<double> rebuild_ms, floor_ms, light_ms, object_ms;
  uint32_t rebuild_draws = 0;
  for (int i = 0; i < kRepeats; ++i) {
    rt.request_rebuild();
    rebuild_ms.push_back(timed_settle(rt));
    rebuild_draws = rt.stats().draws;
  }
  // Fill-rate floor: the same texel count, full-target passes.
  for (int i = 0; i < kRepeats; ++i) {
    glFinish();
    const uint64_t t0 = platform::monotonic_ns();
    if (rt.draw_fill_floor(rebuild_texels, &error) != Status::kOk) throw CookError(error.message);
    glFinish();
    floor_ms.push_back(platform::elapsed_ms(t0, platform::monotonic_ns()));
    timed_settle(rt);  // the floor overwrote the accumulator: the runtime rebuilds (untimed)
  }
  // Incremental light change (intensity x0.5 and back) and object toggle.
  // Texels of the median change: a change that tips the drift bound also runs a rebuild in its
  // frame (planner.h), which the maximum would report as the change's cost.
  std::vector<ChangeTexels> light_texel_runs, object_texel_runs;
  if (rt.light_count() > 0) {
    const float authored = rt.light(0).intensity;
    for (int i = 0; i < kRepeats; ++i) {
      check(rt.set_light_intensity(0, i % 2 ? authored : authored * 0.5f), "set light");
      light_ms.push_back(timed_settle(rt));
      light_texel_runs.push_back(change_texels(rt.stats()));
    }
  }
  if (rt.object_count() > 0) {
    for (int i = 0; i < kRepeats; ++i) {
      check(rt.set_object_visible(0, !rt.object_visible(0)), "toggle object");
      object_ms.push_back(timed_settle(rt));
      object_texel_runs.push_back(change_texels(rt.stats()));
    }
    if (!rt.object_visible(0)) check(rt.set_object_visible(0, true), "toggle object");
    timed_settle(rt);
  }
  // Budgets.
  std::vector<BudgetRun> runs;
  const uint64_t clear = uint64_t(rt.width()) * rt.height();
  const uint64_t budgets[] = {std::max<uint64_t>(rebuild_texels / 16, 1024),
                              std::max<uint64_t>(rebuild_texels / 4, 1024), clear, rebuild_texels};
  for (uint64_t budget : budgets) {
    BudgetRun run;
    run.budget = budget;
    double total = 0;
    uint32_t timed = 0;
    rt.request_rebuild();
    run.rebuild_frames = frames_until_idle(rt, budget, &run, &total, &timed);
    if (rt.light_count() > 0) {
      const LightState s = rt.light(0);
      check(rt.set_light_on(0, !s.on), "set light");
      run.light_change_frames = frames_until_idle(rt, budget, &run, &total, &timed);
      check(rt.set_light_on(0, s.on), "set light");
      frames_until_idle(rt, budget, &run, &total, &timed);
    }
    if (rt.object_count() > 0) {
      check(rt.set_object_visible(0, false), "toggle object");
      run.object_toggle_frames = frames_until_idle(rt, budget, &run, &total, &timed);
      check(rt.set_object_visible(0, true), "toggle object");
      frames_until_idle(rt, budget, &run, &total, &timed);
    }
    run.mean_frame_ms = timed ? total / timed : 0.0;
    runs.push_back(run);
  }

  const RuntimeMemory mem = rt.memory();
  const double rebuild = median(rebuild_ms), floor = median(floor_ms);
  const ChangeTexels light_texels = median(light_texel_runs);
  const ChangeTexels object_texels = median(object_texel_runs);
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  nlohmann::ordered_json j;
  j["pack"] = path;
  j["renderer"] = renderer ? renderer : "";
  j["lightmap"] = {rt.width(), rt.height()};
  j["indirect_map"] = {rt.indirect_width(), rt.indirect_height()};
  j["indirect_scale"] = rt.indirect_scale();
  j["path"] = path_name(rt.path());
  j["accumulator_rounding"] = {{"unit_roundoff", rt.precision().unit_roundoff},
                               {"truncates", rt.precision().truncates}};
  j["patches"] = pack.patch_count();
  j["groups"] = pack.group_count();
  j["full_rebuild"] = {{"ms", rebuild}, {"texels", rebuild_texels}, {"draws", rebuild_draws}};
  j["fill_floor"] = {{"ms", floor}, {"texels", rebuild_texels}};
  j["rebuild_to_floor_ratio"] = floor > 0 ? rebuild / floor : 0.0;
  if (!light_ms.empty()) j["light_change"] = change_json(median(light_ms), light_texels);
  if (!object_ms.empty()) j["object_toggle"] = change_json(median(object_ms), object_texels);
  nlohmann::ordered_json jb = nlohmann::ordered_json::array();
  for (const BudgetRun& r : runs) {
    jb.push_back({{"budget_texels", r.budget},
                  {"rebuild_frames", r.rebuild_frames},
                  {"light_change_frames", r.light_change_frames},
                  {"object_toggle_frames", r.object_toggle_frames},
                  {"max_frame_texels", r.max_frame_texels},
                  {"max_frame_ms", r.max_frame_ms},
                  {"mean_frame_ms", r.mean_frame_ms}});
  }
  j["budgets"] = jb;
  j["gpu_memory_bytes"] = {{"atlases", mem.atlases},
                           {"light_map", mem.light_map},
                           {"accumulator", mem.accumulator},
                           {"indirect_map", mem.indirect_map},
                           {"indirect_accumulator", mem.indirect_accumulator},
                           {"vertex_buffer", mem.vertex_buffer},
                           {"index_buffer", mem.index_buffer}};
  if (json) {
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("pack %s on %s, light map %ux%u, %u patches in %u groups\n", path.c_str(),
              renderer ? renderer : "?", rt.width(), rt.height(), pack.patch_count(),
              pack.group_count());
  if (pack.has_indirect_map()) {
    std::printf("indirect map %ux%u (1/%u per axis)\n", rt.indirect_width(), rt.indirect_height(),
                rt.indirect_scale());
  }
  std::printf("path %s, accumulator unit roundoff %g%s\n", path_name(rt.path()),
              double(rt.precision().unit_roundoff), rt.precision().truncates ? " (truncates)" : "");
  std::printf("full rebuild     %8.3f ms  (%llu texels, %u draws)\n", rebuild,
              static_cast<unsigned long long>(rebuild_texels), rebuild_draws);
  std::printf("fill-rate floor  %8.3f ms  (same texels, full-target passes): ratio %.2fx\n", floor,
              floor > 0 ? rebuild / floor : 0.0);
  auto print_change = [](const char* what, double ms, const ChangeTexels& t) {
    std::printf("%-16s %8.3f ms  (%llu texels: %llu light map, %llu indirect map)\n", what, ms,
                static_cast<unsigned long long>(t.total),
                static_cast<unsigned long long>(t.total - t.indirect),
                static_cast<unsigned long long>(t.indirect));
  };
  if (!light_ms.empty()) print_change("light change", median(light_ms), light_texels);
  if (!object_ms.empty()) print_change("object toggle", median(object_ms), object_texels);
  std::printf(
      "budget (texels)  rebuild frames  light frames  toggle frames  max frame ms  mean ms\n");
  for (const BudgetRun& r : runs) {
    std::printf("%15llu  %14u  %12u  %13u  %12.3f  %7.3f\n",
                static_cast<unsigned long long>(r.budget), r.rebuild_frames, r.light_change_frames,
                r.object_toggle_frames, r.max_frame_ms, r.mean_frame_ms);
  }
  std::printf(
      "GPU memory: atlases %llu B, light map %llu B, accumulator %llu B, indirect map %llu B, "
      "indirect accumulator %llu B, vertices %llu B, indices %llu B\n",
      static_cast<unsigned long long>(mem.atlases), static_cast<unsigned long long>(mem.light_map),
      static_cast<unsigned long long>(mem.accumulator),
      static_cast<unsigned long long>(mem.indirect_map),
      static_cast<unsigned long long>(mem.indirect_accumulator),
      static_cast<unsigned long long>(mem.vertex_buffer),
      static_cast<unsigned long long>(mem.index_buffer));
  return 0;
}

}  // namespace lightpatch::tool
