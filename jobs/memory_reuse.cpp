#include "jobs/memory_reuse.h"

#include <cstdlib>  // defines __GLIBC__ on glibc
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace sirl {

void keep_freed_memory_for_reuse() {
#if defined(__GLIBC__)
  mallopt(M_ARENA_MAX, 1);
  mallopt(M_MMAP_MAX, 0);         // when the heap cannot grow, glibc still falls back to mmap
  mallopt(M_TRIM_THRESHOLD, -1);  // never give the heap's top back (the largest value: no trim)
#endif
}

}  // namespace sirl
