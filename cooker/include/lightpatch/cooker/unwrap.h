// Light-map parameterization, per glTF node (region): its own TEXCOORD_1 in [0,1] placed whole
// with one scale and offset (options.unwrap kAuto/kNever), or an automatic unwrap (charts grown
// by normal similarity, planar projection, overlap rejection, borders, per-region packing; seed
// 004 §6.1-6.2, §6.9); one TEXCOORD_1 layout over the whole scene is used as it is. Density
// follows each node's MeshInstance::lightmap_scale; excluded meshes get an empty MeshLayout and
// no region. Deterministic.
#pragma once

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/scene.h"

namespace lightpatch::cooker {

// Throws CookError (overlapping TEXCOORD_1 triangles within one node, a mesh without TEXCOORD_1
// under kNever, every mesh excluded), naming the mesh.
Layout build_layout(const Scene& scene, const LayoutOptions& options);

}  // namespace lightpatch::cooker
