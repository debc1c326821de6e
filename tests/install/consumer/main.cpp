// A small game loop on the installed runtime: map a pack, validate it, open a runtime on a
// headless context, change a light and an object, and run budgeted updates until the map is
// presented. Exit 0 and "lightpatch VERSION: ok" on success.
#include <cstdio>

#include "lightpatch/pack_view.h"
#include "lightpatch/platform/egl_context.h"
#include "lightpatch/platform/file_mapping.h"
#include "lightpatch/runtime.h"
#include "lightpatch/version.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: lightpatch_consumer PACK\n");
    return 2;
  }
  char message[256] = {};
  lightpatch::platform::FileMapping mapping;
  if (!mapping.open(argv[1], message, sizeof message)) {
    std::fprintf(stderr, "%s\n", message);
    return 1;
  }
  lightpatch::PackView pack;
  lightpatch::Error error;
  if (lightpatch::PackView::open(mapping.data(), mapping.size(), &pack, &error) !=
      lightpatch::Status::kOk) {
    std::fprintf(stderr, "%s\n", error.message);
    return 1;
  }
  lightpatch::platform::EglContext context;
  if (!context.create_headless(message, sizeof message)) {
    std::fprintf(stderr, "%s\n", message);
    return 1;
  }
  lightpatch::Runtime runtime;
  if (runtime.open(pack, lightpatch::RuntimeLimits(), &error) != lightpatch::Status::kOk) {
    std::fprintf(stderr, "%s\n", error.message);
    return 1;
  }
  const uint64_t budget = uint64_t(runtime.width()) * runtime.height() / 2 + 1;
  int frames = 0;
  for (; frames < 1000 && !runtime.idle(); ++frames) {
    if (frames == 1 && runtime.light_count() > 0) runtime.set_light_intensity(0, 0.5f);
    if (frames == 2 && runtime.object_count() > 0) runtime.set_object_visible(0, false);
    if (runtime.update(budget) != lightpatch::Status::kOk) return 1;
    if (runtime.stats().texels > budget && !runtime.stats().oversize_steps) return 1;
  }
  if (!runtime.ready() || !runtime.idle() || runtime.light_map_texture() == 0) {
    std::fprintf(stderr, "the runtime did not settle\n");
    return 1;
  }
  std::printf("lightpatch %s: ok (%s path, %d frames, %ux%u)\n", LIGHTPATCH_VERSION_STRING,
              lightpatch::path_name(runtime.path()), frames, runtime.width(), runtime.height());
  return 0;
}
