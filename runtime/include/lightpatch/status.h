// Error codes and messages returned across the runtime's API (no exceptions).
#pragma once

#include <cstdint>

namespace lightpatch {

enum class Status : int32_t {
  kOk = 0,
  kInvalidArgument,  // a caller's argument is out of range or null
  kTruncated,        // the data ends before a structure it declares
  kBadMagic,         // not a lightpatch pack
  kUnsupportedVersion,
  kCorrupt,           // a field, offset, index or rectangle is out of range or inconsistent
  kChecksumMismatch,  // table checksum does not match
  kOutOfMemory,       // an allocation at load time failed
  kUnsupported,       // the device lacks a required feature
  kGlError,           // the GL driver reported an error
  kNotFound,          // a name lookup failed
  kOverLimit,         // valid, but asks for more than the stated limits (RecomposeLimits)
  kOutOfRange,        // a value the light map cannot represent (see Runtime::set_light)
};

const char* status_name(Status status);

// A message for the user: what is wrong and where. Fixed size so that filling it never allocates.
struct Error {
  Status status = Status::kOk;
  char message[256] = {};
};

// Fills `error` (if non-null) with status and a printf-style message; returns status.
Status set_error(Error* error, Status status, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

}  // namespace lightpatch
