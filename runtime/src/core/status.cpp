#include "lightpatch/status.h"

#include <cstdarg>
#include <cstdio>

namespace lightpatch {

const char* status_name(Status status) {
  switch (status) {
    case Status::kOk:
      return "ok";
    case Status::kInvalidArgument:
      return "invalid argument";
    case Status::kTruncated:
      return "truncated";
    case Status::kBadMagic:
      return "not a lightpatch pack";
    case Status::kUnsupportedVersion:
      return "unsupported version";
    case Status::kCorrupt:
      return "corrupt";
    case Status::kChecksumMismatch:
      return "checksum mismatch";
    case Status::kOutOfMemory:
      return "out of memory";
    case Status::kUnsupported:
      return "unsupported";
    case Status::kGlError:
      return "GL error";
    case Status::kNotFound:
      return "not found";
    case Status::kOverLimit:
      return "over limit";
    case Status::kOutOfRange:
      return "out of range";
  }
  return "unknown";
}

Status set_error(Error* error, Status status, const char* format, ...) {
  if (error != nullptr) {
    error->status = status;
    va_list args;
    va_start(args, format);
    std::vsnprintf(error->message, sizeof(error->message), format, args);
    va_end(args);
  }
  return status;
}

}  // namespace lightpatch
