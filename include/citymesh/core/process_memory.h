// SPDX-License-Identifier: MIT
// This process's memory, for progress lines and run reports (Linux /proc; 0 elsewhere).
#pragma once

#include <cstdint>

namespace citymesh {

/// Resident set size now, in bytes.
std::uint64_t resident_bytes();
/// Largest resident set size so far (VmHWM), in bytes.
std::uint64_t peak_resident_bytes();

}  // namespace citymesh
