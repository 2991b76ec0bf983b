#pragma once
// An opt-in memory policy for a process that resizes large garments: how
// glibc's heap grows and is reused. The library never sets it by itself (it
// leaves a host program's allocator alone); the command line sets it at start,
// and a host such as the Python module or its batch workers may opt in.
#include <cstddef>

namespace refit {

/// Freed buffers kept for the next ones instead of handed back to the system
/// (see heap.cpp), for the whole process. Call once, before anything large is
/// allocated. Returns false where it does nothing (an allocator other than
/// glibc's, such as a sanitizer's).
bool keep_freed_memory();

/// For a garment resized in memory by the whole pipeline, whose peak is
/// estimated at `peak_bytes` (a run's true peak, not a bound far above it):
/// blocks of any size come from the heap, and when the run is large the heap
/// is grown to the estimate at once, its new memory first-touched by all worker
/// threads, then freed for the run to reuse. On a virtual machine a first touch
/// costs a fault the kernel serves by zeroing the page, and a run's serial
/// parts touched much of their memory one thread at a time (bench/README.md,
/// "The heap grown ahead"). Not for the chunked mode, whose peak it would raise.
void grow_heap_for_run(std::size_t peak_bytes);

/// The heap's free memory handed back to the system, before the run's last output
/// is written (see heap.cpp): the file's page cache then reuses it.
void release_free_heap();

}  // namespace refit
