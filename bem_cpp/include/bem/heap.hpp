#pragma once
// The C library's heap after a set-up: the near fields and the blocks' scratch of an
// H-matrix set-up are many small allocations, freed when it ends, which glibc's malloc keeps
// in its heaps (one per thread) rather than returning them to the system; the later large
// arrays (NumPy's, mapped anew) cannot reuse them. On the 3D Lame S_h of 24^3 cubes' surface:
// 548 MB resident after the set-up, 340 MB after release_free_heap() (the operator holds
// 289 MB; docs/design/elasticity.md).
#include <cstdlib>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace bem {

/// Returns the free memory at the top and inside the C library's heaps to the system (glibc:
/// malloc_trim(0); elsewhere nothing). true if some was returned.
inline bool release_free_heap() {
#if defined(__GLIBC__)
  return malloc_trim(0) != 0;
#else
  return false;
#endif
}

}  // namespace bem
