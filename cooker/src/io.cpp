#include "lightpatch/cooker/io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "lightpatch/cooker/error.h"

namespace lightpatch::cooker {

namespace {

std::string errno_text() {
  return std::strerror(errno);
}

std::string directory_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

bool host_is_little_endian() {
  const uint32_t one = 1;
  uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

uint32_t byteswap32(uint32_t x) {
  return (x >> 24) | ((x >> 8) & 0xff00u) | ((x << 8) & 0xff0000u) | (x << 24);
}

}  // namespace

void write_file_atomic(const std::string& path, const void* data, size_t size) {
  if (path.empty()) throw CookError("cannot write: empty output path");
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
    throw CookError("cannot write '" + path + "': it is a directory");
  }
  // The temporary lives in the destination's folder so that rename() is atomic.
  std::string temp = path + ".tmp.XXXXXX";
  const int fd = ::mkstemp(temp.data());
  if (fd < 0) {
    throw CookError("cannot create a temporary file in '" + directory_of(path) +
                    "': " + errno_text());
  }
  auto fail = [&](const std::string& what) {
    const std::string reason = errno_text();
    ::close(fd);
    ::unlink(temp.c_str());
    throw CookError("cannot write '" + path + "' (" + what + "): " + reason);
  };
  const auto* bytes = static_cast<const uint8_t*>(data);
  size_t written = 0;
  while (written < size) {
    const ssize_t n = ::write(fd, bytes + written, size - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("write");
    }
    written += static_cast<size_t>(n);
  }
  if (::fchmod(fd, 0644) != 0) fail("chmod");
  if (::fsync(fd) != 0) fail("fsync");
  if (::close(fd) != 0) {
    const std::string reason = errno_text();
    ::unlink(temp.c_str());
    throw CookError("cannot write '" + path + "' (close): " + reason);
  }
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    const std::string reason = errno_text();
    ::unlink(temp.c_str());
    throw CookError("cannot write '" + path + "' (rename): " + reason);
  }
}

std::vector<uint8_t> read_file(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw CookError("cannot read '" + path + "': " + errno_text());
  struct stat st {};
  if (::fstat(::fileno(f), &st) == 0 && S_ISDIR(st.st_mode)) {
    std::fclose(f);
    throw CookError("cannot read '" + path + "': it is a directory");
  }
  std::vector<uint8_t> out;
  uint8_t buffer[1 << 16];
  size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), f)) > 0)
    out.insert(out.end(), buffer, buffer + n);
  const bool error = std::ferror(f) != 0;
  std::fclose(f);
  if (error) throw CookError("cannot read '" + path + "': read error");
  return out;
}

void write_pfm(const std::string& path, const FloatImage& image) {
  if (image.channels != 1 && image.channels != 3) {
    throw CookError("cannot write '" + path + "': PFM needs 1 or 3 channels, got " +
                    std::to_string(image.channels));
  }
  if (image.width <= 0 || image.height <= 0 ||
      image.data.size() != size_t(image.width) * image.height * image.channels) {
    throw CookError("cannot write '" + path + "': empty or inconsistent image");
  }
  const std::string header = std::string(image.channels == 3 ? "PF" : "Pf") + "\n" +
                             std::to_string(image.width) + " " + std::to_string(image.height) +
                             "\n-1.0\n";
  std::vector<uint8_t> bytes(header.begin(), header.end());
  const size_t row_floats = size_t(image.width) * image.channels;
  const size_t start = bytes.size();
  bytes.resize(start + row_floats * image.height * sizeof(float));
  const bool little = host_is_little_endian();
  // Scanlines bottom to top: image row height-1 first, row 0 (glTF v = 0) last.
  for (int r = 0; r < image.height; ++r) {
    const int src_row = image.height - 1 - r;
    const float* src = image.data.data() + size_t(src_row) * row_floats;
    uint8_t* dst = bytes.data() + start + size_t(r) * row_floats * sizeof(float);
    for (size_t i = 0; i < row_floats; ++i) {
      uint32_t u = 0;
      std::memcpy(&u, &src[i], 4);
      if (!little) u = byteswap32(u);
      std::memcpy(dst + i * 4, &u, 4);
    }
  }
  write_file_atomic(path, bytes.data(), bytes.size());
}

FloatImage read_pfm(const std::string& path) {
  const std::vector<uint8_t> bytes = read_file(path);
  size_t pos = 0;
  auto bad = [&](const std::string& what) -> CookError {
    return CookError("'" + path + "' is not a valid PFM file: " + what);
  };
  auto skip_space = [&] {
    while (pos < bytes.size() && std::isspace(bytes[pos])) ++pos;
  };
  auto token = [&]() {
    skip_space();
    std::string t;
    while (pos < bytes.size() && !std::isspace(bytes[pos]) && t.size() < 32) {
      t.push_back(static_cast<char>(bytes[pos++]));
    }
    return t;
  };
  const std::string magic = token();
  int channels = 0;
  if (magic == "PF")
    channels = 3;
  else if (magic == "Pf")
    channels = 1;
  else
    throw bad("missing 'PF' or 'Pf' signature");
  const std::string ws = token(), hs = token(), ss = token();
  char* end = nullptr;
  const long w = std::strtol(ws.c_str(), &end, 10);
  if (ws.empty() || *end) throw bad("bad width '" + ws + "'");
  const long h = std::strtol(hs.c_str(), &end, 10);
  if (hs.empty() || *end) throw bad("bad height '" + hs + "'");
  const double scale = std::strtod(ss.c_str(), &end);
  if (ss.empty() || *end || !std::isfinite(scale) || scale == 0.0)
    throw bad("bad scale '" + ss + "'");
  if (w <= 0 || h <= 0 || w > 65536 || h > 65536) throw bad("size out of range");
  // Exactly one whitespace character separates the header from the data.
  if (pos >= bytes.size() || !std::isspace(bytes[pos])) throw bad("truncated header");
  ++pos;
  const size_t row_floats = size_t(w) * channels;
  const size_t need = row_floats * size_t(h) * sizeof(float);
  if (bytes.size() - pos < need) throw bad("truncated pixel data");
  FloatImage image(static_cast<int>(w), static_cast<int>(h), channels);
  const bool file_little = scale < 0;
  const bool swap = file_little != host_is_little_endian();
  for (long r = 0; r < h; ++r) {
    const long dst_row = h - 1 - r;
    const uint8_t* src = bytes.data() + pos + size_t(r) * row_floats * sizeof(float);
    float* dst = image.data.data() + size_t(dst_row) * row_floats;
    for (size_t i = 0; i < row_floats; ++i) {
      uint32_t u = 0;
      std::memcpy(&u, src + i * 4, 4);
      if (swap) u = byteswap32(u);
      std::memcpy(&dst[i], &u, 4);
    }
  }
  return image;
}

}  // namespace lightpatch::cooker
