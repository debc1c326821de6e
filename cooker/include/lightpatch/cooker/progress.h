// Progress on the terminal during long work: stage, percent, elapsed. Thread-safe; quiet mode
// prints nothing. Writes to stderr, redrawing one line when stderr is a terminal.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace lightpatch::cooker {

// Wall-clock seconds from `t` to now.
double seconds_since(std::chrono::steady_clock::time_point t);

class Progress {
 public:
  explicit Progress(bool quiet);
  // Starts a named stage of `total` work units.
  void begin(const std::string& stage, uint64_t total);
  // Adds finished units (any thread).
  void advance(uint64_t units = 1);
  // Ends the stage; returns its elapsed seconds.
  double end();
  void message(
      const std::string& text);  // a line of its own (not suppressed by quiet? no: suppressed)
  bool quiet() const { return quiet_; }

 private:
  void draw(bool final_line);
  bool quiet_;
  bool tty_;
  std::mutex mutex_;
  std::string stage_;
  uint64_t total_ = 0;
  std::atomic<uint64_t> done_{0};
  int last_percent_ = -1;
  std::chrono::steady_clock::time_point start_, stage_start_;
};

}  // namespace lightpatch::cooker
