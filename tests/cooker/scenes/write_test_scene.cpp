// write_test_scene: writes the test scenes the accuracy measurements use (docs/accuracy.md), so
// that every table there can be measured again from a build.
// Usage: write_test_scene room_soft|thin_panel|low_slab|two_rooms OUT.glb|OUT.gltf
#include <cstdio>
#include <exception>
#include <string>

#include "gltf_files.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(
        stderr,
        "usage: write_test_scene room_soft|thin_panel|low_slab|two_rooms OUT.glb|OUT.gltf\n");
    return 2;
  }
  const std::string name = argv[1];
  try {
    if (name == "room_soft") {
      lightpatch::test::small_room(0.1f).write(argv[2]);
    } else if (name == "thin_panel") {
      lightpatch::test::thin_panel_room().write(argv[2]);
    } else if (name == "low_slab") {
      lightpatch::test::low_slab_room().write(argv[2]);
    } else if (name == "two_rooms") {
      lightpatch::test::two_rooms_lantern().write(argv[2]);
    } else {
      std::fprintf(
          stderr,
          "write_test_scene: unknown scene '%s' (room_soft, thin_panel, low_slab, two_rooms)\n",
          name.c_str());
      return 2;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "write_test_scene: %s\n", e.what());
    return 1;
  }
  return 0;
}
