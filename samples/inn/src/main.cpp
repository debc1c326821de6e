// lightpatch-inn: generates the inn scene and plays it.
//   lightpatch-inn generate -o inn.glb [--draco] [--scale full|small] [--seed N] [--no-lantern]
//   lightpatch-inn play [--scene inn.glb --pack inn.lpk] [--headless --script default --out DIR]
//   (play_command.h has the options)
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>

#include "inn_generator.h"
#include "play_command.h"

namespace {

// The whole command line, to `out` (stdout for --help, stderr after a usage error).
void print_usage(std::FILE* out) {
  std::fprintf(out,
               "usage: lightpatch-inn generate -o OUT.glb|OUT.gltf [--draco] [--scale full|small] "
               "[--seed N] [--no-lantern]\n"
               "       lightpatch-inn play [--scene inn.glb --pack inn.lpk] [--headless --script "
               "default --out DIR]\n"
               "       lightpatch-inn VERB --help\n");
}

int usage() {
  print_usage(stderr);
  return 2;
}

void print_generate_help() {
  std::printf(
      "usage: lightpatch-inn generate -o OUT.glb|OUT.gltf [--draco] [--scale full|small] "
      "[--seed N] [--no-lantern]\n"
      "  Writes the inn scene (glTF 2.0; .glb binary, or .gltf with a .bin beside it) and, beside\n"
      "  it, OUT.state.json (the initial scene state, DESIGN.md's format) and\n"
      "  OUT.scenario.json (the scripted scenario `play --headless` runs).\n"
      "options:\n"
      "  -o, --output PATH  the scene file to write (required)\n"
      "  --draco            compress the meshes with KHR_draco_mesh_compression (default: off)\n"
      "  --scale full|small full: the demo's inn (two floors, ~225k triangles, 17 semi-dynamic\n"
      "                     lights); small: two rooms (~5.6k triangles, 4 semi-dynamic lights)\n"
      "                     for fast tests (default: full)\n"
      "  --seed N           varies colours, clutter and book sizes, not the layout; an integer\n"
      "                     in [0, 2^32); the same seed gives the same bytes (default: 1)\n"
      "  --no-lantern       leave out the lantern the player carries (a moving light: its panes\n"
      "                     take most of the pack's atlas bytes and the cook's time; README)\n"
      "  -h, --help         this text\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::string(argv[1]) == "play")
    return lightpatch::inn::play_command(argc - 1, argv + 1);
  if (argc >= 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    print_usage(stdout);
    return 0;
  }
  if (argc < 2 || std::string(argv[1]) != "generate") return usage();
  std::string out;
  bool draco = false;
  lightpatch::inn::InnOptions options;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "lightpatch-inn: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--help" || a == "-h") {
      print_generate_help();
      return 0;
    } else if (a == "-o" || a == "--output") {
      out = value();
    } else if (a == "--draco") {
      draco = true;
    } else if (a == "--no-lantern") {
      options.lantern = false;
    } else if (a == "--scale") {
      const std::string s = value();
      if (s == "full")
        options.scale = lightpatch::inn::InnScale::kFull;
      else if (s == "small")
        options.scale = lightpatch::inn::InnScale::kSmall;
      else {
        std::fprintf(stderr, "lightpatch-inn: --scale must be full or small, not '%s'\n",
                     s.c_str());
        return 2;
      }
    } else if (a == "--seed") {
      const std::string s = value();
      char* end = nullptr;
      const unsigned long v = std::strtoul(s.c_str(), &end, 10);
      if (s.empty() || *end != '\0' || v > 0xFFFFFFFFul) {
        std::fprintf(stderr, "lightpatch-inn: --seed must be an integer in [0, 2^32), not '%s'\n",
                     s.c_str());
        return 2;
      }
      options.seed = static_cast<std::uint32_t>(v);
    } else {
      std::fprintf(stderr, "lightpatch-inn: unknown option '%s'\n", a.c_str());
      return usage();
    }
  }
  if (out.empty()) {
    std::fprintf(stderr, "lightpatch-inn: missing -o OUT.glb\n");
    return usage();
  }
  try {
    const lightpatch::inn::Inn inn = lightpatch::inn::generate_inn(options);
    lightpatch::inn::write_inn(inn, out, draco);
    const auto size = std::filesystem::file_size(out);
    std::printf(
        "%s: %zu triangles, %zu semi-dynamic lights, %zu static lights, %zu semi-dynamic objects "
        "(%zu items), %llu bytes\n",
        out.c_str(), inn.stats.triangles, inn.stats.semi_dynamic_lights, inn.stats.static_lights,
        inn.stats.semi_dynamic_objects, inn.stats.items, static_cast<unsigned long long>(size));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lightpatch-inn: %s\n", e.what());
    return 1;
  }
  return 0;
}
