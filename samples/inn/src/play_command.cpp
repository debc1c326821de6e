#include "play_command.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "interactive_run.h"
#include "play_session.h"
#include "scripted_run.h"

namespace lightpatch::inn {
namespace {

int usage() {
  std::fprintf(
      stderr,
      "usage: lightpatch-inn play [--scene inn.glb] [--pack inn.lpk] [--size WxH] [--budget "
      "TEXELS]\n"
      "                           [--exposure F] [--drift-ulps F] [--cpu]\n"
      "       lightpatch-inn play --headless [--script default|SCENARIO.json] --out DIR [same "
      "options]\n"
      "  defaults: --scene demo-out/inn.glb --pack demo-out/inn.lpk (what ./run demo makes);\n"
      "  the budget is texels recomposed per frame (default: half the light map's area);\n"
      "  --drift-ulps is the planner's drift tolerance (default 512).\n"
      "  Window: W A S D walk, Shift runs, mouse or arrow keys look, E uses, Esc quits.\n"
      "  Headless: plays the scenario beside the scene, writes screenshots, frames.csv,\n"
      "  steps.csv and summary.json to DIR; exits 1 if a step fails.\n");
  return 2;
}

bool parse_size(const std::string& s, int* w, int* h) {
  char* end = nullptr;
  const long a = std::strtol(s.c_str(), &end, 10);
  if (!end || *end != 'x') return false;
  const long b = std::strtol(end + 1, &end, 10);
  if (*end != '\0' || a < 16 || b < 16 || a > 8192 || b > 8192) return false;
  *w = static_cast<int>(a);
  *h = static_cast<int>(b);
  return true;
}

bool parse_float(const std::string& s, float* out) {
  char* end = nullptr;
  const float v = std::strtof(s.c_str(), &end);
  if (s.empty() || *end != '\0' || !std::isfinite(v) || v <= 0.0f) return false;
  *out = v;
  return true;
}

}  // namespace

int play_command(int argc, char** argv) {
  PlayOptions o;
  bool window = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "lightpatch-inn play: %s needs a value\n", a.c_str());
        return nullptr;
      }
      return argv[++i];
    };
    const char* v = nullptr;
    if (a == "--help" || a == "-h") {
      usage();
      return 0;
    } else if (a == "--headless") {
      o.headless = true;
    } else if (a == "--window") {
      window = true;
    } else if (a == "--cpu") {
      o.force_cpu = true;
    } else if (a == "--scene" || a == "--pack" || a == "--script" || a == "--out" ||
               a == "--size" || a == "--budget" || a == "--exposure" || a == "--drift-ulps") {
      if (!(v = value())) return usage();
      const std::string s = v;
      if (a == "--scene") o.scene = s;
      if (a == "--pack") o.pack = s;
      if (a == "--script") o.script = s;
      if (a == "--out") o.out = s;
      if (a == "--size" && !parse_size(s, &o.width, &o.height)) {
        std::fprintf(stderr, "lightpatch-inn play: --size wants WxH (16..8192), not '%s'\n", v);
        return 2;
      }
      if (a == "--budget") {
        char* end = nullptr;
        const unsigned long long b = std::strtoull(v, &end, 10);
        if (s.empty() || *end != '\0' || b == 0) {
          std::fprintf(
              stderr, "lightpatch-inn play: --budget wants a positive number of texels, not '%s'\n",
              v);
          return 2;
        }
        o.budget = b;
      }
      if (a == "--exposure" && !parse_float(s, &o.exposure)) {
        std::fprintf(stderr, "lightpatch-inn play: --exposure wants a positive number, not '%s'\n",
                     v);
        return 2;
      }
      if (a == "--drift-ulps" && !parse_float(s, &o.drift_ulps)) {
        std::fprintf(stderr,
                     "lightpatch-inn play: --drift-ulps wants a positive number, not '%s'\n", v);
        return 2;
      }
    } else {
      std::fprintf(stderr, "lightpatch-inn play: unknown option '%s'\n", a.c_str());
      return usage();
    }
  }
  if (window && o.headless) {
    std::fprintf(stderr, "lightpatch-inn play: --window and --headless exclude each other\n");
    return 2;
  }
  if (!o.script.empty() && !o.headless) {
    std::fprintf(stderr, "lightpatch-inn play: --script runs headless; add --headless\n");
    return 2;
  }
  if (o.headless) {
    if (o.script.empty()) o.script = "default";
    if (o.out.empty()) {
      std::fprintf(stderr, "lightpatch-inn play: --headless needs --out DIR\n");
      return 2;
    }
  }
  if (o.width == 0) {
    o.width = o.headless ? 960 : 1280;
    o.height = o.headless ? 540 : 720;
  }
  try {
    const auto session = open_session(o);
    return o.headless ? run_scripted(*session, o) : run_interactive(*session, o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lightpatch-inn play: %s\n", e.what());
    return 1;
  }
}

}  // namespace lightpatch::inn
