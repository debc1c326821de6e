// The nesting depth of JSON text, measured before a parser sees it: tinygltf and nlohmann's
// dump() recurse once per level, so a file nested 100,000 levels deep overflows the stack.
// glTF and state files nest a few levels; callers refuse anything deeper than kMaxJsonDepth.
#pragma once

#include <cstddef>

namespace lightpatch::cooker {

constexpr int kMaxJsonDepth = 256;

// True when the brackets of `text` (outside strings) nest deeper than `max_depth`.
inline bool json_deeper_than(const char* text, size_t size, int max_depth) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (size_t i = 0; i < size; ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) return true;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return false;
}

}  // namespace lightpatch::cooker
