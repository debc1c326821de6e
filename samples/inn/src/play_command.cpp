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

// The options, to `out` (stdout for --help, stderr after a usage error).
void print_help(std::FILE* out) {
  std::fprintf(
      out,
      "usage: lightpatch-inn play [--window] [--scene inn.glb] [--pack inn.lpk] [OPTIONS]\n"
      "       lightpatch-inn play --headless [--script default|SCENARIO.json] --out DIR "
      "[OPTIONS]\n"
      "  Plays a generated inn from its cooked pack. In a window: W A S D walk, Shift runs,\n"
      "  mouse or arrow keys look, E uses (takes the lantern, lights or snuffs a flame, takes\n"
      "  or places an item), Esc quits. Headless (EGL surfaceless): plays the scenario, writes\n"
      "  screenshots, frames.csv, steps.csv (and the lantern's state at each move) and\n"
      "  summary.json to DIR, and exits 1 if a scripted step fails (a change misses its latency\n"
      "  bound) or GL reports an error.\n"
      "options:\n"
      "  --window           play in a window (the default without --headless)\n"
      "  --headless         play the scripted scenario offscreen; needs --out\n"
      "  --script S         headless: 'default' (the OUT.scenario.json beside the scene) or a\n"
      "                     scenario file (default: default)\n"
      "  --out DIR          headless: where screenshots and records go (created)\n"
      "  --scene PATH       the inn's glTF (default: demo-out/inn.glb, what ./run demo makes)\n"
      "  --pack PATH        its cooked pack (default: demo-out/inn.lpk)\n"
      "  --size WxH         frame size, 16..8192 each (default: 960x540, where the window\n"
      "                     shows the full inn at 25-28 frames per second on llvmpipe with\n"
      "                     two cores; its drawing alone 26-31 while the lantern is carried)\n"
      "  --budget TEXELS    texels recomposed per frame (default: half the light map's area\n"
      "                     headless, at most 262144 in a window)\n"
      "  --exposure F       multiplies the light map before tone mapping, > 0 (default: 1.5)\n"
      "  --drift-ulps F     the planner's drift tolerance in half-float ulps (2^-11) of each\n"
      "                     texel's magnitude, > 0; lower rebuilds more often (default: 2)\n"
      "  --frames N         windowed: quit after N frames and print the frame times (mean,\n"
      "                     median, 95th percentile, frames per second); for measurements\n"
      "  --cpu              recompose on the runtime's CPU path, as on devices without\n"
      "                     renderable float targets (default: GLES when it can)\n"
      "  -h, --help         this text\n");
}

int usage() {
  print_help(stderr);
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
      print_help(stdout);
      return 0;
    } else if (a == "--headless") {
      o.headless = true;
    } else if (a == "--window") {
      window = true;
    } else if (a == "--cpu") {
      o.force_cpu = true;
    } else if (a == "--scene" || a == "--pack" || a == "--script" || a == "--out" ||
               a == "--size" || a == "--budget" || a == "--exposure" || a == "--drift-ulps" ||
               a == "--frames") {
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
      if (a == "--frames") {
        char* end = nullptr;
        const long n = std::strtol(v, &end, 10);
        if (s.empty() || *end != '\0' || n < 1 || n > 1000000) {
          std::fprintf(stderr, "lightpatch-inn play: --frames wants 1..1000000, not '%s'\n", v);
          return 2;
        }
        o.frames = static_cast<int>(n);
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
  if (o.frames && o.headless) {
    std::fprintf(stderr,
                 "lightpatch-inn play: --frames is for the window; the script ends on "
                 "its own\n");
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
    o.width = 960;
    o.height = 540;
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
