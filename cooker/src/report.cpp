#include "lightpatch/cooker/report.h"

#include "lightpatch/cooker/io.h"

namespace lightpatch::cooker {

void Report::stage_time(const std::string& stage, double seconds) {
  std::lock_guard<std::mutex> lock(mutex_);
  nlohmann::json& stages = root_["stages"];
  if (!stages.is_object()) stages = nlohmann::json::object();
  const double before = stages.contains(stage) ? stages[stage].get<double>() : 0.0;
  stages[stage] = before + seconds;
}

void Report::add_decision(const std::string& what, bool taken, const std::string& reason) {
  std::lock_guard<std::mutex> lock(mutex_);
  nlohmann::json& decisions = root_["decisions"];
  if (!decisions.is_array()) decisions = nlohmann::json::array();
  decisions.push_back({{"what", what}, {"taken", taken}, {"reason", reason}});
}

void Report::add_decision(const std::string& what, bool taken, const std::string& reason,
                          double seconds) {
  std::lock_guard<std::mutex> lock(mutex_);
  nlohmann::json& decisions = root_["decisions"];
  if (!decisions.is_array()) decisions = nlohmann::json::array();
  decisions.push_back({{"what", what}, {"taken", taken}, {"reason", reason}, {"seconds", seconds}});
}

void Report::write(const std::string& path) const {
  const std::string text = root_.dump(2) + "\n";
  write_file_atomic(path, text.data(), text.size());
}

}  // namespace lightpatch::cooker
