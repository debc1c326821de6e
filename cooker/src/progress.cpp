#include "lightpatch/cooker/progress.h"

#include <unistd.h>

#include <cstdio>

#include "lightpatch/cooker/printable.h"

namespace lightpatch::cooker {

namespace {
// What a progress line shows of a stage's label and of a message at most.
constexpr size_t kStageBytes = 120;
constexpr size_t kMessageBytes = 2000;
}  // namespace

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

Progress::Progress(bool quiet)
    : quiet_(quiet),
      tty_(::isatty(::fileno(stderr)) != 0),
      start_(std::chrono::steady_clock::now()),
      stage_start_(start_) {}

void Progress::begin(const std::string& stage, uint64_t total) {
  std::lock_guard<std::mutex> lock(mutex_);
  stage_ = printable(stage, kStageBytes);  // stages name lights and objects: cut, escaped
  total_ = total;
  done_.store(0);
  last_percent_ = -1;
  stage_start_ = std::chrono::steady_clock::now();
  draw(false);
}

void Progress::advance(uint64_t units) {
  const uint64_t done = done_.fetch_add(units) + units;
  if (quiet_ || total_ == 0) return;
  const int percent = static_cast<int>(done >= total_ ? 100 : done * 100 / total_);
  // Redraw only when the percentage moves; never block a worker on the terminal.
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;
  if (percent <= last_percent_) return;
  draw(false);
}

double Progress::end() {
  std::lock_guard<std::mutex> lock(mutex_);
  done_.store(total_);
  draw(true);
  return seconds_since(stage_start_);
}

void Progress::message(const std::string& text) {
  if (quiet_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (tty_) std::fprintf(stderr, "\r\033[K");
  std::fprintf(stderr, "%s\n", printable(text, kMessageBytes).c_str());
}

// Caller holds mutex_.
void Progress::draw(bool final_line) {
  const uint64_t done = done_.load();
  const int percent =
      total_ == 0 ? 100 : static_cast<int>(done >= total_ ? 100 : done * 100 / total_);
  if (quiet_) {
    last_percent_ = percent;
    return;
  }
  const double elapsed = seconds_since(start_);
  if (tty_) {
    std::fprintf(stderr, "\r\033[K[%7.1fs] %-24s %3d%%%s", elapsed, stage_.c_str(), percent,
                 final_line ? "\n" : "");
  } else if (final_line) {
    std::fprintf(stderr, "[%7.1fs] %-24s done in %.2fs\n", elapsed, stage_.c_str(),
                 seconds_since(stage_start_));
  } else if (last_percent_ < 0 || percent / 25 != last_percent_ / 25) {
    // Logs get a line at the start and every quarter.
    std::fprintf(stderr, "[%7.1fs] %-24s %3d%%\n", elapsed, stage_.c_str(), percent);
  }
  std::fflush(stderr);
  last_percent_ = percent;
}

}  // namespace lightpatch::cooker
