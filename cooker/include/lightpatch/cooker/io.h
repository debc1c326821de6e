// File helpers for the tools, and the one place their file-safety rules live:
//  * reads take regular files only (never a FIFO, a device or a directory), up to a size limit
//    (input_size_limit(); the tool's --max-input-mb raises it);
//  * writes are atomic (a temporary in the same folder, flushed, then renamed), never replace
//    something that is not a regular file, and leave no temporary behind: removed on failure, on
//    SIGINT/SIGTERM/SIGHUP (install_temporary_cleanup()), and a killed run's leftover (named
//    OUT.lightpatch-tmp-PID-XXXXXX) is removed by the next write of the same OUT;
//  * check_command_files() refuses, before any work, a command whose output is one of its inputs
//    or another of its outputs;
//  * PFM float images (scanlines bottom to top, as the format says).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/cooker/maps.h"

namespace lightpatch::cooker {

// Input files larger than this are refused unless raised (README, "Limits").
constexpr uint64_t kDefaultInputSizeLimit = uint64_t(1) << 30;  // 1 GiB
uint64_t input_size_limit();
void set_input_size_limit(uint64_t bytes);
// The option that raises it, for messages.
constexpr const char* kInputSizeOption = "--max-input-mb";

// The whole of a regular file of at most input_size_limit() bytes. Throws CookError naming the
// file and the reason (missing, not a regular file, over the limit and how to raise it).
std::vector<uint8_t> read_file(const std::string& path);

// Checks a command's files before it does any work (empty paths are ignored): no output may be
// an input or another output, compared by path (after resolving links and "..") and by device and
// inode; an output that exists must be a regular file (or a link to one). Throws CookError naming
// both files.
void check_command_files(const std::vector<std::string>& inputs,
                         const std::vector<std::string>& outputs);

// A file written in full or not at all. The constructor refuses a destination that exists and is
// not a regular file (a link to a regular file is followed: its target is replaced), removes
// leftovers of killed runs for the same destination and creates the temporary. commit() flushes
// and renames; the destructor removes an uncommitted temporary. Throws CookError.
class AtomicFile {
 public:
  explicit AtomicFile(const std::string& path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  void write(const void* data, size_t size);
  void commit();
  const std::string& temporary_path() const { return temp_; }

 private:
  void fail(const std::string& what);
  std::string path_, target_, temp_;
  int fd_ = -1;
  int slot_ = -1;  // where the signal handler finds temp_
};

// Writes `size` bytes to `path` through an AtomicFile: nothing is left at `path` unless the whole
// write succeeded; an existing file stays untouched on failure. Throws CookError.
void write_file_atomic(const std::string& path, const void* data, size_t size);

// Installs handlers for SIGINT, SIGTERM and SIGHUP (where their disposition is the default) that
// remove every AtomicFile temporary of the process, then die of the same signal. For tools.
void install_temporary_cleanup();

// The marker in temporary names: OUT + kTemporaryMarker + PID + "-" + 6 random characters.
constexpr const char* kTemporaryMarker = ".lightpatch-tmp-";

// PFM: "PF" (3 channels) or "Pf" (1 channel), little-endian (scale -1). FloatImage row 0 is the
// top row, so it is written last.
void write_pfm(const std::string& path, const FloatImage& image);  // atomic; throws CookError
FloatImage read_pfm(const std::string& path);                      // throws CookError

}  // namespace lightpatch::cooker
