// The cooker's error type. The cooker (a host tool) uses exceptions internally; the tool's verbs
// catch CookError, print its message and exit non-zero.
#pragma once

#include <stdexcept>
#include <string>

namespace lightpatch::cooker {

class CookError : public std::runtime_error {
 public:
  explicit CookError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace lightpatch::cooker
