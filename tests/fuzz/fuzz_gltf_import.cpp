// libFuzzer target: glTF import (.gltf JSON or .glb bytes) and, for scenes it accepts, the
// light-map layout (where the TEXCOORD_1 checks live). Any input must end in a Scene or a
// CookError; anything else (a crash, a sanitizer report, another exception) is a finding.
#include <cstddef>
#include <cstdint>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/cooker/unwrap.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace lightpatch::cooker;
  try {
    // External buffers and images resolve in a folder that does not exist: the fuzzer reads no
    // file of this machine.
    const Scene scene = import_gltf_memory(data, size, "fuzz", "/nonexistent-lightpatch-fuzz/");
    if (scene.triangle_count() <= 4096) {
      LayoutOptions options;
      options.lightmap_size = 64;
      (void)build_layout(scene, options);
    }
  } catch (const CookError&) {
    // A clear error is the right answer to bad input.
  }
  return 0;
}
