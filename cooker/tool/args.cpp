#include "args.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace lightpatch::tool {

bool Args::option(const std::string& name, std::string* value) {
  const std::string eq = name + "=";
  for (size_t i = 0; i < items.size(); ++i) {
    if (items[i] == name) {
      if (i + 1 >= items.size()) throw ArgsError(name + " needs a value");
      *value = items[i + 1];
      items.erase(items.begin() + static_cast<long>(i), items.begin() + static_cast<long>(i) + 2);
      return true;
    }
    if (items[i].rfind(eq, 0) == 0) {
      *value = items[i].substr(eq.size());
      items.erase(items.begin() + static_cast<long>(i));
      return true;
    }
  }
  value->clear();
  return false;
}

bool Args::flag(const std::string& name, const std::string& short_name) {
  for (size_t i = 0; i < items.size(); ++i) {
    if (items[i] == name || (!short_name.empty() && items[i] == short_name)) {
      items.erase(items.begin() + static_cast<long>(i));
      return true;
    }
  }
  return false;
}

int Args::int_option(const std::string& name, int fallback, int min_value, int max_value) {
  std::string v;
  if (!option(name, &v)) return fallback;
  errno = 0;
  char* end = nullptr;
  const long x = std::strtol(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || errno != 0 || x < min_value || x > max_value) {
    throw ArgsError(name + " takes an integer in [" + std::to_string(min_value) + ", " +
                    std::to_string(max_value) + "], got '" + v + "'");
  }
  return static_cast<int>(x);
}

uint64_t Args::count_option(const std::string& name, uint64_t fallback, uint64_t min_value,
                            uint64_t max_value) {
  std::string v;
  if (!option(name, &v)) return fallback;
  errno = 0;
  char* end = nullptr;
  const unsigned long long x = std::strtoull(v.c_str(), &end, 10);
  if (v.empty() || v[0] == '-' || *end != '\0' || errno != 0 || x < min_value || x > max_value) {
    throw ArgsError(name + " takes an integer in [" + std::to_string(min_value) + ", " +
                    std::to_string(max_value) + "], got '" + v + "'");
  }
  return x;
}

float Args::float_option(const std::string& name, float fallback, float min_value,
                         float max_value) {
  std::string v;
  if (!option(name, &v)) return fallback;
  char* end = nullptr;
  const float x = std::strtof(v.c_str(), &end);
  if (v.empty() || *end != '\0' || !std::isfinite(x) || x < min_value || x > max_value) {
    throw ArgsError(name + " takes a number in [" + std::to_string(min_value) + ", " +
                    std::to_string(max_value) + "], got '" + v + "'");
  }
  return x;
}

std::string Args::positional(const std::string& what) {
  for (size_t i = 0; i < items.size(); ++i) {
    if (items[i].size() > 1 && items[i][0] == '-') continue;
    std::string v = items[i];
    items.erase(items.begin() + static_cast<long>(i));
    return v;
  }
  throw ArgsError("missing " + what);
}

void Args::finish() {
  if (!items.empty()) throw ArgsError("unexpected argument '" + items.front() + "'");
}

}  // namespace lightpatch::tool
