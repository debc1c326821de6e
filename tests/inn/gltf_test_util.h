// Helpers for the inn tests: reading a .glb back, scratch folders, running the glTF validator.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <sys/wait.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace lightpatch::test {

struct Glb {
  nlohmann::json json;
  std::vector<std::uint8_t> bin;
};

inline std::uint32_t read_u32(const std::vector<std::uint8_t>& b, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

// Parses a .glb image; fails the test (and returns an empty Glb) when malformed.
inline Glb parse_glb(const std::vector<std::uint8_t>& b) {
  Glb out;
  EXPECT_GE(b.size(), 20u);
  if (b.size() < 20) return out;
  EXPECT_EQ(read_u32(b, 0), 0x46546C67u);
  EXPECT_EQ(read_u32(b, 4), 2u);
  EXPECT_EQ(read_u32(b, 8), b.size());
  const std::uint32_t json_len = read_u32(b, 12);
  EXPECT_EQ(read_u32(b, 16), 0x4E4F534Au);
  EXPECT_EQ(json_len % 4, 0u);
  EXPECT_LE(20u + json_len, b.size());
  if (20u + json_len > b.size()) return out;
  out.json = nlohmann::json::parse(b.begin() + 20, b.begin() + 20 + json_len);
  const std::size_t bin_at = 20u + json_len;
  if (bin_at < b.size()) {
    const std::uint32_t bin_len = read_u32(b, bin_at);
    EXPECT_EQ(read_u32(b, bin_at + 4), 0x004E4942u);
    EXPECT_EQ(bin_at + 8 + bin_len, b.size());
    out.bin.assign(b.begin() + static_cast<std::ptrdiff_t>(bin_at + 8), b.end());
  }
  return out;
}

inline std::vector<std::uint8_t> read_file(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

// A fresh scratch folder per test (tests run in parallel processes).
inline std::filesystem::path scratch_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      ("lightpatch_inn_" + std::string(info->test_suite_name()) + "_" + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// The validator's node_modules folder: $LIGHTPATCH_GLTF_VALIDATOR, else the build's npm folder.
inline std::string validator_dir() {
  const char* env = std::getenv("LIGHTPATCH_GLTF_VALIDATOR");
  return env != nullptr && *env != '\0' ? std::string(env) : std::string(LIGHTPATCH_VALIDATOR_DIR);
}

// Runs the Khronos glTF validator on `file`; returns the script's exit code (0: no errors) and
// leaves its report in `file`.report.json and its summary in `file`.log.
inline int run_validator(const std::filesystem::path& file) {
  const std::string cmd = std::string("\"") + LIGHTPATCH_NODE + "\" \"" +
                          LIGHTPATCH_VALIDATE_SCRIPT + "\" \"" + file.string() + "\" \"" +
                          validator_dir() + "\" > \"" + file.string() + ".report.json\" 2> \"" +
                          file.string() + ".log\"";
  const int rc = std::system(cmd.c_str());
  return rc == -1 ? -1 : WEXITSTATUS(rc);
}

inline std::string slurp(const std::filesystem::path& p) {
  const std::vector<std::uint8_t> b = read_file(p);
  return std::string(b.begin(), b.end());
}

}  // namespace lightpatch::test
