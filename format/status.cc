#include "format/status.h"

#include <cstdarg>
#include <cstdio>

namespace ecrf {

const char* ErrorCodeName(int code) {
  switch (code) {
    case kOk:
      return "ok";
    case kErrInvalidArgument:
      return "invalid argument";
    case kErrTruncated:
      return "truncated";
    case kErrCorrupt:
      return "corrupt";
    case kErrUnsupported:
      return "unsupported";
    case kErrLimit:
      return "limit exceeded";
    case kErrChecksum:
      return "checksum mismatch";
    case kErrOutOfMemory:
      return "out of memory";
    case kErrIo:
      return "i/o error";
    default:
      return "unknown error";
  }
}

Status Status::Error(int code, const char* format, ...) {
  Status s;
  s.code_ = code == kOk ? kErrInvalidArgument : code;
  va_list args;
  va_start(args, format);
  std::vsnprintf(s.message_, kMessageCapacity, format, args);
  va_end(args);
  return s;
}

}  // namespace ecrf
