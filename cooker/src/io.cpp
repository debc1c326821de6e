#include "lightpatch/cooker/io.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/printable.h"

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

std::string file_name_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
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

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

std::atomic<uint64_t> g_input_size_limit{kDefaultInputSizeLimit};

// ---- temporaries the signal handler removes ----------------------------------------------------

// Fixed slots, so that the handler touches only lock-free atomics and static memory.
struct TemporarySlot {
  std::atomic<int> state{0};  // 0 free, 1 being filled, 2 holds a temporary's path
  char path[PATH_MAX];
};
TemporarySlot g_temporaries[16];

int claim_slot(const std::string& path) {
  if (path.size() >= sizeof(g_temporaries[0].path)) return -1;  // the next run removes it
  for (int i = 0; i < int(std::size(g_temporaries)); ++i) {
    int expected = 0;
    if (!g_temporaries[i].state.compare_exchange_strong(expected, 1)) continue;
    std::memcpy(g_temporaries[i].path, path.c_str(), path.size() + 1);
    g_temporaries[i].state.store(2);
    return i;
  }
  return -1;
}

void release_slot(int slot) {
  if (slot >= 0) g_temporaries[slot].state.store(0);
}

extern "C" void remove_temporaries_and_die(int sig) {
  for (TemporarySlot& t : g_temporaries)
    if (t.state.load() == 2) ::unlink(t.path);
  ::raise(sig);  // SA_RESETHAND restored the default action: die of the same signal
}

// Removes OUT.lightpatch-tmp-PID-* files of `target` whose process is gone (killed mid-write).
void remove_stale_temporaries(const std::string& target) {
  const std::string dir = directory_of(target);
  const std::string prefix = file_name_of(target) + kTemporaryMarker;
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return;
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    char* end = nullptr;
    const long pid = std::strtol(name.c_str() + prefix.size(), &end, 10);
    if (pid <= 0 || *end != '-' || pid == long(::getpid())) continue;
    if (::kill(pid_t(pid), 0) == 0 || errno != ESRCH) continue;  // its writer may still run
    const std::string path = dir + "/" + name;
    struct stat st {};
    if (::lstat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode)) ::unlink(path.c_str());
  }
  ::closedir(d);
}

// ---- command files -----------------------------------------------------------------------------

struct FileId {
  std::string given, resolved;
  bool exists = false;
  dev_t dev = 0;
  ino_t ino = 0;
  mode_t mode = 0;
};

FileId identify(const std::string& path) {
  FileId id;
  id.given = path;
  std::error_code ec;
  std::filesystem::path p = std::filesystem::weakly_canonical(std::filesystem::absolute(path), ec);
  id.resolved = ec ? std::filesystem::absolute(path, ec).lexically_normal().string() : p.string();
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    id.exists = true;
    id.dev = st.st_dev;
    id.ino = st.st_ino;
    id.mode = st.st_mode;
  }
  return id;
}

bool same_file(const FileId& a, const FileId& b) {
  return a.resolved == b.resolved || (a.exists && b.exists && a.dev == b.dev && a.ino == b.ino);
}

}  // namespace

uint64_t input_size_limit() {
  return g_input_size_limit.load();
}

void set_input_size_limit(uint64_t bytes) {
  g_input_size_limit.store(bytes);
}

std::vector<uint8_t> read_file(const std::string& path) {
  const std::string name = quote_path(path);
  // O_NONBLOCK: opening a FIFO must not wait for a writer; fstat then refuses it.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) throw CookError("cannot read " + name + ": " + errno_text());
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const std::string reason = errno_text();
    ::close(fd);
    throw CookError("cannot read " + name + ": " + reason);
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    throw CookError("cannot read " + name + ": it is " + kind_of(st.st_mode) +
                    ", not a regular file");
  }
  const uint64_t limit = input_size_limit();
  auto over = [&](uint64_t size) {
    return CookError("cannot read " + name + ": " + std::to_string(size) +
                     " bytes, over the input size limit of " + std::to_string(limit) + " bytes (" +
                     std::to_string(limit >> 20) + " MiB; " + kInputSizeOption + " N raises it)");
  };
  if (uint64_t(st.st_size) > limit) {
    ::close(fd);
    throw over(uint64_t(st.st_size));
  }
  std::vector<uint8_t> out;
  out.reserve(size_t(st.st_size));
  uint8_t buffer[1 << 16];
  for (;;) {  // to the end, not to st_size: the file may have grown, within the limit
    const ssize_t n = ::read(fd, buffer, sizeof(buffer));
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string reason = errno_text();
      ::close(fd);
      throw CookError("cannot read " + name + ": " + reason);
    }
    if (n == 0) break;
    if (out.size() + size_t(n) > limit) {
      ::close(fd);
      throw over(out.size() + size_t(n));
    }
    out.insert(out.end(), buffer, buffer + n);
  }
  ::close(fd);
  return out;
}

void check_command_files(const std::vector<std::string>& inputs,
                         const std::vector<std::string>& outputs) {
  std::vector<FileId> in, out;
  for (const std::string& p : inputs)
    if (!p.empty()) in.push_back(identify(p));
  for (const std::string& p : outputs)
    if (!p.empty()) out.push_back(identify(p));
  for (size_t i = 0; i < out.size(); ++i) {
    const FileId& o = out[i];
    if (o.exists && !S_ISREG(o.mode)) {
      throw CookError("refusing to write " + quote_path(o.given) + ": it exists and is " +
                      kind_of(o.mode) + ", not a regular file");
    }
    for (const FileId& f : in) {
      if (same_file(o, f)) {
        throw CookError("refusing to write " + quote_path(o.given) + ": it is the input " +
                        quote_path(f.given) + " of the same command, which would be lost");
      }
    }
    for (size_t j = 0; j < i; ++j) {
      if (same_file(o, out[j])) {
        throw CookError("refusing to write " + quote_path(o.given) + ": it is also the output " +
                        quote_path(out[j].given) + " of the same command");
      }
    }
  }
}

// ---- atomic files ------------------------------------------------------------------------------

AtomicFile::AtomicFile(const std::string& path) : path_(path), target_(path) {
  if (path.empty()) throw CookError("cannot write: empty output path");
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0) {
    if (S_ISLNK(st.st_mode) && ::stat(path.c_str(), &st) == 0) {
      // Replace what the link points to, and keep the link.
      char real[PATH_MAX];
      if (!S_ISREG(st.st_mode) || ::realpath(path.c_str(), real) == nullptr) {
        throw CookError("cannot write " + quote_path(path) + ": it links to " +
                        kind_of(st.st_mode) + ", not a regular file");
      }
      target_ = real;
    } else if (!S_ISLNK(st.st_mode) && !S_ISREG(st.st_mode)) {
      throw CookError("cannot write " + quote_path(path) + ": it exists and is " +
                      kind_of(st.st_mode) + ", not a regular file");
    }
  }
  remove_stale_temporaries(target_);
  // The temporary lives in the destination's folder so that rename() is atomic.
  temp_ = target_ + kTemporaryMarker + std::to_string(::getpid()) + "-XXXXXX";
  fd_ = ::mkstemp(temp_.data());
  if (fd_ < 0) {
    throw CookError("cannot create a temporary file in " + quote_path(directory_of(target_)) +
                    " (for " + quote_path(path) + "): " + errno_text());
  }
  slot_ = claim_slot(temp_);
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!temp_.empty()) ::unlink(temp_.c_str());
  release_slot(slot_);
}

void AtomicFile::fail(const std::string& what) {
  const std::string reason = errno_text();
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  ::unlink(temp_.c_str());
  temp_.clear();
  release_slot(slot_);
  slot_ = -1;
  throw CookError("cannot write " + quote_path(path_) + " (" + what + "): " + reason);
}

void AtomicFile::write(const void* data, size_t size) {
  if (fd_ < 0) throw CookError("cannot write " + quote_path(path_) + ": already finished");
  const auto* bytes = static_cast<const uint8_t*>(data);
  size_t written = 0;
  while (written < size) {
    const ssize_t n = ::write(fd_, bytes + written, size - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("write");
    }
    written += static_cast<size_t>(n);
  }
}

void AtomicFile::commit() {
  if (fd_ < 0) throw CookError("cannot write " + quote_path(path_) + ": already finished");
  if (::fchmod(fd_, 0644) != 0) fail("chmod");
  if (::fsync(fd_) != 0) fail("fsync");
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail("close");
  if (::rename(temp_.c_str(), target_.c_str()) != 0) fail("rename");
  temp_.clear();
  release_slot(slot_);
  slot_ = -1;
}

void write_file_atomic(const std::string& path, const void* data, size_t size) {
  AtomicFile file(path);
  file.write(data, size);
  file.commit();
}

void install_temporary_cleanup() {
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler != SIG_DFL) continue;
    struct sigaction sa {};
    sa.sa_handler = remove_temporaries_and_die;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND | SA_NODEFER;
    ::sigaction(sig, &sa, nullptr);
  }
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
