// glTF 2.0 import (.gltf, .glb): tinygltf, KHR_draco_mesh_compression, KHR_lights_punctual,
// KHR_materials_emissive_strength, node extras semiDynamic, lightRadius, lightmapScale and
// lightmapExclude (booleans as true/false or Blender's 1/0).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/cooker/scene.h"

namespace lightpatch::cooker {

// What a scene may ask of the cooker, checked before the work it bounds (README, "Limits"). A
// scene over a limit is refused with a message naming the limit and the option that raises it.
struct ImportLimits {
  // Triangles and vertices (POSITION elements) of the whole scene, a mesh counted once per node
  // that instances it; counted from the accessors before any is read (--max-triangles,
  // --max-vertices).
  uint64_t max_triangles = 4'000'000;
  uint64_t max_vertices = 12'000'000;
  // Pixels of the base-colour images, summed, from each image's header before it is decoded
  // (--max-texture-pixels). Other images (normal maps, ...) are never decoded.
  uint64_t max_texture_pixels = uint64_t(1) << 25;
  // Folders external buffers and images may come from besides the scene's own folder and its
  // subfolders (--uri-root DIR); links are resolved first.
  std::vector<std::string> uri_roots;
};

// The options that raise each limit, for messages and --help.
constexpr const char* kMaxTrianglesOption = "--max-triangles";
constexpr const char* kMaxVerticesOption = "--max-vertices";
constexpr const char* kMaxTexturePixelsOption = "--max-texture-pixels";
constexpr const char* kUriRootOption = "--uri-root";

// Reads and validates a scene. Throws CookError with a message naming the problem (file, node,
// mesh, accessor) on any bad input: unreadable file, invalid JSON, NaN/Inf, indices out of range,
// missing buffers, zero-area-only meshes, unsupported required extensions, duplicate or missing
// names of semi-dynamic nodes, invalid TEXCOORD_1, extras of the wrong type, a scene over
// `limits`, a buffer or image file outside the scene's folder and limits.uri_roots. Files are read
// with io.h's read_file.
Scene import_gltf(const std::string& path, const ImportLimits& limits = {});

// The same from `size` bytes in memory (.glb when they start with "glTF", else .gltf JSON); `name`
// prefixes every error message; external buffers and images are looked up in `base_dir` (empty:
// the working directory; a folder that does not exist: nowhere, as the fuzzer wants).
Scene import_gltf_memory(const uint8_t* data, size_t size, const std::string& name,
                         const std::string& base_dir, const ImportLimits& limits = {});

}  // namespace lightpatch::cooker
