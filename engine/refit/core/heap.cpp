#include <refit/core/heap.hpp>

#include <refit/core/parallel.hpp>

#include <malloc.h>

#include <cstdlib>
#include <vector>

namespace refit {

// glibc maps every block above its mmap threshold (128 KB, rising with use) on
// its own and unmaps it on free, and trims the heap's top, so each stage's
// vectors of a million rows first-touched fresh pages again, each zeroed by the
// kernel. Blocks up to 32 MB (glibc's largest threshold: a million rows of 3
// doubles is 24 MB) now come from the heap, which is not trimmed. Measured on
// the dense 1M dress (bench/README.md, "Freed memory kept"): minor faults 29k
// -> 15k, system time 1.9 -> 1.1 s. Not trimmed at all (-1): the largest
// threshold (INT_MAX) still trimmed a free top above 2 GB, so a 4M garment's
// heap grown ahead for the run was handed back at once and touched again
// (bench/README.md, "A heap above 2 GB was handed back").
bool keep_freed_memory() {
  // mallopt returns 1 on success (0 from an allocator that takes no such settings).
  const bool threshold = mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024) == 1;
  const bool trim = mallopt(M_TRIM_THRESHOLD, -1) == 1;
  return threshold && trim;
}

void grow_heap_for_run(std::size_t peak_bytes) {
  // Larger blocks too (the element tree's 60 MB of a 1M garment, once a stage):
  // the chunked mode, which keeps its peak to a budget, still maps them.
  mallopt(M_MMAP_MAX, 0);
  // Below this a run's own first touches take a few tens of ms, and the
  // estimate (made for the largest garments) is well above a small run's peak.
  constexpr std::size_t kWorthIt = std::size_t(256) << 20;
  const struct mallinfo2 heap = mallinfo2();
  const std::size_t in_use = heap.uordblks + heap.hblkhd;  // blocks mapped on their own (before this) too
  if (peak_bytes < kWorthIt || peak_bytes <= in_use) return;
  // Blocks below the mmap threshold, freed in reverse: they join the heap's top again.
  constexpr std::size_t kBlock = std::size_t(16) << 20, kPage = 4096;
  std::vector<char*> blocks;
  blocks.reserve((peak_bytes - in_use) / kBlock + 1);
  for (std::size_t got = in_use; got < peak_bytes; got += kBlock) {
    char* b = static_cast<char*>(std::malloc(kBlock));
    if (!b) break;  // less memory than estimated: the run itself says so if it needs it
    blocks.push_back(b);
  }
  parallel_for(0, blocks.size(), 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      volatile char* p = blocks[k];
      for (std::size_t at = 0; at < kBlock; at += kPage) p[at] = 0;
    }
  });
  for (auto it = blocks.rbegin(); it != blocks.rend(); ++it) std::free(*it);
}

// The output's page cache takes as much fresh memory as the file is long, and the
// kernel hands out first what was freed a moment ago. On a virtual machine that
// returns free memory to its host, fresh memory costs about 5 ms per MB more than
// memory freed within seconds, so the heap's free pages (the collision step's
// arrays) handed back just before the write serve the file's pages: the 4M
// dress's write took 6.3-8.4 s, now 0.9 s (bench/README.md, "The heap handed back
// before the last write"). Only before the last body's write: a body after it
// would touch its heap afresh.
void release_free_heap() { malloc_trim(0); }

}  // namespace refit
