// ECRF_MULTIVERSION: compile a hot function twice, for x86-64-v3 (AVX2 + FMA) and for the
// baseline, and pick one at load time: the default build targets baseline x86-64 (SSE2), which
// halves the throughput of the wide float loops (the grid DCT, the entropy model). Empty where
// the compiler lacks target_clones (clang's differ) or the target is not x86-64. One definition
// for every layer that uses it.
#ifndef ECRF_DECODER_MULTIVERSION_H_
#define ECRF_DECODER_MULTIVERSION_H_

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define ECRF_MULTIVERSION __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define ECRF_MULTIVERSION
#endif

#endif  // ECRF_DECODER_MULTIVERSION_H_
