// The tool's content verbs as a user runs them (issue 13), end to end through subprocesses:
// `cook --write-gltf` (the Khronos validator accepts the file; drawn with the runtime's light
// map at its TEXCOORD_1 it shows the closed-form irradiance), `preview` and `bake-state --png`
// (readable PNGs of the sizes and colours asked for), the authoring note for a scene with
// nothing semi-dynamic, and `--unwrap`. Scenes are written as a Blender export would be: Draco,
// a mirrored node, Blender's integer booleans.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <vector>

#include <stb/stb_image.h>

#include "cooker/gltf_files.h"
#include "cooker/tool_runner.h"
#include "direct_light.h"
#include "inn/gltf_test_util.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/cooker/io.h"
#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/platform/file_mapping.h"
#include "lightpatch/scene_state.h"

namespace lightpatch::test {
namespace {

namespace sg = scenegen;

ToolRun expect_success(const std::vector<std::string>& args) {
  const ToolRun r = run_tool(args);
  EXPECT_EQ(r.code, 0) << describe(args, r);
  return r;
}

// A floor and a back wall (its node mirrored in x, as an exporter writes a mirrored copy), under
// a semi-dynamic lamp (Blender's integer 1) and a static spot; nothing between them, so a
// texel's light has a closed form. Draco-compressed, as an export with compression on.
std::string lit_corner(const ScratchDir& dir) {
  sg::SceneBuilder b;
  b.add_mesh_node("floor", sg::make_quad({-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, {-2, 0, -2}), -1);
  const int wall =
      b.add_mesh("wall", sg::make_quad({2, 0, -2}, {-2, 0, -2}, {-2, 2.5f, -2}, {2, 2.5f, -2}), -1);
  b.add_node({.name = "wall", .scale = {-1.0f, 1.0f, 1.0f}, .mesh = wall});
  b.add_light_node("lamp", {.name = "lamp", .intensity = 12.0f}, {0.3f, 1.8f, 0.2f});
  b.add_light_node("spot",
                   {.name = "spot",
                    .type = sg::LightType::kSpot,
                    .intensity = 30.0f,
                    .inner_cone_angle = 0.5f,
                    .outer_cone_angle = 1.1f},
                   {-1.0f, 2.2f, 1.0f}, glm::normalize(glm::vec3(0.4f, -1.0f, -0.6f)));
  GltfParts parts = parts_of(b, {.draco = true});
  for (auto& n : parts.json["nodes"])
    if (n["name"] == "lamp") n["extras"] = {{"semiDynamic", 1}};
  return write_glb(dir, "corner", parts);
}

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;
};

Image read_png(const std::string& path) {
  const std::vector<uint8_t> bytes = read_bytes(path);
  Image img;
  int comp = 0;
  uint8_t* px =
      stbi_load_from_memory(bytes.data(), int(bytes.size()), &img.width, &img.height, &comp, 3);
  EXPECT_NE(px, nullptr) << path << " is not a readable PNG";
  if (!px) return img;
  img.rgb.assign(px, px + size_t(img.width) * size_t(img.height) * 3);
  stbi_image_free(px);
  return img;
}

// The runtime's CPU recomposition of the authored state.
std::vector<float> runtime_map(const std::string& pack_path, uint32_t* w, uint32_t* h) {
  platform::FileMapping mapping;
  char message[256] = {};
  EXPECT_TRUE(mapping.open(pack_path.c_str(), message, sizeof(message))) << message;
  PackView view;
  Error error;
  EXPECT_EQ(PackView::open(mapping.data(), mapping.size(), &view, &error), Status::kOk)
      << error.message;
  SceneState state;
  CpuRecomposer cpu;
  EXPECT_EQ(state.init(view, &error), Status::kOk);
  EXPECT_EQ(cpu.init(view, &error), Status::kOk);
  cpu.rebuild(state);
  *w = cpu.width();
  *h = cpu.height();
  return std::vector<float>(cpu.rgb(), cpu.rgb() + size_t(*w) * (*h) * 3);
}

float bilinear(const std::vector<float>& map, uint32_t w, uint32_t h, glm::vec2 uv, int c) {
  const float fx = uv.x * float(w) - 0.5f, fy = uv.y * float(h) - 0.5f;
  const int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
  const float ax = fx - float(x0), ay = fy - float(y0);
  float v = 0.0f;
  for (int k = 0; k < 4; ++k) {
    const int x = std::clamp(x0 + (k & 1), 0, int(w) - 1);
    const int y = std::clamp(y0 + (k >> 1), 0, int(h) - 1);
    v += ((k & 1) ? ax : 1 - ax) * ((k >> 1) ? ay : 1 - ay) * map[(size_t(y) * w + x) * 3 + c];
  }
  return v;
}

TEST(ContentTool, WrittenGltfIsValidAndShowsTheRuntimeMapAtItsTexcoord1) {
  ScratchDir dir;
  const std::string scene = lit_corner(dir);
  const std::string pack = dir.file("corner.lpk"), out = dir.file("corner_lightmapped.glb");
  expect_success({"cook", scene, "-o", pack, "--write-gltf", out, "--quality", "draft",
                  "--no-indirect", "--texels-per-unit", "16", "--quiet"});
  EXPECT_EQ(run_validator(out), 0) << slurp(out + ".report.json");

  // Any glTF loader: the written file imports with its names, extras and TEXCOORD_1.
  const cooker::Scene written = cooker::import_gltf(out);
  ASSERT_EQ(written.meshes.size(), 2u);
  ASSERT_EQ(written.lights.size(), 2u);
  EXPECT_TRUE(written.lights[0].semi_dynamic);
  uint32_t w = 0, h = 0;
  const std::vector<float> map = runtime_map(pack, &w, &h);
  ASSERT_FALSE(HasFatalFailure());

  // Drawn as a game draws it: at points inside every triangle, the runtime's map sampled
  // bilinearly at the interpolated TEXCOORD_1 against the closed-form irradiance there.
  double err = 0.0, ref = 0.0;
  int points = 0;
  for (const cooker::MeshInstance& m : written.meshes) {
    ASSERT_EQ(m.uv1.size(), m.positions.size()) << m.name;
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3)
      for (float a = 0.1f; a < 0.85f; a += 0.125f)
        for (float b = 0.1f; a + b < 0.9f; b += 0.125f) {
          const float c = 1.0f - a - b;
          const uint32_t i0 = m.indices[t], i1 = m.indices[t + 1], i2 = m.indices[t + 2];
          const glm::vec3 p = a * m.positions[i0] + b * m.positions[i1] + c * m.positions[i2];
          const glm::vec3 n =
              glm::normalize(a * m.normals[i0] + b * m.normals[i1] + c * m.normals[i2]);
          const glm::vec2 uv = a * m.uv1[i0] + b * m.uv1[i1] + c * m.uv1[i2];
          float want = 0.0f;
          for (const cooker::Light& l : written.lights)
            want += l.intensity * cooker::punctual_irradiance(l, l.position, p, n, 0.0f);
          const float got = bilinear(map, w, h, uv, 0);
          err += double(got - want) * (got - want);
          ref += double(want) * want;
          ++points;
        }
  }
  const double rmse = std::sqrt(err / ref);
  std::printf("%d points on the written glTF: relative RMSE %.3f%% against the closed form\n",
              points, 100.0 * rmse);
  EXPECT_GT(points, 50);
  EXPECT_LT(rmse, 0.02);
}

TEST(ContentTool, PreviewAndBakeStatePngShowWhatWasBaked) {
  ScratchDir dir;
  const std::string scene = lit_corner(dir);
  const std::string pack = dir.file("corner.lpk");
  expect_success({"cook", scene, "-o", pack, "--quality", "draft", "--no-indirect",
                  "--lightmap-size", "64", "--quiet"});
  uint32_t w = 0, h = 0;
  runtime_map(pack, &w, &h);
  ASSERT_FALSE(HasFatalFailure());
  for (const std::string view : {"lightmap", "charts", "checker", "atlases"}) {
    const std::string png = dir.file(view + ".png");
    expect_success({"preview", pack, "-o", png, "--view", view, "--zoom", "2"});
    const Image img = read_png(png);
    ASSERT_FALSE(img.rgb.empty()) << view;
    if (view != "atlases") {
      EXPECT_EQ(img.width, int(2 * w)) << view;
      EXPECT_EQ(img.height, int(2 * h)) << view;
    }
    std::set<uint32_t> colours;
    size_t lit = 0;
    for (size_t i = 0; i < img.rgb.size(); i += 3) {
      colours.insert(uint32_t(img.rgb[i]) << 16 | uint32_t(img.rgb[i + 1]) << 8 | img.rgb[i + 2]);
      lit += img.rgb[i] + img.rgb[i + 1] + img.rgb[i + 2] > 0 ? 1 : 0;
    }
    EXPECT_GT(lit, img.rgb.size() / 3 / 4) << view << ": mostly black";
    // The two meshes' charts in colours of their own, a checker in two shades of each.
    if (view == "checker") {
      EXPECT_GE(colours.size(), 4u);
    }
  }
  // bake-state's picture: the same size, and no magenta (negative) texel.
  const std::string png = dir.file("state.png");
  expect_success({"bake-state", scene, "-o", dir.file("state.pfm"), "--png", png, "--quality",
                  "draft", "--no-indirect", "--lightmap-size", "64", "--quiet"});
  const Image img = read_png(png);
  EXPECT_EQ(img.width, int(w));
  size_t magenta = 0;
  for (size_t i = 0; i < img.rgb.size(); i += 3)
    magenta += img.rgb[i] == 255 && img.rgb[i + 1] == 0 && img.rgb[i + 2] == 255 ? 1 : 0;
  EXPECT_EQ(magenta, 0u);
  const ToolRun bad = run_tool({"preview", pack, "-o", dir.file("x.png"), "--view", "heat"});
  EXPECT_EQ(bad.code, 2) << describe({"preview"}, bad);
}

TEST(ContentTool, ASceneWithNothingSemiDynamicIsToldHowBlenderWritesExtras) {
  ScratchDir dir;
  sg::SceneBuilder b;
  b.add_mesh_node("floor", sg::make_quad({-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, {-2, 0, -2}), -1);
  b.add_light_node("lamp", {.name = "lamp", .intensity = 5.0f}, {0, 2, 0});
  b.write(dir.file("static.glb"));
  const ToolRun r = expect_success({"cook", dir.file("static.glb"), "-o", dir.file("s.lpk"),
                                    "--quality", "draft", "--lightmap-size", "32"});
  EXPECT_NE(r.err.find("no light or object semi-dynamic"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("Include > Custom Properties"), std::string::npos) << r.err;
  // Marked, the note goes away.
  small_room().write(dir.file("room.glb"));
  const ToolRun marked = expect_success({"cook", dir.file("room.glb"), "-o", dir.file("r.lpk"),
                                         "--quality", "draft", "--lightmap-size", "32"});
  EXPECT_EQ(marked.err.find("Custom Properties"), std::string::npos) << marked.err;

  const ToolRun unwrap =
      run_tool({"cook", dir.file("room.glb"), "-o", dir.file("u.lpk"), "--unwrap", "sometimes"});
  EXPECT_EQ(unwrap.code, 2);
  EXPECT_NE(unwrap.err.find("--unwrap"), std::string::npos) << unwrap.err;
  const ToolRun never = run_tool(
      {"cook", dir.file("room.glb"), "-o", dir.file("u.lpk"), "--unwrap", "never", "--quiet"});
  EXPECT_NE(never.code, 0);
  EXPECT_NE(never.err.find("TEXCOORD_1"), std::string::npos) << never.err;
}

}  // namespace
}  // namespace lightpatch::test
