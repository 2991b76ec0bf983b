#pragma once
// The command's memory policy: how its heap grows and is reused. Only the
// command sets it; the library leaves a host program's allocator alone.
#include <cstddef>

namespace refit::cli {

/// Freed buffers kept for the next ones instead of handed back to the system
/// (see heap.cpp). Call once, before anything large is allocated.
void keep_freed_memory();

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

}  // namespace refit::cli
