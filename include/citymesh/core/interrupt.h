// SPDX-License-Identifier: MIT
// Cooperative interruption: SIGINT/SIGTERM set a flag that long loops poll.
#pragma once

#include <string_view>

namespace citymesh {

/// Installs SIGINT and SIGTERM handlers that request an interruption.
void install_interrupt_handlers();
/// True once a signal arrived (or request_interrupt() was called).
[[nodiscard]] bool interrupt_requested() noexcept;
void request_interrupt() noexcept;
void clear_interrupt() noexcept;
/// Throws InterruptedError mentioning `where` if an interruption was requested.
void throw_if_interrupted(std::string_view where);

}  // namespace citymesh
