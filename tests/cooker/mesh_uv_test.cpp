// The pack's mesh section as a game reads it (issue 13): each record's vertices name glTF
// vertices of the primitive, so a game that fetches positions from its glTF loader by
// source_vertex draws the same triangles; an instance laid out by its own TEXCOORD_1 carries the
// scale and offset that turn the glTF's TEXCOORD_1 into the vertices' light-map UVs. Scenes are
// written as glTF and cooked in process (import, layout, bake, pack), shaped like exports: a
// mesh without normals (the importer unwelds it), one mesh instanced by three nodes, per-mesh
// UVs in [0,1], Blender's 1/0 booleans.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "gltf_files.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/cooker/pack_builder.h"
#include "lightpatch/cooker/texel_builder.h"
#include "lightpatch/cooker/tracer.h"
#include "lightpatch/cooker/unwrap.h"
#include "lightpatch/pack_view.h"

namespace lightpatch::test {
namespace {

namespace sg = scenegen;

struct CookedPack {
  cooker::Scene scene;
  cooker::Layout layout;
  std::vector<uint8_t> bytes;
  PackView view;
};

void cook_file(const std::string& path, CookedPack& c) {
  c.scene = cooker::import_gltf(path);
  cooker::LayoutOptions lo;
  lo.texels_per_unit = 8.0f;
  c.layout = cooker::build_layout(c.scene, lo);
  auto tracer = cooker::make_embree_tracer(c.scene);
  const cooker::TexelSet texels = cooker::build_texels(c.scene, c.layout, tracer.get());
  cooker::BakeOptions bo;
  bo.quality = cooker::Quality::kDraft;
  bo.indirect = false;
  cooker::Progress progress(true);
  cooker::Report report;
  cooker::BakedMaps maps =
      cooker::bake_maps(c.scene, c.layout, texels, *tracer, bo, progress, report);
  cooker::finalize_maps(maps, c.scene, c.layout, texels);
  c.bytes = cooker::build_pack(c.scene, c.layout, maps, cooker::PackOptions{}, report);
  Error error;
  ASSERT_EQ(PackView::open(c.bytes.data(), c.bytes.size(), &c.view, &error), Status::kOk)
      << error.message;
}

// The glTF's own index list and vertex count of a primitive, read back from the written JSON.
struct GltfPrimitive {
  std::vector<uint32_t> indices;
  size_t vertices = 0;
  std::vector<glm::vec2> uv1;
};

GltfPrimitive gltf_primitive(const GltfParts& parts, int mesh) {
  const auto& prim = parts.json["meshes"][size_t(mesh)]["primitives"][0];
  GltfPrimitive g;
  const int pos = prim["attributes"]["POSITION"];
  g.vertices = parts.json["accessors"][size_t(pos)]["count"];
  const int idx = prim["indices"];
  const auto& acc = parts.json["accessors"][size_t(idx)];
  const auto& view = parts.json["bufferViews"][size_t(acc["bufferView"].get<int>())];
  const size_t at = view.value("byteOffset", size_t(0)) + acc.value("byteOffset", size_t(0));
  for (size_t i = 0; i < acc["count"].get<size_t>(); ++i) {
    if (acc["componentType"] == 5123) {
      uint16_t v;
      std::memcpy(&v, parts.bin.data() + at + 2 * i, 2);
      g.indices.push_back(v);
    } else {
      uint32_t v;
      std::memcpy(&v, parts.bin.data() + at + 4 * i, 4);
      g.indices.push_back(v);
    }
  }
  if (prim["attributes"].contains("TEXCOORD_1")) {
    const int uv = prim["attributes"]["TEXCOORD_1"];
    for (size_t i = 0; i < g.vertices; ++i)
      g.uv1.push_back({get_float(parts, uv, i, 0), get_float(parts, uv, i, 1)});
  }
  return g;
}

// Every record's triangle k is the glTF's triangle k, by glTF vertex (corners may rotate, never
// change), and every vertex names a vertex of the primitive.
void expect_triangles_of_the_gltf(const PackView& v, uint32_t record, const GltfPrimitive& g) {
  const pack::MeshRecord& m = v.mesh(record);
  ASSERT_EQ(m.index_count, g.indices.size());
  const pack::MeshVertex* mv = v.mesh_vertices(record);
  const uint32_t* mi = v.mesh_indices(record);
  for (uint32_t k = 0; k < m.vertex_count; ++k) EXPECT_LT(mv[k].source_vertex, g.vertices);
  for (size_t t = 0; t < g.indices.size(); t += 3)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(mv[mi[t + size_t(c)]].source_vertex, g.indices[t + size_t(c)])
          << "triangle " << t / 3 << " corner " << c;
}

TEST(MeshUvs, AMeshWithoutNormalsNamesItsGltfVertices) {
  // A 2 x 2 grid of quads over 9 shared vertices, no NORMAL: the importer gives each triangle
  // its own 3 vertices (flat normals, glTF 3.7.2.1); the pack must still name the 9.
  ScratchDir dir;
  sg::SceneBuilder b;
  b.add_mesh_node("floor", sg::make_quad({-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, {-2, 0, -2}, 2, 2), -1);
  b.add_light_node("lamp", {.name = "lamp", .intensity = 10.0f}, {0, 2, 0}, {0, -1, 0}, true);
  GltfParts parts = parts_of(b);
  parts.json["meshes"][0]["primitives"][0]["attributes"].erase("NORMAL");
  CookedPack c;
  cook_file(write_glb(dir, "no_normals", parts), c);
  ASSERT_FALSE(HasFatalFailure());
  ASSERT_EQ(c.scene.meshes[0].positions.size(), 24u);  // unwelded
  ASSERT_EQ(c.view.mesh_count(), 1u);
  const GltfPrimitive g = gltf_primitive(parts, 0);
  ASSERT_EQ(g.vertices, 9u);
  expect_triangles_of_the_gltf(c.view, 0, g);
}

TEST(MeshUvs, InstancedMeshWithItsOwnTexcoord1GetsAScaleAndOffsetPerNode) {
  // A chair mesh used by three nodes, its light-map UVs over the whole square, and a floor with
  // UVs of its own; the lamp marked with Blender's integer 1.
  ScratchDir dir;
  sg::SceneBuilder b;
  sg::Geometry floor = sg::make_quad({-3, 0, 3}, {3, 0, 3}, {3, 0, -3}, {-3, 0, -3});
  floor.uv1 = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};  // grid order: the bottom row, then the top
  b.add_mesh_node("floor", floor, -1);
  sg::Geometry seat = sg::make_box({-0.25f, 0.0f, -0.25f}, {0.25f, 0.5f, 0.25f});
  // The box's six faces in a 3 x 2 grid of cells with a margin, as Lightmap Pack lays them.
  seat.uv1.resize(seat.positions.size());
  for (size_t v = 0; v < seat.positions.size(); ++v) {
    const size_t face = v / 4, corner = v % 4;
    const glm::vec2 cell(float(face % 3) / 3.0f, float(face / 3) / 2.0f);
    const glm::vec2 local(float(corner & 1), float(corner >> 1));  // grid order
    seat.uv1[v] = cell + (glm::vec2(0.02f) + local * 0.29f) * glm::vec2(1.0f, 1.5f);
  }
  const int chair = b.add_mesh("chair", seat, -1);
  for (int i = 0; i < 3; ++i)
    b.add_node({.name = "chair_" + std::to_string(i),
                .translation = {-1.5f + 1.5f * float(i), 0.0f, 0.5f},
                .mesh = chair});
  b.add_light_node("lamp", {.name = "lamp", .intensity = 10.0f}, {0, 2, 0});
  GltfParts parts = parts_of(b);
  for (auto& n : parts.json["nodes"])
    if (n["name"] == "lamp") n["extras"] = {{"semiDynamic", 1}};
  CookedPack c;
  cook_file(write_glb(dir, "chairs", parts), c);
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_EQ(c.layout.uv1_regions, 4);
  ASSERT_EQ(c.view.mesh_count(), 4u);
  ASSERT_EQ(c.view.light_count(), 1u);  // the lamp is semi-dynamic
  std::vector<std::array<float, 4>> placements;
  for (uint32_t r = 0; r < c.view.mesh_count(); ++r) {
    const pack::MeshRecord& m = c.view.mesh(r);
    ASSERT_EQ(m.flags, pack::kMeshFlagTexcoord1);
    const GltfPrimitive g = gltf_primitive(parts, r == 0 ? 0 : 1);
    expect_triangles_of_the_gltf(c.view, r, g);
    // The glTF's TEXCOORD_1 through the record's scale and offset: the vertices' UVs, inside
    // the light map.
    const float* so = m.lightmap_scale_offset;
    const pack::MeshVertex* mv = c.view.mesh_vertices(r);
    for (uint32_t k = 0; k < m.vertex_count; ++k) {
      const glm::vec2 uv1 = g.uv1[mv[k].source_vertex];
      EXPECT_NEAR(uv1.x * so[0] + so[2], mv[k].u, 1e-6f);
      EXPECT_NEAR(uv1.y * so[1] + so[3], mv[k].v, 1e-6f);
      EXPECT_TRUE(mv[k].u >= 0.0f && mv[k].u <= 1.0f && mv[k].v >= 0.0f && mv[k].v <= 1.0f);
    }
    placements.push_back({so[0], so[1], so[2], so[3]});
  }
  // One region per chair node, same size, different places.
  EXPECT_EQ(placements[1][0], placements[2][0]);
  EXPECT_EQ(placements[2][0], placements[3][0]);
  EXPECT_NE(placements[1], placements[2]);
  EXPECT_NE(placements[2], placements[3]);
  EXPECT_NE(placements[1], placements[3]);
}

}  // namespace
}  // namespace lightpatch::test
