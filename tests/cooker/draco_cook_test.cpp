// A Draco-compressed copy of a scene bakes (through `lightpatch bake-state`) to the same light map
// as the uncompressed scene, within the quantization of positions and light-map UVs. The scene
// carries its own TEXCOORD_1: Draco reorders vertices and triangles, and the automatic unwrap
// lays charts out in triangle order, so only a verbatim parameterization gives both files the
// same texel for the same surface point. Direct light only: quantized positions move the bounce
// light's gather rays, so indirect light differs by its Monte Carlo noise, not by quantization.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "gltf_files.h"
#include "lightpatch/cooker/io.h"
#include "tool_runner.h"

namespace lightpatch::test {
namespace {

TEST(DracoCook, CompressedSceneBakesToTheSameMap) {
  ScratchDir dir;
  const scenegen::SceneBuilder b = small_room_with_uv1();
  b.write(dir.file("plain.glb"));
  b.write(dir.file("draco.glb"), {.draco = true});
  ASSERT_LT(read_bytes(dir.file("draco.glb")).size(), read_bytes(dir.file("plain.glb")).size());
  write_text(dir.file("state.json"), R"({"lights": {"lamp": {"intensity": 9.0}}})");
  for (const char* name : {"plain", "draco"}) {
    const std::vector<std::string> args = {"bake-state",
                                           dir.file(std::string(name) + ".glb"),
                                           "--state",
                                           dir.file("state.json"),
                                           "-o",
                                           dir.file(std::string(name) + ".pfm"),
                                           "--quality",
                                           "draft",
                                           "--lightmap-size",
                                           "64",
                                           "--no-indirect",
                                           "--quiet"};
    const ToolRun r = run_tool(args);
    ASSERT_EQ(r.code, 0) << describe(args, r);
  }
  const cooker::FloatImage plain = cooker::read_pfm(dir.file("plain.pfm"));
  const cooker::FloatImage draco = cooker::read_pfm(dir.file("draco.pfm"));
  ASSERT_EQ(plain.width, 64);
  ASSERT_EQ(draco.width, plain.width);
  ASSERT_EQ(draco.height, plain.height);
  ASSERT_EQ(draco.channels, plain.channels);
  double diff = 0, ref = 0;
  for (size_t i = 0; i < plain.data.size(); ++i) {
    ASSERT_TRUE(std::isfinite(draco.data[i]));
    diff += double(draco.data[i] - plain.data[i]) * double(draco.data[i] - plain.data[i]);
    ref += double(plain.data[i]) * double(plain.data[i]);
  }
  ASSERT_GT(ref, 0.0);
  const double relative_rmse = std::sqrt(diff / ref);
  RecordProperty("relative_rmse", std::to_string(relative_rmse));
  std::printf("plain vs Draco bake: relative RMSE %.6f\n", relative_rmse);
  EXPECT_LT(relative_rmse, 0.002) << "relative RMSE between the plain and the Draco bake";
}

}  // namespace
}  // namespace lightpatch::test
