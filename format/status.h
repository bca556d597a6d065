// Status: how every ecrf component reports failure without exceptions.
//
// The decoder and format/ build with -fno-exceptions, so errors travel as values. Codes are
// negative (0 is success) so the C API can return them unchanged. The message is a fixed buffer:
// producing an error never allocates, which matters when the error is "out of memory".
#ifndef ECRF_FORMAT_STATUS_H_
#define ECRF_FORMAT_STATUS_H_

namespace ecrf {

enum ErrorCode : int {
  kOk = 0,
  kErrInvalidArgument = -1,  // the caller passed something impossible (null buffer, bad size)
  kErrTruncated = -2,        // the data ended before the syntax said it would
  kErrCorrupt = -3,          // the data is present but violates the syntax or its semantics
  kErrUnsupported = -4,      // valid syntax for a feature or version this build does not know
  kErrLimit = -5,            // a size exceeds a decoder limit (checked before allocating)
  kErrChecksum = -6,         // a CRC did not match
  kErrOutOfMemory = -7,
  kErrIo = -8,  // file system errors (host tools only)
};

// Short, stable name of a code ("truncated", "corrupt", ...).
const char* ErrorCodeName(int code);

// [[nodiscard]]: a Status dropped on the floor is an error nobody sees; a caller that ignores one
// on purpose casts it to void and says why.
class [[nodiscard]] Status {
 public:
  Status() : code_(kOk) { message_[0] = '\0'; }
  static Status Ok() { return Status(); }
  // printf-style message: say what failed, where (offset, chunk, index) and why.
  static Status Error(int code, const char* format, ...)
#if defined(__GNUC__)
      __attribute__((format(printf, 2, 3)))
#endif
      ;

  bool ok() const { return code_ == kOk; }
  int code() const { return code_; }
  const char* message() const { return message_; }

 private:
  static constexpr int kMessageCapacity = 480;
  int code_;
  char message_[kMessageCapacity];
};

}  // namespace ecrf

#define ECRF_RETURN_IF_ERROR(expr)               \
  do {                                           \
    ::ecrf::Status ecrf_status_ = (expr);        \
    if (!ecrf_status_.ok()) return ecrf_status_; \
  } while (0)

// Validation in the style of dav1d's validate_input: fail with a message naming the condition.
#define ECRF_CHECK_OR_RETURN(cond, code, ...)                       \
  do {                                                              \
    if (!(cond)) return ::ecrf::Status::Error((code), __VA_ARGS__); \
  } while (0)

#endif  // ECRF_FORMAT_STATUS_H_
