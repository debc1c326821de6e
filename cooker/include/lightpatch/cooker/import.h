// glTF 2.0 import (.gltf, .glb): tinygltf, KHR_draco_mesh_compression, KHR_lights_punctual,
// KHR_materials_emissive_strength, node extras semiDynamic, lightRadius, lightmapScale and
// lightmapExclude (booleans as true/false or Blender's 1/0).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "lightpatch/cooker/scene.h"

namespace lightpatch::cooker {

// Reads and validates a scene. Throws CookError with a message naming the problem (file, node,
// mesh, accessor) on any bad input: unreadable file, invalid JSON, NaN/Inf, indices out of range,
// missing buffers, zero-area-only meshes, unsupported required extensions, duplicate or missing
// names of semi-dynamic nodes, invalid TEXCOORD_1, extras of the wrong type.
Scene import_gltf(const std::string& path);

// The same from `size` bytes in memory (.glb when they start with "glTF", else .gltf JSON); `name`
// prefixes every error message; external buffers and images are looked up in `base_dir` (empty:
// the working directory; a folder that does not exist: nowhere, as the fuzzer wants).
Scene import_gltf_memory(const uint8_t* data, size_t size, const std::string& name,
                         const std::string& base_dir);

}  // namespace lightpatch::cooker
