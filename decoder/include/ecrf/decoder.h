/* ecrf decoder: C API. Depends on nothing but the C++ standard library inside.
 *
 * Functions return 0 or a negative error code (ECRF_ERR_*); messages are available per handle.
 * The scene API (open, decode grids, render) lands with the bitstream work; this header fixes
 * the conventions it will follow. */
#ifndef ECRF_DECODER_H_
#define ECRF_DECODER_H_

#ifdef __cplusplus
extern "C" {
#endif

#define ECRF_OK 0
#define ECRF_ERR_INVALID_ARGUMENT (-1)
#define ECRF_ERR_TRUNCATED (-2)
#define ECRF_ERR_CORRUPT (-3)
#define ECRF_ERR_UNSUPPORTED (-4)
#define ECRF_ERR_LIMIT (-5)
#define ECRF_ERR_CHECKSUM (-6)
#define ECRF_ERR_OUT_OF_MEMORY (-7)

/* Library version as (major << 16) | (minor << 8) | patch, and as text. */
unsigned ecrf_version(void);
const char* ecrf_version_string(void);
/* Highest bitstream major version this decoder reads. */
int ecrf_bitstream_version(void);
/* Short name of an error code ("truncated", "corrupt", ...). */
const char* ecrf_error_name(int code);

#ifdef __cplusplus
}
#endif

#endif /* ECRF_DECODER_H_ */
