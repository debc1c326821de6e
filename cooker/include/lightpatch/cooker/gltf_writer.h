// The scene written back as a .glb with the light-map UVs the cook used (`cook --write-gltf`),
// so a game loads it with any glTF loader and samples the runtime's light map at TEXCOORD_1.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/scene.h"

namespace lightpatch::cooker {

// `scene_path` (the .gltf or .glb that import_gltf() read into `scene`) as .glb bytes: every
// baked primitive rewritten as a triangle list of its layout vertices (POSITION, NORMAL,
// TEXCOORD_0, which is the light-map UV too where it had none, TEXCOORD_1 = the light-map UV),
// uncompressed, in its node's local
// space; a node that shares its mesh with other nodes gets a copy of its own. Everything else of
// the file (nodes, names, extras, materials, textures, lights, animations) is kept; every buffer
// and image is embedded in the one binary chunk. A baked primitive loses its other attributes
// (tangents, colours, skins, morph targets), which its new vertices could not carry. Throws
// CookError when the file cannot be read again.
std::vector<uint8_t> gltf_with_lightmap_uvs(const std::string& scene_path, const Scene& scene,
                                            const Layout& layout);

}  // namespace lightpatch::cooker
