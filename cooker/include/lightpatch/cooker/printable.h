// Names and other text from input files, made safe to print in messages and listings: control
// characters and terminal escapes are escaped, invalid UTF-8 shows as \xNN bytes, and long text
// is cut (a 100 MB node name must not become 100 MB of stderr).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace lightpatch::cooker {

// How many bytes of a name, and of a file's path, a message shows before cutting it.
constexpr size_t kMessageNameBytes = 80;
constexpr size_t kMessagePathBytes = 1024;

// `text` with C0/C1 control characters, DEL, backslash, Unicode bidirectional overrides and
// invalid UTF-8 escaped (\n, \t, \\, \xNN, \u202E); at most about `max_bytes` bytes of it, then
// "... (N bytes)" naming the whole length.
std::string printable(std::string_view text, size_t max_bytes = kMessageNameBytes);

// printable(text, max_bytes) in single quotes, as messages name things.
std::string quote(std::string_view text, size_t max_bytes = kMessageNameBytes);
// A file's path in single quotes (cut at kMessagePathBytes).
std::string quote_path(std::string_view path);

}  // namespace lightpatch::cooker
