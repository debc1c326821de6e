// The cook report (--report REPORT.json): scene statistics, planned and skipped effects with
// reasons, pairs kept/skipped, time per stage, rays traced.
#pragma once

#include <nlohmann/json.hpp>

#include <mutex>
#include <string>

namespace lightpatch::cooker {

class Report {
 public:
  // Each section is a JSON object the stages fill; access under lock from worker threads.
  nlohmann::json& root() { return root_; }
  std::mutex& mutex() { return mutex_; }
  void stage_time(const std::string& stage, double seconds);
  void add_decision(const std::string& what, bool taken, const std::string& reason);
  // With the seconds the decision's work took (where one decision's work is timed on its own).
  void add_decision(const std::string& what, bool taken, const std::string& reason, double seconds);
  // Atomic write (temporary file + rename). Throws CookError.
  void write(const std::string& path) const;

 private:
  nlohmann::json root_ = nlohmann::json::object();
  std::mutex mutex_;
};

}  // namespace lightpatch::cooker
