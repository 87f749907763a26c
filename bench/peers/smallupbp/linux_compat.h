// Force-included (g++ -include) into every SmallUPBP translation unit by build.sh.
// Supplies the Microsoft C runtime names SmallUPBP uses, in terms of POSIX/C++11.
// Written for lightgraph's peer build; contains no SmallUPBP code.
#ifndef LIGHTGRAPH_SMALLUPBP_LINUX_COMPAT_H
#define LIGHTGRAPH_SMALLUPBP_LINUX_COMPAT_H

// Standard headers first, so that SmallUPBP's own `#undef INFINITY` (Misc/Defs.hxx,
// which then declares `const float INFINITY = 1e36f`) is not undone by a later <math.h>.
#include <cerrno>
#include <cmath>
#include <math.h>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <algorithm>
#include <iomanip>
#include <iostream>
#include <limits>
#include <omp.h>
#include <x86intrin.h>

// MSVC's <cmath> also declares the C float functions in std.
namespace std {
using ::sqrtf;
}

// Macros, not typedefs: SmallUPBP also writes `unsigned __int64`.
#define __int8 char
#define __int16 short
#define __int32 int
#define __int64 long long
typedef int errno_t;

#ifndef __forceinline
#define __forceinline inline __attribute__((always_inline))
#endif
#define __declspec(spec) __lg_declspec_##spec
#define __lg_declspec_align(n) __attribute__((aligned(n)))

#define _isnanf(x) std::isnan(x)
#define _isnan(x) std::isnan(x)
#define _finite(x) std::isfinite(x)
#define _finitef(x) std::isfinite(x)

// The *_s functions: the buffer-size arguments that follow are ignored by the plain ones.
#define sscanf_s sscanf
#define fscanf_s fscanf
#define sprintf_s snprintf

static inline errno_t fopen_s(FILE **file, const char *name, const char *mode)
{
	*file = std::fopen(name, mode);
	return *file ? 0 : errno;
}

// A temporary where MSVC let SmallUPBP pass one to a non-const reference (port.py).
template <class T> static inline T &lg_lvalue(T &&value)
{
	return value;
}

// Misc/Timer.hxx uses the Windows performance counter; a monotonic clock in nanoseconds.
typedef int64_t LARGE_INTEGER;
static inline int QueryPerformanceFrequency(LARGE_INTEGER *f)
{
	*f = 1000000000LL;
	return 1;
}
static inline int QueryPerformanceCounter(LARGE_INTEGER *t)
{
	timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	*t = (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
	return 1;
}

// SmallUPBP.cxx measures its time budget with clock(), which is wall time on Windows but
// the process's CPU time (all threads summed) on Linux; build.sh points those calls here.
static inline clock_t lg_wall_clock()
{
	return (clock_t)(omp_get_wtime() * CLOCKS_PER_SEC);
}

#endif
