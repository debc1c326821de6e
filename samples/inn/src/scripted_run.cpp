#include "scripted_run.h"

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "held_item.h"
#include "latency_bound.h"
#include "light_meter.h"
#include "lightpatch/platform/clock.h"
#include "lightpatch/platform/gl.h"
#include "offscreen_target.h"
#include "ray_cast.h"

namespace lightpatch::inn {
namespace {

constexpr double kFrameSeconds = 1.0 / 30.0;  // the scripted clock: reproducible flicker
constexpr int kSettleFrames = 4;              // frames of flicker after a change lands
constexpr int kBenchFrames = 30;

struct FrameRecord {
  uint64_t frame = 0;
  std::string step;
  double total_ms = 0, recompose_ms = 0, render_ms = 0;
  uint64_t texels = 0;
  uint32_t draws = 0, pending = 0, oldest_pending_frames = 0, completed = 0, max_latency = 0;
  bool rebuild_active = false, presented = false;
  uint32_t flicker_updates = 0;
  uint64_t probe_entries = 0;      // LightProbes::update()'s cost this frame
  uint32_t probe_sets = 0;         // probe sets whose factor changed
  SceneRenderer::DrawStats drawn;  // triangles the frame's passes drew
};

struct StepRecord {
  std::string name, action, node;
  uint64_t applied_frame = 0, landed_frame = 0;
  uint32_t latency = 0, bound = 0;
  bool landed = false;
  float meter_before = -1.0f, meter_after = -1.0f;
  // The carried item's light from the probes (unflickered state; -1: nothing carried).
  std::string item;
  ItemIrradiance item_before{-1.0f, -1.0f}, item_after{-1.0f, -1.0f};
  std::string screenshot, error;
  std::string state;  // a lantern move: the game's whole state after it (STATE.json, DESIGN.md)
  // A lantern move carried over frames ("frames" in the step): how many, and their mean total ms.
  uint32_t glide_frames = 0;
  double glide_ms = 0.0;
};

float mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0f : static_cast<float>(s / static_cast<double>(v.size()));
}

nlohmann::json load_steps(const PlaySession& s, const PlayOptions& o) {
  if (o.script == "default") return s.scenario.at("steps");
  std::ifstream f(o.script);
  if (!f)
    throw std::runtime_error("--script: cannot read " + o.script +
                             " (use 'default' or a scenario JSON file)");
  return nlohmann::json::parse(f).at("steps");
}

// Camera of step i: its own, else the next step's that has one, else the previous one's.
bool step_camera(const nlohmann::json& steps, size_t i, glm::vec3* eye, glm::vec3* focus) {
  auto get = [&](size_t k) {
    const nlohmann::json& st = steps[k];
    if (!st.contains("camera") || !st.contains("focus")) return false;
    *eye = glm::vec3(st["camera"][0].get<float>(), st["camera"][1].get<float>(),
                     st["camera"][2].get<float>());
    *focus = glm::vec3(st["focus"][0].get<float>(), st["focus"][1].get<float>(),
                       st["focus"][2].get<float>());
    return true;
  };
  for (size_t k = i; k < steps.size(); ++k)
    if (get(k)) return true;
  for (size_t k = i; k-- > 0;)
    if (get(k)) return true;
  return false;
}

// The scenario's camera sits halfway between the room's centre and the focus, which can be very
// close to it (or inside furniture). Look from farther back along the same direction instead,
// stopping short of the first surface behind.
glm::vec3 frame_camera(const World& world, glm::vec3 camera, glm::vec3 focus) {
  constexpr float kDistance = 2.6f, kClearance = 0.3f;
  glm::vec3 away(camera.x - focus.x, 0.0f, camera.z - focus.z);
  away = glm::length(away) > 1e-3f ? glm::normalize(away) : glm::vec3(1.0f, 0.0f, 0.0f);
  const glm::vec3 want = glm::vec3(focus.x, camera.y, focus.z) + away * kDistance;
  const float length = glm::length(want - focus);
  const glm::vec3 dir = (want - focus) / length;
  RayHit hit;
  const IndexRange all{0, static_cast<uint32_t>(world.indices.size())};
  if (cast_ray(world, all, focus, dir, length, true, &hit)) {
    return focus + dir * std::max(kClearance, hit.distance - kClearance);
  }
  return want;
}

// The light the carried item gets from the probes at the hand, for the game's base (unflickered)
// light state: flicker would make two measurements of the same state differ. `steady` and
// `probes` are the measurement's own state and probes, apart from the frame's.
ItemIrradiance measure_item(const PlaySession& s, const glm::mat4& view, SceneState* steady,
                            LightProbes* probes, std::string* item) {
  ItemIrradiance r{-1.0f, -1.0f};
  const HeldItem held = hold_item(*s.game, s.world, s.probes, view);
  if (held.object < 0) return r;
  *item = s.world.objects[static_cast<size_t>(held.object)].name;
  if (steady->assign(s.runtime.state()) != Status::kOk) return r;
  for (uint32_t l = 0; l < steady->light_count(); ++l) {
    if (steady->light_is_pane(l)) continue;  // follows the moving lights
    if (steady->set_light(l, s.game->base_light(l)) != Status::kOk) return r;
  }
  float sh[kProbeShFloats];
  const float p[3] = {held.position.x, held.position.y, held.position.z};
  if (probes->update(*steady) != Status::kOk || !probes->sample(p, sh)) return r;
  // Facing the nearest light's flame.
  glm::vec3 facing(0.0f, 1.0f, 0.0f);
  float nearest = INFINITY;
  for (const WorldLight& l : s.world.lights) {
    const float d = glm::length(l.position - held.position);
    if (d > 1e-4f && d < nearest) {
      nearest = d;
      facing = (l.position - held.position) / d;
    }
  }
  return item_irradiance(sh, facing);
}

// The game's wanted state in DESIGN.md's format: every light's base (unflickered) state, the
// lantern's position, every object's visibility.
nlohmann::ordered_json game_state(const PlaySession& s) {
  nlohmann::ordered_json lights = nlohmann::ordered_json::object(),
                         objects = nlohmann::ordered_json::object();
  for (uint32_t l = 0; l < s.runtime.light_count(); ++l) {
    if (s.runtime.state().light_is_pane(l)) continue;
    const LightState& b = s.game->base_light(l);
    nlohmann::ordered_json j = {
        {"on", b.on}, {"color", {b.color[0], b.color[1], b.color[2]}}, {"intensity", b.intensity}};
    if (static_cast<int32_t>(l) == s.game->lantern()) {
      const glm::vec3 p = s.game->lantern_position();
      j["position"] = {p.x, p.y, p.z};
    }
    lights[s.world.lights[l].name] = j;
  }
  for (uint32_t o = 0; o < s.runtime.object_count(); ++o)
    objects[s.world.objects[o].name] = {{"visible", s.runtime.object_visible(o)}};
  return {{"lights", lights}, {"objects", objects}};
}

}  // namespace

int run_scripted(PlaySession& s, const PlayOptions& o) {
  Runtime& rt = s.runtime;
  InnGame& game = *s.game;
  const nlohmann::json steps = load_steps(s, o);
  std::filesystem::create_directories(o.out);
  OffscreenTarget target;
  if (!target.init(o.width, o.height))
    throw std::runtime_error("cannot create the offscreen framebuffer");
  LightMeter meter;
  meter.init();
  SceneState steady;
  LightProbes steady_probes;
  {
    Error e;
    if (steady.init(s.pack, &e) != Status::kOk || steady_probes.init(s.pack, &e) != Status::kOk)
      throw std::runtime_error(std::string("light probes: ") + e.message);
  }

  const glm::mat4 projection =
      glm::perspective(glm::radians(70.0f),
                       static_cast<float>(o.width) / static_cast<float>(o.height), 0.05f, 100.0f);
  glm::mat4 view(1.0f);
  std::vector<float> flames(s.world.lights.size());
  std::vector<uint8_t> visible(s.world.objects.size());
  std::vector<FrameRecord> frames;
  frames.reserve(4096);
  std::vector<StepRecord> records;
  std::string caption;
  bool gl_failed = false;
  uint64_t frame_no = 0;

  auto frame = [&](const std::string& step, bool flicker) {
    FrameRecord r;
    r.frame = ++frame_no;
    r.step = step;
    const uint64_t t0 = platform::monotonic_ns();
    r.flicker_updates =
        flicker ? game.animate(static_cast<double>(frame_no) * kFrameSeconds, s.budget) : 0;
    const uint64_t r0 = platform::monotonic_ns();
    Status status = rt.update(s.budget);
    glFinish();
    const uint64_t r1 = platform::monotonic_ns();
    if (status == Status::kOk) status = s.probes.update(rt.planner());
    r.probe_entries = s.probes.stats().entries_last_update;
    r.probe_sets = s.probes.stats().sets_changed_last_update;
    const HeldItem held = hold_item(game, s.world, s.probes, view);
    target.bind();
    game.flame_glow(flames.data());
    game.shown_objects(visible.data());
    SceneRenderer::Frame f;
    f.view_projection = projection * view;
    f.light_map = rt.light_map_texture();
    f.indirect_map = rt.indirect_map_texture();
    f.object_visible = visible.data();
    f.flame = flames.data();
    f.exposure = o.exposure * rt.light_map_scale();
    f.viewport_width = o.width;
    f.viewport_height = o.height;
    f.held_object = held.object;
    f.held_model = held.model;
    f.held_sh = held.sh;
    light_lantern(game, s.world, rt.light_map_scale(), &f);
    r.drawn = s.renderer.draw(f);
    s.overlay.draw(caption.c_str(), 10, 10, o.height >= 400 ? 2.0f : 1.0f, o.width, o.height);
    glFinish();
    const uint64_t t1 = platform::monotonic_ns();
    const GLenum gl_error = glGetError();
    if (status != Status::kOk || gl_error != GL_NO_ERROR) {
      std::fprintf(stderr, "lightpatch-inn: frame %" PRIu64 " (%s): %s, GL error 0x%x\n", frame_no,
                   step.c_str(), status_name(status), gl_error);
      gl_failed = true;
    }
    const FrameStats& st = rt.stats();
    r.total_ms = platform::elapsed_ms(t0, t1);
    r.recompose_ms = platform::elapsed_ms(r0, r1);
    r.render_ms = platform::elapsed_ms(r1, t1);
    r.texels = st.texels;
    r.draws = st.draws;
    r.pending = st.pending_changes;
    r.oldest_pending_frames = st.oldest_pending_frames;
    r.completed = st.completed_changes;
    r.max_latency = st.max_latency_frames;
    r.rebuild_active = st.rebuild_active;
    r.presented = st.presented;
    frames.push_back(r);
  };

  // The initial build of the starting state (a full rebuild spread over frames).
  {
    glm::vec3 eye, focus;
    if (step_camera(steps, 0, &eye, &focus)) {
      view = glm::lookAt(frame_camera(s.world, eye, focus), focus, glm::vec3(0, 1, 0));
    }
    caption = "initial build";
    StepRecord r;
    r.name = "initial_build";
    r.action = "build";
    r.applied_frame = frame_no + 1;
    uint64_t all = uint64_t(rt.width()) * rt.height();
    for (uint32_t g = 0; g < s.pack.group_count(); ++g) all += rt.planner().group_texels(g);
    r.bound = rebuild_frames_bound(s.pack, all, s.budget);
    while (!rt.idle() && frame_no + 1 - r.applied_frame < 4ull * r.bound + 100)
      frame("initial_build", true);
    r.landed = rt.idle();
    r.landed_frame = frame_no;
    r.latency = static_cast<uint32_t>(frame_no - r.applied_frame + 1);
    if (!r.landed || r.latency > r.bound)
      r.error = "the initial build did not complete within its bound";
    records.push_back(r);
  }

  for (size_t i = 0; i < steps.size(); ++i) {
    const nlohmann::json& st = steps[i];
    StepRecord r;
    r.name = st.value("name", "step_" + std::to_string(i));
    r.action = st.value("action", "");
    r.node = st.value("node", "");
    glm::vec3 eye, focus;
    if (step_camera(steps, i, &eye, &focus)) {
      // A close-up (the carried item held beside a light) looks from where the step says.
      const glm::vec3 from = st.value("close_up", false) ? eye : frame_camera(s.world, eye, focus);
      view = glm::lookAt(from, focus, glm::vec3(0, 1, 0));
    }

    int32_t light = -1, object = -1;
    bool lantern_move = false;
    std::vector<glm::ivec2> meter_texels;
    bool applied = true;
    if (r.action == "light" || r.action == "spell_done") {
      light = rt.find_light(r.node.c_str());
      if (light < 0)
        throw std::runtime_error("step " + r.name + ": the pack has no light '" + r.node + "'");
      meter_texels =
          LightMeter::texels_around(s.world, s.world.lights[static_cast<size_t>(light)].position,
                                    rt.width(), rt.height(), 0.1f, 3.0f);
      r.meter_before = meter.measure(rt, meter_texels);
      r.item_before = measure_item(s, view, &steady, &steady_probes, &r.item);
      bool on = true;
      if (r.action == "light" && st.contains("state") && st["state"].contains("lights") &&
          st["state"]["lights"].contains(r.node))
        on = st["state"]["lights"][r.node].value("on", true);
      r.bound = change_latency_bound(rt, s.pack, s.budget, light, -1, !on);
      if (r.action == "light") {
        applied = game.set_light_on(static_cast<uint32_t>(light), on);
      } else {
        game.complete_spell();
      }
    } else if (r.action == "take") {
      object = rt.find_object(r.node.c_str());
      if (object < 0)
        throw std::runtime_error("step " + r.name + ": the pack has no object '" + r.node + "'");
      r.bound = change_latency_bound(rt, s.pack, s.budget, -1, object, false);
      applied = game.take(static_cast<uint32_t>(object));
    } else if (r.action == "place") {
      object = rt.find_object(r.node.c_str());
      applied = false;
      for (uint32_t k = 0; k < game.items().size() && object >= 0; ++k) {
        if (game.items()[k].placed == static_cast<uint32_t>(object)) {
          r.bound = change_latency_bound(rt, s.pack, s.budget, -1, object, false);
          applied = game.place(k);
        }
      }
    } else if (r.action == "carry" || r.action == "move") {
      if (game.lantern() < 0 || rt.find_light(r.node.c_str()) != game.lantern())
        throw std::runtime_error("step " + r.name + ": '" + r.node + "' is not the lantern");
      if (r.action == "carry") {
        applied = game.take_lantern();
      } else {
        const nlohmann::json& at = st.at("state").at("lights").at(r.node).at("position");
        const glm::vec3 p(at.at(0).get<float>(), at.at(1).get<float>(), at.at(2).get<float>());
        // Carried there at a walk: one pose a frame along the way ("frames"), the last one below;
        // the latency counts from the frame of the last pose.
        const int glide = std::max(1, st.value("frames", 1));
        const glm::vec3 from = game.lantern_position();
        const size_t first_frame = frames.size();
        for (int k = 1; k < glide && applied; ++k) {
          applied = game.move_lantern(glm::mix(from, p, float(k) / float(glide)));
          frame(r.name, true);
        }
        r.glide_frames = static_cast<uint32_t>(frames.size() - first_frame);
        for (size_t k = first_frame; k < frames.size(); ++k) r.glide_ms += frames[k].total_ms;
        if (r.glide_frames) r.glide_ms /= r.glide_frames;
        r.bound = moving_light_bound(rt, s.pack, s.budget);
        applied = applied && game.move_lantern(p);
        lantern_move = true;
      }
    } else if (r.action != "start") {
      throw std::runtime_error("step " + r.name + ": unknown action '" + r.action + "'");
    }
    if (!applied) r.error = "the game refused the action";

    // The game's wanted state must be the step's state (DESIGN.md's state format).
    if (st.contains("state")) {
      const nlohmann::json& want = st["state"];
      if (want.contains("lights")) {
        for (const auto& [name, ls] : want["lights"].items()) {
          const int32_t l = rt.find_light(name.c_str());
          if (l < 0) {
            r.error = "state names unknown light " + name;
            continue;
          }
          const LightState& b = game.base_light(static_cast<uint32_t>(l));
          bool same = !ls.contains("on") || ls["on"].get<bool>() == b.on;
          if (ls.contains("intensity")) same = same && ls["intensity"].get<float>() == b.intensity;
          if (ls.contains("color"))
            for (int c = 0; c < 3; ++c)
              same = same && ls["color"][static_cast<size_t>(c)].get<float>() == b.color[c];
          if (ls.contains("position"))
            for (int a = 0; a < 3; ++a)
              same =
                  same && l == game.lantern() &&
                  ls["position"][static_cast<size_t>(a)].get<float>() == game.lantern_position()[a];
          if (!same) r.error = "the game's state of " + name + " differs from the step's";
        }
      }
      if (want.contains("objects")) {
        for (const auto& [name, os] : want["objects"].items()) {
          const int32_t ob = rt.find_object(name.c_str());
          if (ob < 0 || (os.contains("visible") &&
                         os["visible"].get<bool>() != rt.object_visible(static_cast<uint32_t>(ob))))
            r.error = "the game's state of " + name + " differs from the step's";
        }
      }
    }

    char line[160];
    std::snprintf(line, sizeof line, "step %zu/%zu: %s\n", i + 1, steps.size(), r.name.c_str());
    caption = line + game.objective();
    r.applied_frame = frame_no + 1;
    auto landed = [&] {
      if (lantern_move) return game.lantern_landed();
      if (light >= 0) return game.light_landed(static_cast<uint32_t>(light));
      if (object >= 0) return game.object_landed(static_cast<uint32_t>(object));
      return true;
    };
    if (light < 0 && object < 0 && !lantern_move) {
      r.landed = true;
      r.landed_frame = r.applied_frame;
    } else {
      // Run until it lands; past its bound it is a failure, but keep going a while so the run
      // can still show what happens.
      const uint64_t cap = 4ull * r.bound + 100;
      while (frame_no + 1 - r.applied_frame < cap) {
        frame(r.name, true);
        if (landed()) {
          r.landed = true;
          r.landed_frame = frame_no;
          break;
        }
      }
      r.latency = r.landed ? static_cast<uint32_t>(r.landed_frame - r.applied_frame + 1) : 0;
      if (!r.landed)
        r.error = "the change never landed";
      else if (r.latency > r.bound)
        r.error = "landed after its latency bound";
    }
    for (int k = 0; k < kSettleFrames; ++k) frame(r.name, true);
    if (light >= 0) {
      r.meter_after = meter.measure(rt, meter_texels);
      r.item_after = measure_item(s, view, &steady, &steady_probes, &r.item);
    }

    char file[160];
    if (lantern_move) {
      // What `lightpatch recompose --state` and `bake-state --state` take to check this pose.
      std::snprintf(file, sizeof file, "%02zu_%s.state.json", i, r.name.c_str());
      r.state = file;
      std::ofstream((std::filesystem::path(o.out) / file).string())
          << game_state(s).dump(1) << "\n";
    }
    std::snprintf(file, sizeof file, "%02zu_%s.png", i, r.name.c_str());
    r.screenshot = file;
    std::vector<uint8_t> pixels;
    target.read(&pixels);
    if (!write_png((std::filesystem::path(o.out) / file).string().c_str(), o.width, o.height,
                   pixels.data())) {
      r.error = "cannot write " + r.screenshot;
    }
    records.push_back(r);
  }

  // Frame cost with nothing to recompose (flicker paused, the map idle), then with flicker.
  caption = "benchmark: no recomposition";
  while (!rt.idle() && frame_no < 1000000) frame("bench_settle", false);
  for (int k = 0; k < kBenchFrames; ++k) frame("bench_static", false);
  caption = "benchmark: flicker";
  for (int k = 0; k < kBenchFrames; ++k) frame("bench_flicker", true);

  // Drift actually accumulated by the incremental path (against the planner's bound): the map as
  // the flicker left it, against a full rebuild of the same state.
  caption = "drift check";
  while (!rt.idle() && frame_no < 1000000) frame("drift_settle", false);
  const float error_bound = rt.stats().error_bound;
  // Both maps where the pack has an indirect map: the light map's texels, then the indirect map's.
  const size_t light_values = static_cast<size_t>(rt.width()) * rt.height() * 4;
  std::vector<float> incremental(light_values + static_cast<size_t>(rt.indirect_width()) *
                                                    rt.indirect_height() * 4),
      rebuilt(incremental.size());
  Error read_error;
  auto read_maps = [&](std::vector<float>& out) {
    return rt.read_light_map(out.data(), &read_error) == Status::kOk &&
           (rt.indirect_map_texture() == 0 ||
            rt.read_indirect_map(out.data() + light_values, &read_error) == Status::kOk);
  };
  bool drift_read = read_maps(incremental);
  rt.request_rebuild();
  while (!rt.idle() && frame_no < 1000000) frame("drift_rebuild", false);
  drift_read = drift_read && read_maps(rebuilt);
  float drift_max = 0.0f, map_max = 0.0f, drift_relative = 0.0f;
  for (size_t k = 0; k < rebuilt.size(); ++k) {
    if (k % 4 == 3) continue;
    drift_max = std::max(drift_max, std::fabs(incremental[k] - rebuilt[k]));
    map_max = std::max(map_max, std::fabs(rebuilt[k]));
  }
  // Relative to the texel's own value, where that value is not negligible (1% of the maximum).
  for (size_t k = 0; k < rebuilt.size(); ++k) {
    if (k % 4 != 3 && std::fabs(rebuilt[k]) >= 0.01f * map_max) {
      drift_relative =
          std::max(drift_relative, std::fabs(incremental[k] - rebuilt[k]) / std::fabs(rebuilt[k]));
    }
  }
  if (!drift_read) {
    std::fprintf(stderr, "lightpatch-inn: reading the light map back failed: %s\n",
                 read_error.message);
    gl_failed = true;
  }

  // Outputs.
  const std::filesystem::path dir(o.out);
  {
    std::ofstream f(dir / "frames.csv");
    f << "frame,step,total_ms,recompose_ms,render_ms,texels,draws,pending_changes,oldest_pending_"
         "frames,"
         "completed_changes,max_latency_frames,rebuild_active,presented,flicker_updates,probe_"
         "entries,probe_sets_changed,scene_triangles,shadow_triangles\n";
    for (const FrameRecord& r : frames) {
      char row[320];
      std::snprintf(row, sizeof row,
                    "%" PRIu64 ",%s,%.3f,%.3f,%.3f,%" PRIu64 ",%u,%u,%u,%u,%u,%d,%d,%u,%" PRIu64
                    ",%u,%" PRIu64 ",%" PRIu64 "\n",
                    r.frame, r.step.c_str(), r.total_ms, r.recompose_ms, r.render_ms, r.texels,
                    r.draws, r.pending, r.oldest_pending_frames, r.completed, r.max_latency,
                    r.rebuild_active ? 1 : 0, r.presented ? 1 : 0, r.flicker_updates,
                    r.probe_entries, r.probe_sets, r.drawn.scene_triangles,
                    r.drawn.shadow_triangles);
      f << row;
    }
  }
  int failures = gl_failed ? 1 : 0;
  {
    std::ofstream f(dir / "steps.csv");
    f << "step,action,node,applied_frame,landed_frame,latency_frames,bound_frames,landed,meter_"
         "before,meter_after,item,item_facing_before,item_facing_after,item_mean_before,item_mean_"
         "after,screenshot,state,glide_frames,glide_ms,error\n";
    for (const StepRecord& r : records) {
      char row[640];
      std::snprintf(row, sizeof row,
                    "%s,%s,%s,%" PRIu64 ",%" PRIu64
                    ",%u,%u,%d,%.6g,%.6g,%s,%.7g,%.7g,%.7g,%.7g,%s,%s,%u,%.3f,%s\n",
                    r.name.c_str(), r.action.c_str(), r.node.c_str(), r.applied_frame,
                    r.landed_frame, r.latency, r.bound, r.landed ? 1 : 0, r.meter_before,
                    r.meter_after, r.item.c_str(), r.item_before.facing, r.item_after.facing,
                    r.item_before.mean, r.item_after.mean, r.screenshot.c_str(), r.state.c_str(),
                    r.glide_frames, r.glide_ms, r.error.c_str());
      f << row;
      if (!r.error.empty()) {
        std::fprintf(stderr, "lightpatch-inn: step %s: %s\n", r.name.c_str(), r.error.c_str());
        ++failures;
      }
    }
  }
  std::vector<double> idle_total, busy_total, busy_recompose, flicker_recompose, render;
  uint64_t busy_texels = 0, probe_entries = 0, probe_entries_max = 0;
  uint32_t probe_sets_max = 0;
  uint64_t scene_triangles = 0, shadow_triangles = 0, shadow_redraws = 0;
  for (const FrameRecord& r : frames) {
    scene_triangles += r.drawn.scene_triangles;
    shadow_triangles += r.drawn.shadow_triangles;
    shadow_redraws += r.drawn.shadow_triangles > 0 ? 1 : 0;
    probe_entries += r.probe_entries;
    probe_entries_max = std::max(probe_entries_max, r.probe_entries);
    probe_sets_max = std::max(probe_sets_max, r.probe_sets);
    (r.texels ? busy_total : idle_total).push_back(r.total_ms);
    if (r.texels) {
      busy_recompose.push_back(r.recompose_ms);
      busy_texels += r.texels;
    }
    if (r.step == "bench_flicker") flicker_recompose.push_back(r.recompose_ms);
    render.push_back(r.render_ms);
  }
  const RuntimeMemory m = rt.memory();
  nlohmann::ordered_json summary;
  summary["scene"] = o.scene;
  summary["pack"] = o.pack;
  summary["viewport"] = {o.width, o.height};
  summary["lightmap"] = {rt.width(), rt.height()};
  summary["budget_texels"] = s.budget;
  summary["gpu_path"] = rt.gpu_path();
  summary["path"] = path_name(rt.path());
  summary["renderer"] = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  summary["runtime_memory_bytes"] = {{"atlases", m.atlases},
                                     {"light_map", m.light_map},
                                     {"accumulator", m.accumulator},
                                     {"indirect_map", m.indirect_map},
                                     {"indirect_accumulator", m.indirect_accumulator},
                                     {"vertex_buffer", m.vertex_buffer},
                                     {"index_buffer", m.index_buffer},
                                     {"cpu_fallback", m.cpu_fallback}};
  summary["game_geometry_bytes"] =
      s.world.vertices.size() * sizeof(WorldVertex) + s.world.indices.size() * 4;
  summary["frames"] = frames.size();
  summary["frame_ms_without_recomposition"] = mean(idle_total);
  summary["frame_ms_with_recomposition"] = mean(busy_total);
  summary["recompose_ms_mean_when_recomposing"] = mean(busy_recompose);
  summary["recompose_ms_mean_flicker_benchmark"] = mean(flicker_recompose);
  summary["texels_mean_when_recomposing"] =
      busy_recompose.empty()
          ? 0.0
          : static_cast<double>(busy_texels) / static_cast<double>(busy_recompose.size());
  summary["render_ms_mean"] = mean(render);
  const double frame_count = frames.empty() ? 1.0 : static_cast<double>(frames.size());
  // Triangles drawn (the camera culls the world's chunks by its view, view_culling.h) against
  // the world's static and object triangles: deterministic for a scenario. A shadow redraw is a
  // frame that drew any of the lantern's cube faces.
  summary["triangles"] = {
      {"world", s.world.indices.size() / 3},
      {"scene_per_frame_mean", static_cast<double>(scene_triangles) / frame_count},
      {"shadow_redraws", shadow_redraws},
      {"shadow_per_redraw_mean",
       shadow_redraws ? static_cast<double>(shadow_triangles) / static_cast<double>(shadow_redraws)
                      : 0.0}};
  const double probe_entries_mean = static_cast<double>(probe_entries) / frame_count;
  summary["light_probes"] = {{"probes", s.probes.probe_count()},
                             {"memory_bytes", s.probes.memory_bytes()},
                             {"entries_per_frame_mean", probe_entries_mean},
                             {"entries_per_frame_max", probe_entries_max},
                             {"sets_changed_per_frame_max", probe_sets_max},
                             {"rebuild_entries", s.probes.stats().rebuild_entries},
                             {"max_entries_per_probe", s.probes.stats().max_entries_per_probe}};
  summary["drift"] = {{"planner_relative_error_bound", error_bound},
                      {"max_abs_difference_vs_rebuild", drift_max},
                      {"max_relative_difference", drift_relative},
                      {"map_max", map_max},
                      {"drift_tolerance_ulps", o.drift_ulps}};
  summary["failures"] = failures;
  nlohmann::ordered_json js = nlohmann::ordered_json::array();
  for (const StepRecord& r : records) {
    js.push_back({{"step", r.name},
                  {"latency_frames", r.latency},
                  {"bound_frames", r.bound},
                  {"landed", r.landed}});
  }
  summary["steps"] = js;
  std::ofstream(dir / "summary.json") << summary.dump(1) << "\n";

  // "meter": the light map around the step's light; "item": the carried item's probe irradiance
  // facing the nearest light and averaged over directions (luminance; - when nothing is carried).
  std::printf("%-34s %8s %6s %10s %10s %21s %21s\n", "step", "latency", "bound", "meter before",
              "after", "item facing bef/aft", "item mean bef/aft");
  for (const StepRecord& r : records) {
    char item[64] = "-", item_mean[64] = "-";
    if (r.item_before.facing >= 0.0f) {
      std::snprintf(item, sizeof item, "%.4g / %.4g", r.item_before.facing, r.item_after.facing);
      std::snprintf(item_mean, sizeof item_mean, "%.4g / %.4g", r.item_before.mean,
                    r.item_after.mean);
    }
    std::printf("%-34s %8u %6u %10.4g %10.4g %21s %21s%s%s\n", r.name.c_str(), r.latency, r.bound,
                r.meter_before, r.meter_after, item, item_mean,
                r.error.empty() ? "" : "  FAILED: ", r.error.c_str());
  }
  std::printf("light map %ux%u, budget %" PRIu64
              " texels/frame, %zu frames; frame %.2f ms without recomposition, "
              "%.2f ms with (recomposition %.2f ms, %.0f texels)\n",
              rt.width(), rt.height(), s.budget, frames.size(), mean(idle_total), mean(busy_total),
              mean(busy_recompose), summary["texels_mean_when_recomposing"].get<double>());
  std::printf("light probes: %u probes, %" PRIu64
              " bytes; update %.1f entries a frame on average, "
              "at most %" PRIu64 " (%u sets changed); a full rebuild %" PRIu64 " entries\n",
              s.probes.probe_count(), s.probes.memory_bytes(), probe_entries_mean,
              probe_entries_max, probe_sets_max, s.probes.stats().rebuild_entries);
  std::printf(
      "drift after the flicker benchmark: max |incremental - rebuilt| = %.4g (relative %.3g; map "
      "max %.4g, "
      "planner bound %.4g of each texel)\n",
      drift_max, drift_relative, map_max, error_bound);
  std::printf("output: %s (screenshots, frames.csv, steps.csv, summary.json)\n",
              std::filesystem::absolute(dir).string().c_str());
  return failures ? 1 : 0;
}

}  // namespace lightpatch::inn
