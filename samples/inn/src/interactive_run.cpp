#include "interactive_run.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "held_item.h"
#include "lightpatch/platform/clock.h"
#include "lightpatch/platform/gl.h"
#include "player.h"

namespace lightpatch::inn {
namespace {

constexpr float kMouseRadiansPerPixel = 0.004f;
constexpr float kKeyTurnRadiansPerSecond = 1.8f;
constexpr double kMessageSeconds = 4.0;
// Keys as the platform reports them (lower-case ASCII), usable as indices.
constexpr uint32_t kW = 'w', kA = 'a', kS = 's', kD = 'd', kUse = 'e';

// The player starts where the scenario's first step with a camera looks from.
void spawn(const nlohmann::json& scenario, Player* player) {
  for (const auto& st : scenario.at("steps")) {
    if (st.contains("camera") && st.contains("focus")) {
      player->place(glm::vec3(st["camera"][0].get<float>(), st["camera"][1].get<float>(),
                              st["camera"][2].get<float>()),
                    glm::vec3(st["focus"][0].get<float>(), st["focus"][1].get<float>(),
                              st["focus"][2].get<float>()));
      return;
    }
  }
  player->place(glm::vec3(1.0f, Player::kEyeHeight, 1.0f),
                glm::vec3(2.0f, Player::kEyeHeight, 2.0f));
}

}  // namespace

int run_interactive(PlaySession& s, const PlayOptions& o) {
  Runtime& rt = s.runtime;
  InnGame& game = *s.game;
  Player player;
  spawn(s.scenario, &player);
  bool keys[512] = {};
  bool have_mouse = false;
  int mouse_x = 0, mouse_y = 0;
  int width = s.context.width(), height = s.context.height();
  std::vector<float> flames(s.world.lights.size());
  std::vector<uint8_t> visible(s.world.objects.size());
  std::string message;
  double message_until = 0.0;
  const uint64_t start = platform::monotonic_ns();
  uint64_t last = start;
  double frame_ms_smoothed = 0.0, recompose_ms_smoothed = 0.0;
  std::vector<double> frame_ms;  // --frames: every frame's time, for the summary
  frame_ms.reserve(static_cast<size_t>(o.frames));
  std::printf("W A S D walk, Shift runs, mouse or arrow keys look, E uses, Esc quits\n");

  for (;;) {
    PlayerInput input;
    platform::InputEvent e;
    bool quit = false, use = false;
    while (s.context.poll_event(&e)) {
      switch (e.type) {
        case platform::InputEvent::kKeyDown:
          if (e.key == platform::kKeyEscape) quit = true;
          if (e.key == kUse && !keys[kUse]) use = true;
          if (e.key < 512) keys[e.key] = true;
          break;
        case platform::InputEvent::kKeyUp:
          if (e.key < 512) keys[e.key] = false;
          break;
        case platform::InputEvent::kMouseMove:
          if (have_mouse) {
            input.turn -= static_cast<float>(e.x - mouse_x) * kMouseRadiansPerPixel;
            input.look -= static_cast<float>(e.y - mouse_y) * kMouseRadiansPerPixel;
          }
          have_mouse = true;
          mouse_x = e.x;
          mouse_y = e.y;
          break;
        case platform::InputEvent::kResize:
          width = e.x;
          height = e.y;
          break;
        case platform::InputEvent::kClose:
          quit = true;
          break;
        case platform::InputEvent::kNone:
          break;
      }
    }
    if (quit || (o.frames && static_cast<int>(frame_ms.size()) >= o.frames)) break;
    const uint64_t now = platform::monotonic_ns();
    // The measured frame time, shown as it is; the simulation steps at most 0.1 s so that a stall
    // does not carry the player through a wall.
    const double real_ms = platform::elapsed_ms(last, now);
    const float dt = std::min(0.1f, static_cast<float>(real_ms * 1e-3));
    last = now;
    if (o.frames && now != start) frame_ms.push_back(real_ms);
    const double time_s = platform::elapsed_ms(start, now) * 1e-3;
    input.forward = (keys[kW] ? 1.0f : 0.0f) - (keys[kS] ? 1.0f : 0.0f);
    input.right = (keys[kD] ? 1.0f : 0.0f) - (keys[kA] ? 1.0f : 0.0f);
    input.turn +=
        ((keys[platform::kKeyLeft] ? 1.0f : 0.0f) - (keys[platform::kKeyRight] ? 1.0f : 0.0f)) *
        kKeyTurnRadiansPerSecond * dt;
    input.look +=
        ((keys[platform::kKeyUp] ? 1.0f : 0.0f) - (keys[platform::kKeyDown] ? 1.0f : 0.0f)) *
        kKeyTurnRadiansPerSecond * dt;
    input.run = keys[platform::kKeyShift];
    player.update(dt, input, *s.grid);
    if (use) {
      const std::string said = game.interact(player.eye(), player.forward());
      if (!said.empty()) {
        message = said;
        message_until = time_s + kMessageSeconds;
      }
    }

    // The carried lantern follows the hand; the runtime moves its bounce light (panes).
    if (game.lantern_carried()) game.move_lantern(lantern_hand_position(player.view()));
    game.animate(time_s, s.budget);
    const uint64_t r0 = platform::monotonic_ns();
    const Status status = rt.update(s.budget);
    const uint64_t r1 = platform::monotonic_ns();
    if (status != Status::kOk) {
      std::fprintf(stderr, "lightpatch-inn: runtime update failed: %s\n", status_name(status));
      return 1;
    }
    // To the state the light map now shows, so the held item changes with the room around it (a
    // few thousand comparisons and the changed sets' entries; no GL work).
    if (s.probes.update(rt.planner()) != Status::kOk) {
      std::fprintf(stderr, "lightpatch-inn: light probe update failed\n");
      return 1;
    }
    const HeldItem held = hold_item(game, s.world, s.probes, player.view());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    game.flame_glow(flames.data());
    game.shown_objects(visible.data());
    SceneRenderer::Frame f;
    const float aspect =
        static_cast<float>(std::max(width, 1)) / static_cast<float>(std::max(height, 1));
    f.view_projection =
        glm::perspective(glm::radians(70.0f), aspect, 0.05f, 100.0f) * player.view();
    f.light_map = rt.light_map_texture();
    f.indirect_map = rt.indirect_map_texture();
    f.object_visible = visible.data();
    f.flame = flames.data();
    f.exposure = o.exposure * rt.light_map_scale();
    f.viewport_width = width;
    f.viewport_height = height;
    f.held_object = held.object;
    f.held_model = held.model;
    f.held_sh = held.sh;
    light_lantern(game, s.world, rt.light_map_scale(), &f);
    s.renderer.draw(f);

    const FrameStats& st = rt.stats();
    frame_ms_smoothed =
        frame_ms_smoothed == 0.0 ? real_ms : 0.9 * frame_ms_smoothed + 0.1 * real_ms;
    recompose_ms_smoothed = 0.9 * recompose_ms_smoothed + 0.1 * platform::elapsed_ms(r0, r1);
    const InnGame::Target target = game.target(player.eye(), player.forward());
    char stats[240];
    std::snprintf(stats, sizeof stats,
                  "%.1f ms/frame (%.0f fps; runtime update %.2f ms), %llu texels recomposed, "
                  "%u pending%s, light probes %llu entries",
                  frame_ms_smoothed, frame_ms_smoothed > 0.0 ? 1e3 / frame_ms_smoothed : 0.0,
                  recompose_ms_smoothed, static_cast<unsigned long long>(st.texels),
                  st.pending_changes, st.rebuild_active ? ", rebuilding" : "",
                  static_cast<unsigned long long>(s.probes.stats().entries_last_update));
    std::string text = game.objective();
    if (target.kind != InnGame::Target::kNone) text += "\n[E] " + target.label;
    if (time_s < message_until) text += "\n" + message;
    text += "\n";
    text += stats;
    s.overlay.draw(text.c_str(), 12, 12, height >= 600 ? 2.0f : 1.0f, width, height);
    // A small cross-hair: where E aims.
    s.overlay.draw("+", width / 2 - 5, height / 2 - 8, 2.0f, width, height);
    const GLenum gl_error = glGetError();
    if (gl_error != GL_NO_ERROR) {
      std::fprintf(stderr, "lightpatch-inn: GL error 0x%x\n", gl_error);
      return 1;
    }
    s.context.swap();
  }
  if (!frame_ms.empty()) {
    std::vector<double> sorted = frame_ms;
    std::sort(sorted.begin(), sorted.end());
    double sum = 0.0;
    for (double v : frame_ms) sum += v;
    const double mean = sum / static_cast<double>(frame_ms.size());
    std::printf(
        "%zu frames at %dx%d, budget %llu texels: frame mean %.1f ms (%.1f fps), median "
        "%.1f ms, 95th percentile %.1f ms, max %.1f ms\n",
        frame_ms.size(), width, height, static_cast<unsigned long long>(s.budget), mean, 1e3 / mean,
        sorted[sorted.size() / 2], sorted[sorted.size() * 95 / 100], sorted.back());
  }
  return 0;
}

}  // namespace lightpatch::inn
