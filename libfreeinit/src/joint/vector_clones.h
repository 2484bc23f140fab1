// Functions built for several instruction sets and chosen at load time (GCC's target_clones):
// AVX-512 (x86-64-v4), AVX2 and the x86-64 baseline. Their vector code runs the same operations
// in the same order per element whatever the width, and the core is built without contraction of
// a * b + c into fused multiply-adds (-ffp-contract=off), so every machine gets the same results.
// Other compilers and architectures build the baseline alone. Only for loops over arrays: GCC
// does not inline a function built for another architecture into the x86-64-v4 clone, so small
// Eigen products there become calls (integrate() and its kin lost 6 % of an initialization that
// way; see docs/performance.md).
#pragma once

#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
#define FREEINIT_VECTOR_CLONES __attribute__((target_clones("arch=x86-64-v4", "avx2", "default")))
#else
#define FREEINIT_VECTOR_CLONES
#endif
