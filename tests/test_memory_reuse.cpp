#include <gtest/gtest.h>

#include <cstdlib>
#include <vector>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "jobs/memory_reuse.h"

#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define SIRL_OWN_ALLOCATOR 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define SIRL_OWN_ALLOCATOR 1
#endif

namespace sirl {
namespace {

// After keep_freed_memory_for_reuse, a block the size of a JacoRobot cell's heads comes from the
// heap, not from mmap, and the heap keeps it after it is freed, so the next cell's allocation
// finds its pages already mapped. (ctest runs each test in a process of its own.)
TEST(MemoryReuse, ALargeBlockComesFromTheHeapAndStaysAfterItIsFreed) {
#if defined(SIRL_OWN_ALLOCATOR) || !defined(__GLIBC__)
  GTEST_SKIP() << "glibc's allocator only (the sanitizers bring their own)";
#else
  const size_t bytes = size_t(128) << 20;
  const struct mallinfo2 start = mallinfo2();
  keep_freed_memory_for_reuse();
  {
    std::vector<float> big(bytes / sizeof(float), 1.f);
    EXPECT_EQ(mallinfo2().hblkhd, start.hblkhd) << "the block was mmapped";
    EXPECT_GE(mallinfo2().arena, bytes) << "the heap did not grow to hold it";
  }
  EXPECT_GE(mallinfo2().arena, bytes) << "the heap gave the block back";
  EXPECT_GE(mallinfo2().fordblks, bytes / 2) << "the freed block is not free space of the heap";
#endif
}

}  // namespace
}  // namespace sirl
