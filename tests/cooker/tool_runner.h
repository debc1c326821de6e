// Runs build/bin/lightpatch as a subprocess, as a user would (the path comes from CMake).
#pragma once

#include <string>
#include <vector>

namespace lightpatch::test {

struct ToolRun {
  int code = -1;  // exit status, or 128 + signal number when killed
  std::string out, err;
};

// Runs `lightpatch args...` and collects its exit status, stdout and stderr.
ToolRun run_tool(const std::vector<std::string>& args);
// The command line and what it printed, for failure messages.
std::string describe(const std::vector<std::string>& args, const ToolRun& r);

// Cook options that keep every cook small and fast (also under ASan).
extern const std::vector<std::string> kFast;
// `a` followed by `b`.
std::vector<std::string> cat(std::vector<std::string> a, const std::vector<std::string>& b);
// Runs `lightpatch args...` and expects exit status 0 (a gtest failure otherwise).
ToolRun expect_success(const std::vector<std::string>& args);

}  // namespace lightpatch::test
