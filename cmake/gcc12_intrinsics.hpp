// Included before every source file of the package when the compiler is GCC older than 12.3
// on x86 (CMakeLists.txt). GCC 12.0-12.2 warn "'__Y' may be used
// uninitialized" inside their own AVX-512 intrinsics (avx512fintrin.h, GCC bug 105593: the
// intrinsics start from an _mm512_undefined_* value on purpose) wherever Eigen instantiates its
// AVX-512 kernels, i.e. with -march=x86-64-v4, skylake-avx512 or native on such a CPU. The
// warning is switched off for the intrinsics headers alone: included here first, under the
// pragma, their include guards keep every later #include from re-reading them, and the
// package's own code keeps -Wmaybe-uninitialized (and -Werror with ACVO_WERROR).
#pragma once
// (Clang reads this file too, in clang-tidy, and knows neither the bug nor the warning.)
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
#include <immintrin.h>
#pragma GCC diagnostic pop
#endif
