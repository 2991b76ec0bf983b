// The opt-in heap policy (refit/core/heap.hpp): a large in-memory run grows
// the heap to its estimated peak at once, and the run then reuses that memory.
#include <refit/core/heap.hpp>

#include <gtest/gtest.h>

#include <malloc.h>

#include <cstdlib>
#include <cstring>

namespace refit {
namespace {

// The address sanitizer's allocator replaces glibc's heap (GCC says so with
// __SANITIZE_ADDRESS__, Clang with __has_feature).
#if defined(__SANITIZE_ADDRESS__)
#define REFIT_HEAP_REPLACED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define REFIT_HEAP_REPLACED 1
#endif
#endif

TEST(Heap, ALargeRunsPeakIsHeldByTheHeapAheadAndReused) {
#if defined(REFIT_HEAP_REPLACED)
  GTEST_SKIP() << "the address sanitizer's allocator replaces glibc's heap";
#else
  constexpr std::size_t kMb = std::size_t(1) << 20;
  EXPECT_TRUE(keep_freed_memory());
  const struct mallinfo2 before = mallinfo2();
  grow_heap_for_run(before.uordblks + 400 * kMb);
  const struct mallinfo2 grown = mallinfo2();
  EXPECT_GE(grown.arena + grown.hblkhd, before.arena + 380 * kMb) << "the heap holds the run's estimate";
  EXPECT_LT(grown.uordblks, before.uordblks + kMb) << "everything it took is free again (the threads keep a few KB)";
  // A run's buffers, large ones too, then come from that memory: the heap does not grow.
  char* big = static_cast<char*>(std::malloc(100 * kMb));
  char* more = static_cast<char*>(std::malloc(200 * kMb));
  ASSERT_TRUE(big && more);
  std::memset(big, 1, 100 * kMb);
  std::memset(more, 2, 200 * kMb);
  const struct mallinfo2 used = mallinfo2();
  EXPECT_EQ(used.arena, grown.arena);
  EXPECT_EQ(used.hblkhd, grown.hblkhd) << "no block mapped on its own";
  std::free(more);
  std::free(big);
#endif
}

// A 4M garment's heap, grown to its 2.5 GB estimate, was handed back to the
// system as soon as it was freed (glibc trims a free top above its threshold,
// and the largest one it takes as a number is INT_MAX bytes), so the run
// touched its memory twice. Untouched here: no page is faulted in.
TEST(Heap, AFreedTopAboveTwoGigabytesStaysInTheHeap) {
#if defined(REFIT_HEAP_REPLACED)
  GTEST_SKIP() << "the address sanitizer's allocator replaces glibc's heap";
#else
  constexpr std::size_t kMb = std::size_t(1) << 20;
  EXPECT_TRUE(keep_freed_memory());
  grow_heap_for_run(0);  // every block from the heap (and nothing grown ahead: too small to be worth it)
  char* block = static_cast<char*>(std::malloc(2300 * kMb));
  if (!block) GTEST_SKIP() << "no 2.3 GB of address space here (ulimit -v, or no overcommit)";
  const struct mallinfo2 held = mallinfo2();
  std::free(block);
  const struct mallinfo2 after = mallinfo2();
  EXPECT_GE(after.arena, held.arena) << "the heap's free top is kept for the run to reuse";
#endif
}

}  // namespace
}  // namespace refit
