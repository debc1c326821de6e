// `lightpatch accuracy` as a user runs it: a quick sweep of a small scene writes a CSV with one
// row of finite measurements per setting and a PNG plot, production beats draft against the
// reference, the reference is cached and reused, the runtime CSV holds one row per encoding,
// and bad options fail cleanly, writing nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <stb/stb_image.h>

#include "gltf_files.h"
#include "tool_runner.h"

namespace lightpatch::test {
namespace {

struct Csv {
  std::vector<std::string> notes;
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
};

// Splits one line at commas outside double quotes; quotes are dropped.
std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  return out;
}

Csv read_csv(const std::string& path) {
  const std::vector<std::uint8_t> bytes = read_bytes(path);
  std::istringstream in(std::string(bytes.begin(), bytes.end()));
  Csv csv;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("#", 0) == 0) {
      csv.notes.push_back(line);
    } else if (csv.header.empty()) {
      csv.header = fields(line);
    } else {
      const std::vector<std::string> f = fields(line);
      EXPECT_EQ(f.size(), csv.header.size()) << line;
      std::map<std::string, std::string> row;
      for (size_t i = 0; i < f.size() && i < csv.header.size(); ++i) row[csv.header[i]] = f[i];
      csv.rows.push_back(row);
    }
  }
  return csv;
}

double number(const std::map<std::string, std::string>& row, const std::string& key) {
  const auto it = row.find(key);
  EXPECT_NE(it, row.end()) << key;
  if (it == row.end()) return NAN;
  char* end = nullptr;
  const double v = std::strtod(it->second.c_str(), &end);
  EXPECT_TRUE(!it->second.empty() && *end == '\0') << key << " = '" << it->second << "'";
  return v;
}

std::string cache_file(const ScratchDir& dir) {
  for (const std::string& e : dir.entries()) {
    if (e.rfind("lightpatch-accuracy-reference-", 0) == 0) return e;
  }
  return "";
}

TEST(Accuracy, QuickSweepWritesCsvAndPlotAndReusesTheCachedReference) {
  ScratchDir dir;
  small_room().write(dir.file("room.glb"));
  const std::vector<std::string> args = {"accuracy",
                                         dir.file("room.glb"),
                                         "--quick",
                                         "--csv",
                                         dir.file("acc.csv"),
                                         "--plot",
                                         dir.file("acc.png"),
                                         "--runtime-csv",
                                         dir.file("runtime.csv")};
  const ToolRun first = run_tool(args);
  ASSERT_EQ(first.code, 0) << describe(args, first);
  EXPECT_NE(first.err.find("reference: baking"), std::string::npos) << first.err;
  const std::string cache = cache_file(dir);
  ASSERT_FALSE(cache.empty()) << "no reference cache next to the CSV";
  const std::vector<std::uint8_t> cache_bytes = read_bytes(dir.file(cache));

  const Csv csv = read_csv(dir.file("acc.csv"));
  EXPECT_FALSE(csv.notes.empty());
  for (const char* column : {"setting",
                             "knob",
                             "quality",
                             "gather_rays",
                             "indirect_scale",
                             "denoise",
                             "area_samples",
                             "lightmap_size",
                             "encoding",
                             "cook_s",
                             "rays",
                             "pack_bytes",
                             "rel_rmse",
                             "max_rel_error",
                             "psnr_db",
                             "pareto",
                             "rel_rmse_excess",
                             "within_noise",
                             "max_rel_error_beyond_noise",
                             "max_error_x",
                             "max_error_y",
                             "bias",
                             "median_ratio"}) {
    EXPECT_NE(std::find(csv.header.begin(), csv.header.end(), column), csv.header.end()) << column;
  }
  // --quick: draft, production, and draft with each fixed encoding.
  ASSERT_EQ(csv.rows.size(), 4u);
  std::map<std::string, const std::map<std::string, std::string>*> by_name;
  int pareto = 0;
  for (const auto& row : csv.rows) {
    by_name[row.at("setting")] = &row;
    for (const char* key : {"cook_s", "rays", "pack_bytes", "rel_rmse", "max_rel_error", "psnr_db",
                            "lightmap_size", "bias", "median_ratio"}) {
      EXPECT_TRUE(std::isfinite(number(row, key))) << row.at("setting") << " " << key;
    }
    EXPECT_GT(number(row, "cook_s"), 0.0);
    EXPECT_GT(number(row, "rays"), 0.0);
    EXPECT_GT(number(row, "pack_bytes"), 0.0);
    EXPECT_GT(number(row, "rel_rmse"), 0.0);
    EXPECT_GE(number(row, "max_rel_error"), 0.0);
    EXPECT_EQ(number(row, "lightmap_size"), 32.0);
    pareto += row.at("pareto") == "1" ? 1 : 0;
  }
  EXPECT_GE(pareto, 1);
  // The path-traced reference states its own noise; a row's excess error is below its rel_rmse.
  bool noise_noted = false;
  for (const std::string& n : csv.notes) {
    noise_noted = noise_noted || n.find("reference noise: relative RMSE") != n.npos;
  }
  EXPECT_TRUE(noise_noted);
  bool below_max = false;
  for (const auto& row : csv.rows) {
    EXPECT_LE(number(row, "rel_rmse_excess"), number(row, "rel_rmse"));
    EXPECT_TRUE(row.at("within_noise") == "0" || row.at("within_noise") == "1");
    // Beyond the noise: never above the max error, never below 0; the worst texel is in the page.
    EXPECT_LE(number(row, "max_rel_error_beyond_noise"), number(row, "max_rel_error"));
    EXPECT_GE(number(row, "max_rel_error_beyond_noise"), 0.0);
    EXPECT_GE(number(row, "max_error_x"), 0.0);
    EXPECT_LT(number(row, "max_error_x"), 32.0);
    EXPECT_GE(number(row, "max_error_y"), 0.0);
    EXPECT_LT(number(row, "max_error_y"), 32.0);
    below_max =
        below_max || number(row, "max_rel_error_beyond_noise") < number(row, "max_rel_error");
  }
  EXPECT_TRUE(below_max) << "the path tracer's noise took nothing off any row's max error";
  EXPECT_NE(first.err.find("reference: baking (path tracing"), std::string::npos) << first.err;
  ASSERT_TRUE(by_name.count("preset=draft"));
  ASSERT_TRUE(by_name.count("preset=production"));
  const double draft = number(*by_name["preset=draft"], "rel_rmse");
  const double production = number(*by_name["preset=production"], "rel_rmse");
  EXPECT_LT(production, draft) << "production should be closer to the reference than draft";
  EXPECT_GT(number(*by_name["preset=production"], "rays"),
            number(*by_name["preset=draft"], "rays"));
  // The sign of the error: production's light in sum and its typical texel's within a few percent
  // of the path tracer's (measured: -0.5 % and 0.99 on this 32x32 page); a bias is no RMSE, it
  // can be either sign, and a ratio is positive.
  const double bias = number(*by_name["preset=production"], "bias");
  EXPECT_LT(std::abs(bias), 0.03);
  EXPECT_LE(std::abs(bias), number(*by_name["preset=production"], "rel_rmse") * 1.5);
  EXPECT_NEAR(number(*by_name["preset=production"], "median_ratio"), 1.0, 0.05);
  for (const auto& row : csv.rows) EXPECT_GT(number(row, "median_ratio"), 0.0);

  const std::vector<std::uint8_t> png = read_bytes(dir.file("acc.png"));
  int w = 0, h = 0, channels = 0;
  stbi_uc* pixels = stbi_load_from_memory(png.data(), int(png.size()), &w, &h, &channels, 3);
  ASSERT_NE(pixels, nullptr) << "the plot is not a PNG";
  EXPECT_EQ(w, 1000);
  EXPECT_EQ(h, 640);
  stbi_image_free(pixels);

  // The runtime: each encoding on the CPU reference's float target, against the float
  // composition of the same bake; only 8-bit quantization separates them.
  const Csv runtime = read_csv(dir.file("runtime.csv"));
  EXPECT_FALSE(runtime.notes.empty());
  ASSERT_EQ(runtime.rows.size(), 3u);
  std::vector<std::string> encodings;
  for (const auto& row : runtime.rows) {
    encodings.push_back(row.at("encoding"));
    EXPECT_EQ(row.at("target"), "cpu-float32");
    for (const char* key :
         {"recompose_ms", "atlas_bytes", "target_bytes", "rel_rmse", "max_rel_error", "psnr_db"}) {
      EXPECT_TRUE(std::isfinite(number(row, key))) << row.at("encoding") << " " << key;
    }
    EXPECT_GE(number(row, "recompose_ms"), 0.0);
    EXPECT_GT(number(row, "atlas_bytes"), 0.0);
    EXPECT_EQ(number(row, "target_bytes"), 32.0 * 32.0 * 3.0 * 4.0);
    EXPECT_GT(number(row, "rel_rmse"), 0.0);
    EXPECT_LT(number(row, "rel_rmse"), 0.02) << "more than 8-bit quantization error";
  }
  EXPECT_EQ(encodings, (std::vector<std::string>{"auto", "linear", "square"}));

  // Second run: the cached reference is used, not baked again; --maps writes each row's
  // recomposed map and the reference.
  std::filesystem::create_directory(dir.file("maps"));
  std::vector<std::string> with_maps = args;
  with_maps.insert(with_maps.end(), {"--maps", dir.file("maps")});
  const ToolRun second = run_tool(with_maps);
  ASSERT_EQ(second.code, 0) << describe(args, second);
  EXPECT_NE(second.err.find("reference: using the cache"), std::string::npos) << second.err;
  EXPECT_EQ(second.err.find("reference: baking"), std::string::npos) << second.err;
  EXPECT_EQ(cache_file(dir), cache);
  EXPECT_TRUE(read_bytes(dir.file(cache)) == cache_bytes);
  const Csv again = read_csv(dir.file("acc.csv"));
  bool noted = false;
  for (const std::string& n : again.notes) noted = noted || n.find("from the cache") != n.npos;
  EXPECT_TRUE(noted);
  EXPECT_EQ(again.rows.size(), 4u);
  const std::vector<std::string> maps = {
      "preset_draft", "preset_production", "encoding_linear__draft_", "encoding_square__draft_",
      "reference",    "reference.stderr"};
  std::vector<std::string> want;
  for (const std::string& m : maps) want.push_back(m + ".pfm");
  std::sort(want.begin(), want.end());
  std::vector<std::string> written;
  for (const auto& e : std::filesystem::directory_iterator(dir.file("maps")))
    written.push_back(e.path().filename().string());
  std::sort(written.begin(), written.end());
  EXPECT_EQ(written, want);
  // Each a 32x32 RGB PFM; draft's map is not the reference's, but near it.
  auto sum_of = [&](const std::string& name) {
    const std::vector<std::uint8_t> b = read_bytes(dir.file("maps/" + name + ".pfm"));
    const std::string head = "PF\n32 32\n-1.0\n";
    EXPECT_EQ(b.size(), head.size() + 32 * 32 * 3 * 4) << name;
    EXPECT_EQ(std::string(b.begin(), b.begin() + long(std::min(b.size(), head.size()))), head)
        << name;
    double sum = 0.0;
    for (size_t i = head.size(); i + 4 <= b.size(); i += 4) {
      float v = 0.0f;
      std::memcpy(&v, &b[i], 4);
      sum += v;
    }
    return sum;
  };
  const double reference = sum_of("reference"), draft_sum = sum_of("preset_draft");
  EXPECT_GT(reference, 0.0);
  EXPECT_NE(draft_sum, reference);
  EXPECT_NEAR(draft_sum / reference, 1.0, 0.5);
}

TEST(Accuracy, HelpListsTheOptions) {
  const ToolRun r = run_tool({"accuracy", "--help"});
  EXPECT_EQ(r.code, 0);
  for (const char* option :
       {"--csv", "--plot", "--runtime-csv", "--gles", "--lightmap-size", "--quick",
        "--reference-integrator", "--reference-samples", "--reference-noise", "--reference-scale",
        "--maps", "--no-cache", "--seed", "--threads", "--quiet"}) {
    EXPECT_NE(r.out.find(option), std::string::npos) << option << " not in: " << r.out;
  }
}

TEST(Accuracy, BadOptionsFailWithAMessageAndWriteNothing) {
  ScratchDir dir;
  small_room().write(dir.file("room.glb"));
  write_text(dir.file("broken.glb"), "not a glTF file");
  const std::string scene = dir.file("room.glb"), csv = dir.file("a.csv"), png = dir.file("a.png");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"accuracy", scene, "--plot", png, "--quick"}, "--csv"},
      {{"accuracy", scene, "--csv", csv, "--quick"}, "--plot"},
      {{"accuracy", scene, "--csv", csv, "--plot", png, "--lightmap-size", "3"}, "--lightmap-size"},
      {{"accuracy", scene, "--csv", csv, "--plot", png, "--threads", "zero"}, "--threads"},
      {{"accuracy", scene, "--csv", csv, "--plot", png, "--bogus"}, "--bogus"},
      {{"accuracy", "--csv", csv, "--plot", png}, "SCENE"},
      {{"accuracy", scene, "--csv", csv, "--plot", csv}, "same file"},
      {{"accuracy", scene, "--csv", csv, "--plot", png, "--runtime-csv", csv}, "same file"},
      {{"accuracy", scene, "--csv", csv, "--plot", png, "--gles"}, "--runtime-csv"},
      {{"accuracy", scene, "--csv", csv, "--plot", png, "--reference-integrator", "vpl"},
       "--reference-integrator"},
      {{"accuracy", scene, "--csv", csv, "--plot", png, "--reference-scale", "2"},
       "--reference-scale"},
      {{"accuracy", scene, "--csv", csv, "--plot", png, "--reference-integrator", "cook",
        "--reference-samples", "64"},
       "--reference-samples"},
      {{"accuracy", scene, "--csv", csv, "--plot", png, "--reference-samples", "1"},
       "--reference-samples"},
      {{"accuracy", dir.file("missing.glb"), "--csv", csv, "--plot", png, "--quick"},
       "missing.glb"},
      {{"accuracy", dir.file("broken.glb"), "--csv", csv, "--plot", png, "--quick"}, "broken.glb"},
      {{"accuracy", scene, "--csv", dir.file("no/such/folder/a.csv"), "--plot", png, "--quick"},
       "cannot write"},
      {{"accuracy", scene, "--csv", csv, "--plot", png, "--quick", "--maps", dir.file("none")},
       "not a folder"},
  };
  for (const auto& [args, word] : cases) {
    const std::vector<std::string> before = dir.entries();
    const ToolRun r = run_tool(args);
    const std::string what = describe(args, r);
    EXPECT_NE(r.code, 0) << what;
    EXPECT_LT(r.code, 128) << "killed by a signal: " << what;
    EXPECT_NE(r.err.find(word), std::string::npos) << "'" << word << "' not in stderr: " << what;
    EXPECT_EQ(dir.entries(), before) << "files left behind: " << what;
  }
}

}  // namespace
}  // namespace lightpatch::test
