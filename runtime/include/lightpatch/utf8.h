// UTF-8 decoding, strict (RFC 3629): no overlong forms, no surrogates, nothing above U+10FFFF.
// One rule for the pack's names (PackView::open refuses names that are not UTF-8) and for the
// tools that print them.
#pragma once

#include <cstddef>
#include <cstdint>

namespace lightpatch {

// Decodes the code point starting at s[0] of the `n` bytes at `s` (n >= 1). Returns its length in
// bytes (1..4) and sets *code_point, or returns 0 when the bytes there are not valid UTF-8.
inline size_t utf8_decode(const char* s, size_t n, uint32_t* code_point) {
  const auto* u = reinterpret_cast<const uint8_t*>(s);
  const uint8_t b0 = u[0];
  if (b0 < 0x80) {
    *code_point = b0;
    return 1;
  }
  size_t len = 0;
  uint32_t cp = 0, min = 0;
  if ((b0 & 0xE0) == 0xC0) {
    len = 2, cp = b0 & 0x1Fu, min = 0x80;
  } else if ((b0 & 0xF0) == 0xE0) {
    len = 3, cp = b0 & 0x0Fu, min = 0x800;
  } else if ((b0 & 0xF8) == 0xF0) {
    len = 4, cp = b0 & 0x07u, min = 0x10000;
  } else {
    return 0;  // a continuation byte or 0xF8..0xFF
  }
  if (n < len) return 0;
  for (size_t i = 1; i < len; ++i) {
    if ((u[i] & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (u[i] & 0x3Fu);
  }
  if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
  *code_point = cp;
  return len;
}

// True when the `n` bytes at `s` are valid UTF-8.
inline bool utf8_valid(const char* s, size_t n) {
  uint32_t cp = 0;
  for (size_t i = 0; i < n;) {
    const size_t len = utf8_decode(s + i, n - i, &cp);
    if (len == 0) return false;
    i += len;
  }
  return true;
}

}  // namespace lightpatch
