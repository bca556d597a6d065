#include "ecrf/decoder.h"

#include "format/container.h"
#include "format/status.h"

// The C API returns the internal codes unchanged (Record in c_api.cc), so each ECRF_ERR_* must be
// its ecrf::ErrorCode.
static_assert(ECRF_OK == ecrf::kOk, "ECRF_OK");
static_assert(ECRF_ERR_INVALID_ARGUMENT == ecrf::kErrInvalidArgument, "ECRF_ERR_INVALID_ARGUMENT");
static_assert(ECRF_ERR_TRUNCATED == ecrf::kErrTruncated, "ECRF_ERR_TRUNCATED");
static_assert(ECRF_ERR_CORRUPT == ecrf::kErrCorrupt, "ECRF_ERR_CORRUPT");
static_assert(ECRF_ERR_UNSUPPORTED == ecrf::kErrUnsupported, "ECRF_ERR_UNSUPPORTED");
static_assert(ECRF_ERR_LIMIT == ecrf::kErrLimit, "ECRF_ERR_LIMIT");
static_assert(ECRF_ERR_CHECKSUM == ecrf::kErrChecksum, "ECRF_ERR_CHECKSUM");
static_assert(ECRF_ERR_OUT_OF_MEMORY == ecrf::kErrOutOfMemory, "ECRF_ERR_OUT_OF_MEMORY");
static_assert(ECRF_VERSION_MINOR < 256 && ECRF_VERSION_PATCH < 256,
              "ecrf_version packs minor and patch into 8 bits each");

#define ECRF_TEXT(x) #x
#define ECRF_NUMBER_TEXT(x) ECRF_TEXT(x)
#define ECRF_VERSION_TEXT              \
  ECRF_NUMBER_TEXT(ECRF_VERSION_MAJOR) \
  "." ECRF_NUMBER_TEXT(ECRF_VERSION_MINOR) "." ECRF_NUMBER_TEXT(ECRF_VERSION_PATCH)

extern "C" {

unsigned ecrf_version(void) {
  return (unsigned{ECRF_VERSION_MAJOR} << 16) | (unsigned{ECRF_VERSION_MINOR} << 8) |
         unsigned{ECRF_VERSION_PATCH};
}
const char* ecrf_version_string(void) { return ECRF_VERSION_TEXT; }
int ecrf_bitstream_version(void) { return ecrf::kVersionMajor; }
int ecrf_bitstream_version_minor(void) { return ecrf::kVersionMinor; }
const char* ecrf_error_name(int code) { return ecrf::ErrorCodeName(code); }

}  // extern "C"
