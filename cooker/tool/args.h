// A small command-line parser for the tool's verbs: positionals and --options, with errors that
// name the option. Throws ArgsError (caught in main, exit code 2).
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace lightpatch::tool {

class ArgsError : public std::runtime_error {
 public:
  explicit ArgsError(const std::string& m) : std::runtime_error(m) {}
};

struct Args {
  std::string verb;
  std::vector<std::string> items;  // remaining arguments, consumed by the calls below

  // --name VALUE (or --name=VALUE); empty string and false if absent.
  bool option(const std::string& name, std::string* value);
  // --name / -n flag.
  bool flag(const std::string& name, const std::string& short_name = "");
  int int_option(const std::string& name, int fallback, int min_value, int max_value);
  uint64_t count_option(const std::string& name, uint64_t fallback, uint64_t min_value,
                        uint64_t max_value);
  float float_option(const std::string& name, float fallback, float min_value, float max_value);
  // Next positional argument; throws with `what` when absent.
  std::string positional(const std::string& what);
  // Throws if anything is left unconsumed (unknown option or extra argument).
  void finish();
};

}  // namespace lightpatch::tool
