// SPDX-License-Identifier: MIT
// This process's memory, for progress lines and run reports (Linux /proc; 0 elsewhere), and
// how the allocator hands it back.
#pragma once

#include <cstdint>
#include <string>

namespace citymesh {

/// Resident set size now, in bytes.
std::uint64_t resident_bytes();
/// Largest resident set size so far (VmHWM), in bytes.
std::uint64_t peak_resident_bytes();
/// This machine's physical memory, in bytes (0 where it cannot be told).
std::uint64_t physical_memory_bytes();
/// What a memory budget leaves beside the resident set now (0 once it is passed).
std::uint64_t memory_left(std::uint64_t budget);
/// "resident N MiB (peak M MiB)": how the debug lines of long stages report memory.
std::string memory_note();

/// Makes the C allocator keep freed memory for the next allocation instead of returning it to
/// the system (glibc: no mmap for large blocks, no trimming of the heap's top). Each tile and
/// each mosaic allocates and frees the same large arrays (the energy's pair index alone is
/// ~150 MB on a street); returned, every page is faulted in and zeroed again by the kernel on
/// the next use, a tenth of the mosaic's time. The resident set then stays at its peak until
/// release_freed_memory(): the peak, which the memory budget bounds, does not change. Call
/// once, first thing in main(); a no-op elsewhere than glibc.
void keep_freed_memory_for_reuse();

/// Gives the free memory the allocator kept back to the system (glibc: malloc_trim over every
/// arena). For the boundaries between a run's stages: what one stage freed is not what the
/// next allocates, and would otherwise stay resident under the next stage's peak. A no-op
/// elsewhere than glibc.
void release_freed_memory();

}  // namespace citymesh
