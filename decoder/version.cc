#include "ecrf/decoder.h"

#include "format/container.h"
#include "format/status.h"

static_assert(ECRF_ERR_TRUNCATED == ecrf::kErrTruncated && ECRF_ERR_CORRUPT == ecrf::kErrCorrupt &&
                  ECRF_ERR_LIMIT == ecrf::kErrLimit &&
                  ECRF_ERR_OUT_OF_MEMORY == ecrf::kErrOutOfMemory,
              "C API error codes must equal the internal ones");

extern "C" {

unsigned ecrf_version(void) { return (0u << 16) | (2u << 8) | 0u; }
const char* ecrf_version_string(void) { return "0.2.0"; }
int ecrf_bitstream_version(void) { return ecrf::kVersionMajor; }
const char* ecrf_error_name(int code) { return ecrf::ErrorCodeName(code); }

}  // extern "C"
