#include "lightpatch/cooker/printable.h"

#include <cstdint>
#include <cstdio>

#include "lightpatch/utf8.h"

namespace lightpatch::cooker {

namespace {

// Code points a terminal could act on or that reorder the text around them.
bool must_escape(uint32_t cp) {
  return cp < 0x20 || cp == 0x7F || (cp >= 0x80 && cp <= 0x9F) || cp == '\\' ||
         (cp >= 0x202A && cp <= 0x202E) || (cp >= 0x2066 && cp <= 0x2069);
}

void append_escape(std::string* out, uint32_t cp, bool raw_byte) {
  char buf[16];
  if (!raw_byte && cp == '\n') {
    *out += "\\n";
  } else if (!raw_byte && cp == '\t') {
    *out += "\\t";
  } else if (!raw_byte && cp == '\r') {
    *out += "\\r";
  } else if (!raw_byte && cp == '\\') {
    *out += "\\\\";
  } else if (raw_byte || cp < 0x80) {
    std::snprintf(buf, sizeof buf, "\\x%02X", unsigned(cp));
    *out += buf;
  } else {
    std::snprintf(buf, sizeof buf, "\\u%04X", unsigned(cp));
    *out += buf;
  }
}

}  // namespace

std::string printable(std::string_view text, size_t max_bytes) {
  std::string out;
  size_t i = 0;
  while (i < text.size() && out.size() < max_bytes) {
    uint32_t cp = 0;
    const size_t len = utf8_decode(text.data() + i, text.size() - i, &cp);
    if (len == 0) {
      append_escape(&out, static_cast<uint8_t>(text[i]), true);
      ++i;
    } else {
      if (must_escape(cp))
        append_escape(&out, cp, false);
      else
        out.append(text.data() + i, len);
      i += len;
    }
  }
  if (i < text.size()) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

std::string quote(std::string_view text, size_t max_bytes) {
  return "'" + printable(text, max_bytes) + "'";
}

std::string quote_path(std::string_view path) {
  return quote(path, kMessagePathBytes);
}

}  // namespace lightpatch::cooker
