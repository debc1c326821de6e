// Atomic writes and PFM files.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/io.h"

namespace lightpatch::cooker {
namespace {

std::string temp_dir() {
  const std::string d =
      std::filesystem::temp_directory_path().string() + "/lp_io_test_" + std::to_string(::getpid());
  std::filesystem::create_directories(d);
  return d;
}

size_t files_in(const std::string& dir) {
  size_t n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) n += e.is_regular_file() ? 1 : 0;
  return n;
}

TEST(Io, AtomicWriteReplacesWholeAndLeavesNoTemporary) {
  const std::string dir = temp_dir();
  const std::string path = dir + "/out.bin";
  write_file_atomic(path, "hello", 5);
  write_file_atomic(path, "bye", 3);
  const std::vector<uint8_t> back = read_file(path);
  EXPECT_EQ(std::string(back.begin(), back.end()), "bye");
  EXPECT_EQ(files_in(dir), 1u);
  std::filesystem::remove_all(dir);
}

TEST(Io, FailedWriteLeavesExistingFileUntouched) {
  const std::string dir = temp_dir();
  const std::string path = dir + "/keep.bin";
  write_file_atomic(path, "original", 8);
  // The destination is a directory: the write fails and no temporary is left behind.
  std::filesystem::create_directories(dir + "/sub");
  EXPECT_THROW(write_file_atomic(dir + "/sub", "x", 1), CookError);
  EXPECT_THROW(write_file_atomic(dir + "/missing/dir/file", "x", 1), CookError);
  const std::vector<uint8_t> back = read_file(path);
  EXPECT_EQ(std::string(back.begin(), back.end()), "original");
  EXPECT_EQ(files_in(dir), 1u);
  EXPECT_THROW(read_file(dir + "/nope"), CookError);
  std::filesystem::remove_all(dir);
}

TEST(Io, PfmWritesScanlinesBottomToTop) {
  const std::string dir = temp_dir();
  FloatImage img(2, 3, 1);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 2; ++x) img.at(x, y, 0) = static_cast<float>(10 * y + x);
  }
  write_pfm(dir + "/a.pfm", img);
  const std::vector<uint8_t> bytes = read_file(dir + "/a.pfm");
  const std::string header = "Pf\n2 3\n-1.0\n";
  ASSERT_EQ(bytes.size(), header.size() + 6 * 4);
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + static_cast<long>(header.size())), header);
  float first = -1, last = -1;
  std::memcpy(&first, bytes.data() + header.size(), 4);
  std::memcpy(&last, bytes.data() + bytes.size() - 4, 4);
  EXPECT_EQ(first, 20.0f);  // bottom row (image row 2) comes first
  EXPECT_EQ(last, 1.0f);    // top row (image row 0, glTF v = 0) comes last
  const FloatImage back = read_pfm(dir + "/a.pfm");
  EXPECT_EQ(back.channels, 1);
  EXPECT_EQ(back.data, img.data);

  FloatImage rgb(3, 2, 3);
  for (size_t i = 0; i < rgb.data.size(); ++i) rgb.data[i] = 0.5f * static_cast<float>(i);
  write_pfm(dir + "/b.pfm", rgb);
  const FloatImage rgb_back = read_pfm(dir + "/b.pfm");
  EXPECT_EQ(rgb_back.channels, 3);
  EXPECT_EQ(rgb_back.width, 3);
  EXPECT_EQ(rgb_back.data, rgb.data);
  std::filesystem::remove_all(dir);
}

TEST(Io, PfmRejectsTruncatedAndForeignFiles) {
  const std::string dir = temp_dir();
  FloatImage img(4, 4, 3);
  write_pfm(dir + "/c.pfm", img);
  const std::vector<uint8_t> bytes = read_file(dir + "/c.pfm");
  for (size_t cut = 0; cut < bytes.size(); cut += 7) {
    write_file_atomic(dir + "/t.pfm", bytes.data(), cut);
    EXPECT_THROW(read_pfm(dir + "/t.pfm"), CookError) << "cut at " << cut;
  }
  write_file_atomic(dir + "/p.pfm", "P6\n4 4\n255\n", 11);
  EXPECT_THROW(read_pfm(dir + "/p.pfm"), CookError);
  EXPECT_THROW(write_pfm(dir + "/bad.pfm", FloatImage(2, 2, 2)), CookError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace lightpatch::cooker
