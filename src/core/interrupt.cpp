// SPDX-License-Identifier: MIT
// Signal handlers only set an atomic flag; work stops at the next poll, leaving no torn files.
#include "citymesh/core/interrupt.h"

#include <fmt/format.h>

#include <atomic>
#include <csignal>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {
std::atomic<bool> g_interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "signal handler needs a lock-free flag");

extern "C" void on_signal(int /*signal*/) { g_interrupted.store(true, std::memory_order_relaxed); }
}  // namespace

void install_interrupt_handlers() {
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
}

bool interrupt_requested() noexcept { return g_interrupted.load(std::memory_order_relaxed); }
void request_interrupt() noexcept { g_interrupted.store(true); }
void clear_interrupt() noexcept { g_interrupted.store(false); }

void throw_if_interrupted(std::string_view where) {
  if (interrupt_requested()) {
    throw InterruptedError(fmt::format("{}: interrupted; re-run the same command to resume", where));
  }
}

}  // namespace citymesh
