// scenegen: shapes, the glTF writer's structure, Draco round trip, validation, errors.
#include <cmath>
#include <set>
#include <stdexcept>

#include <draco/compression/decode.h>
#include <gtest/gtest.h>

#include "gltf_test_util.h"
#include "lightpatch/scenegen/scene_builder.h"

namespace lightpatch::scenegen {
namespace {

using test::parse_glb;

// Signed volume of a closed mesh: positive when the triangles face outward.
double signed_volume(const Geometry& g) {
  double v = 0.0;
  for (std::size_t i = 0; i < g.indices.size(); i += 3) {
    const glm::dvec3 a = g.positions[g.indices[i]];
    const glm::dvec3 b = g.positions[g.indices[i + 1]];
    const glm::dvec3 c = g.positions[g.indices[i + 2]];
    v += glm::dot(a, glm::cross(b, c)) / 6.0;
  }
  return v;
}

// Every normal agrees with its triangles' geometric normals (front faces where normals point).
void expect_normals_agree(const Geometry& g) {
  for (std::size_t i = 0; i < g.indices.size(); i += 3) {
    const glm::vec3 a = g.positions[g.indices[i]];
    const glm::vec3 b = g.positions[g.indices[i + 1]];
    const glm::vec3 c = g.positions[g.indices[i + 2]];
    const glm::vec3 n = glm::cross(b - a, c - a);
    ASSERT_GT(glm::length(n), 0.0f) << "degenerate triangle " << i / 3;
    for (int k = 0; k < 3; ++k)
      EXPECT_GT(glm::dot(n, g.normals[g.indices[i + static_cast<std::size_t>(k)]]), 0.0f);
  }
}

TEST(Shapes, BoxCountsVolumeAndFacing) {
  const Geometry out = make_box({0, 0, 0}, {1, 2, 3}, Facing::kOutward, 3);
  EXPECT_EQ(out.triangle_count(), 12u * 9u);
  EXPECT_NEAR(signed_volume(out), 6.0, 1e-4);
  expect_normals_agree(out);
  const Geometry in = make_box({0, 0, 0}, {1, 2, 3}, Facing::kInward, 1);
  EXPECT_NEAR(signed_volume(in), -6.0, 1e-4);
  expect_normals_agree(in);
  // Inward normals point to the box's centre.
  for (std::size_t i = 0; i < in.positions.size(); ++i) {
    EXPECT_GT(glm::dot(in.normals[i], glm::vec3(0.5f, 1.0f, 1.5f) - in.positions[i]), 0.0f);
  }
}

TEST(Shapes, RoundedBoxStaysInsideItsBoundsAndIsClosed) {
  const Geometry g = make_rounded_box({-1, 0, -0.5f}, {1, 0.8f, 0.5f}, 0.1f, 2);
  EXPECT_EQ(g.triangle_count(), 12u * 25u);
  const glm::vec3 lo = g.bounds_min(), hi = g.bounds_max();
  EXPECT_NEAR(lo.x, -1.0f, 1e-5f);
  EXPECT_NEAR(hi.y, 0.8f, 1e-5f);
  // Volume of a rounded box: box minus what the rounding removes, between the two.
  const double v = signed_volume(g);
  EXPECT_LT(v, 1.6);
  EXPECT_GT(v, 1.55);
  g.check();
  expect_normals_agree(g);
}

TEST(Shapes, LatheCylinderSphereTorusAreClosedAndOutward) {
  const float pi = 3.14159265f;
  const Geometry cyl = make_cylinder(0.5f, 2.0f, 32, 2);
  EXPECT_NEAR(signed_volume(cyl), pi * 0.25 * 2.0, 0.02);
  expect_normals_agree(cyl);
  const Geometry sph = make_sphere(1.0f, 24, 12);
  EXPECT_NEAR(signed_volume(sph), 4.0 / 3.0 * pi, 0.25);  // polygonal: a little less
  expect_normals_agree(sph);
  const Geometry cone = make_frustum(0.5f, 0.0f, 1.0f, 32);
  EXPECT_NEAR(signed_volume(cone), pi * 0.25 / 3.0, 0.01);
  expect_normals_agree(cone);
  const Geometry torus = make_torus(1.0f, 0.25f, 32, 16);
  EXPECT_NEAR(signed_volume(torus), 2.0 * pi * pi * 1.0 * 0.0625, 0.08);
  expect_normals_agree(torus);
}

TEST(Shapes, TransformKeepsFrontFacesUnderMirroring) {
  const Geometry box = make_box({0, 0, 0}, {1, 1, 1});
  const Geometry mirrored = box.transformed(glm::mat4(
      glm::vec4(-1, 0, 0, 0), glm::vec4(0, 2, 0, 0), glm::vec4(0, 0, 1, 0), glm::vec4(0, 0, 0, 1)));
  EXPECT_NEAR(signed_volume(mirrored), 2.0, 1e-4);
  expect_normals_agree(mirrored);
}

TEST(Geometry, CheckAndAppendRejectBadInput) {
  Geometry g = make_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
  g.indices.push_back(7);
  g.indices.push_back(0);
  g.indices.push_back(1);
  EXPECT_THROW(g.check(), std::invalid_argument);
  Geometry with_uv = make_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, 1, 1, true);
  Geometry without_uv = make_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
  EXPECT_THROW(with_uv.append(without_uv), std::invalid_argument);
}

SceneBuilder sample_scene(bool with_uv1) {
  SceneBuilder b;
  const int wood = b.add_material({.name = "wood", .base_color = {0.5f, 0.3f, 0.15f, 1.0f}});
  const int glow =
      b.add_material({.name = "glow", .emissive = {1, 0.5f, 0.2f}, .emissive_strength = 5});
  Geometry room = make_box({-3, 0, -3}, {3, 3, 3}, Facing::kInward, 2);
  room.append(make_rounded_box({-1, 0, -0.5f}, {1, 0.8f, 0.5f}, 0.05f, 1));
  if (with_uv1) {
    room.uv1.resize(room.positions.size());
    for (std::size_t i = 0; i < room.uv1.size(); ++i)
      room.uv1[i] = glm::vec2(room.positions[i].x, room.positions[i].z) / 8.0f + 0.5f;
  }
  b.add_node({.name = "room", .mesh = b.add_mesh("room", room, wood)});
  b.add_mesh_node("lamp", make_sphere(0.1f), glow, {0, 2, 0}, true);
  b.add_light_node("candle", {.type = LightType::kPoint, .intensity = 2.0f, .range = 5.0f},
                   {0, 1, 0}, {0, -1, 0}, true, 0.02f);
  b.add_light_node("spot",
                   {.type = LightType::kSpot,
                    .intensity = 20,
                    .inner_cone_angle = 0.2f,
                    .outer_cone_angle = 0.5f},
                   {0, 2.5f, 0}, {1, -1, 0});
  b.add_light_node("moon", {.type = LightType::kDirectional, .intensity = 0.5f}, {0, 5, 0},
                   {0.3f, -1, 0.2f});
  return b;
}

TEST(SceneBuilder, GlbStructureMinMaxAlignmentAndExtras) {
  const SceneBuilder b = sample_scene(true);
  const test::Glb glb = parse_glb(b.to_glb());
  const nlohmann::json& j = glb.json;
  EXPECT_EQ(j["asset"]["version"], "2.0");
  EXPECT_EQ(j["buffers"][0]["byteLength"].get<std::size_t>(), glb.bin.size());
  for (const auto& v : j["bufferViews"]) {
    EXPECT_EQ(v["byteOffset"].get<std::size_t>() % 4, 0u);
    EXPECT_LE(v["byteOffset"].get<std::size_t>() + v["byteLength"].get<std::size_t>(),
              glb.bin.size());
    EXPECT_FALSE(v.contains("byteStride"));
  }
  // POSITION min/max equal the data's bounds.
  const auto& prim = j["meshes"][0]["primitives"][0];
  EXPECT_TRUE(prim["attributes"].contains("TEXCOORD_1"));
  const auto& acc = j["accessors"][prim["attributes"]["POSITION"].get<int>()];
  EXPECT_EQ(acc["min"], nlohmann::json({-3.0, 0.0, -3.0}));
  EXPECT_EQ(acc["max"], nlohmann::json({3.0, 3.0, 3.0}));
  // Lights and extras.
  const auto& lights = j["extensions"]["KHR_lights_punctual"]["lights"];
  ASSERT_EQ(lights.size(), 3u);
  EXPECT_EQ(lights[1]["type"], "spot");
  EXPECT_FLOAT_EQ(lights[1]["spot"]["outerConeAngle"].get<float>(), 0.5f);
  const auto& candle = j["nodes"][2];
  EXPECT_EQ(candle["name"], "candle");
  EXPECT_EQ(candle["extras"]["semiDynamic"], true);
  EXPECT_FLOAT_EQ(candle["extras"]["lightRadius"].get<float>(), 0.02f);
  EXPECT_EQ(j["nodes"][1]["extras"]["semiDynamic"], true);
  EXPECT_EQ(j["extensionsUsed"],
            nlohmann::json({"KHR_lights_punctual", "KHR_materials_emissive_strength"}));
  EXPECT_FALSE(j.contains("extensionsRequired"));
  // The spot shines along its node's −Z: the rotation maps −Z to (1, −1, 0)/√2.
  const auto& r = j["nodes"][3]["rotation"];
  const glm::quat q(r[3].get<float>(), r[0].get<float>(), r[1].get<float>(), r[2].get<float>());
  const glm::vec3 d = q * glm::vec3(0, 0, -1);
  EXPECT_NEAR(d.x, 0.70710678f, 1e-5f);
  EXPECT_NEAR(d.y, -0.70710678f, 1e-5f);
  EXPECT_NEAR(d.z, 0.0f, 1e-5f);
}

TEST(SceneBuilder, DracoPrimitivesDecodeToTheAccessorCounts) {
  const SceneBuilder b = sample_scene(true);
  const test::Glb glb = parse_glb(b.to_glb({.draco = true}));
  const nlohmann::json& j = glb.json;
  EXPECT_EQ(j["extensionsRequired"], nlohmann::json({"KHR_draco_mesh_compression"}));
  int primitives = 0;
  for (const auto& mesh : j["meshes"]) {
    for (const auto& prim : mesh["primitives"]) {
      ++primitives;
      const auto& ext = prim["extensions"]["KHR_draco_mesh_compression"];
      const auto& view = j["bufferViews"][ext["bufferView"].get<int>()];
      EXPECT_FALSE(view.contains("byteStride"));
      EXPECT_FALSE(view.contains("target"));
      draco::DecoderBuffer buffer;
      buffer.Init(
          reinterpret_cast<const char*>(glb.bin.data()) + view["byteOffset"].get<std::size_t>(),
          view["byteLength"].get<std::size_t>());
      draco::Decoder decoder;
      auto result = decoder.DecodeMeshFromBuffer(&buffer);
      ASSERT_TRUE(result.ok()) << result.status().error_msg();
      const draco::Mesh& mesh_out = *result.value();
      const auto& pos = j["accessors"][prim["attributes"]["POSITION"].get<int>()];
      EXPECT_FALSE(pos.contains("bufferView"));
      EXPECT_EQ(pos["count"].get<std::size_t>(), mesh_out.num_points());
      EXPECT_TRUE(pos.contains("min"));
      EXPECT_EQ(j["accessors"][prim["indices"].get<int>()]["count"].get<std::size_t>(),
                3u * mesh_out.num_faces());
      for (const auto& [semantic, id] : ext["attributes"].items()) {
        EXPECT_TRUE(prim["attributes"].contains(semantic));
        EXPECT_NE(mesh_out.GetAttributeByUniqueId(id.get<std::uint32_t>()), nullptr) << semantic;
      }
    }
  }
  EXPECT_EQ(primitives, 2);
}

TEST(SceneBuilder, SameCallsGiveSameBytes) {
  EXPECT_EQ(sample_scene(false).to_glb(), sample_scene(false).to_glb());
  EXPECT_EQ(sample_scene(true).to_glb({.draco = true}), sample_scene(true).to_glb({.draco = true}));
  EXPECT_NE(sample_scene(false).to_glb(), sample_scene(true).to_glb());
}

TEST(SceneBuilder, RejectsBadInput) {
  SceneBuilder b;
  EXPECT_THROW(b.add_material({.name = "hot", .base_color = {2, 0, 0, 1}}), std::invalid_argument);
  EXPECT_THROW(b.add_mesh("m", make_box({0, 0, 0}, {1, 1, 1}), 3), std::invalid_argument);
  EXPECT_THROW(b.add_mesh("m", Geometry{}, -1), std::invalid_argument);
  EXPECT_THROW(
      b.add_light({.type = LightType::kSpot, .inner_cone_angle = 0.6f, .outer_cone_angle = 0.5f}),
      std::invalid_argument);
  EXPECT_THROW(b.add_light({.intensity = -1.0f}), std::invalid_argument);
  EXPECT_THROW(b.add_node({.name = "n", .mesh = 0}), std::invalid_argument);
  const int a = b.add_node({.name = "a"});
  const int c = b.add_node({.name = "c"});
  b.add_child(a, c);
  b.add_child(c, a);
  EXPECT_THROW(b.to_glb(), std::invalid_argument);  // a cycle
  EXPECT_THROW(b.write("/tmp/x.obj"), std::invalid_argument);
}

TEST(SceneBuilder, WritesGltfWithBinAndEmbeddedAndTheyValidate) {
  const auto dir = test::scratch_dir();
  const SceneBuilder b = sample_scene(true);
  b.write((dir / "plain.gltf").string());
  EXPECT_TRUE(std::filesystem::exists(dir / "plain.bin"));
  b.write((dir / "embedded.gltf").string(), {.storage = BufferStorage::kEmbedded});
  b.write((dir / "draco.glb").string(), {.draco = true});
  b.write((dir / "draco.gltf").string(), {.draco = true});
  bool ok = true;
  for (const char* f : {"plain.gltf", "embedded.gltf", "draco.glb", "draco.gltf"}) {
    const int rc = test::run_validator(dir / f);
    EXPECT_EQ(rc, 0) << f << ": " << test::slurp(dir / (std::string(f) + ".log"));
    ok = ok && rc == 0;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "plain.gltf.tmp"));
  if (ok) std::filesystem::remove_all(dir);  // kept with the reports when something failed
}

}  // namespace
}  // namespace lightpatch::scenegen
