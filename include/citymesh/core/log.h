// SPDX-License-Identifier: MIT
// Logging to stderr (spdlog behind this header): text for people, JSON lines for machines.
#pragma once

#include <fmt/format.h>

#include <string_view>

namespace citymesh::log {

enum class Level { trace, debug, info, warn, error, off };
enum class Format { text, json };

/// Parses "trace", "debug", "info", "warn", "error" or "off"; throws UsageError otherwise.
Level parse_level(std::string_view name);
/// Sets up the process-wide stderr logger. Safe to call again (tests, re-configuration).
void configure(Level level, Format format);
void write(Level level, std::string_view message);
[[nodiscard]] bool enabled(Level level);

template <class... Args>
void debug(fmt::format_string<Args...> f, Args&&... args) {
  if (enabled(Level::debug)) write(Level::debug, fmt::format(f, std::forward<Args>(args)...));
}
template <class... Args>
void info(fmt::format_string<Args...> f, Args&&... args) {
  if (enabled(Level::info)) write(Level::info, fmt::format(f, std::forward<Args>(args)...));
}
template <class... Args>
void warn(fmt::format_string<Args...> f, Args&&... args) {
  if (enabled(Level::warn)) write(Level::warn, fmt::format(f, std::forward<Args>(args)...));
}
template <class... Args>
void error(fmt::format_string<Args...> f, Args&&... args) {
  if (enabled(Level::error)) write(Level::error, fmt::format(f, std::forward<Args>(args)...));
}

}  // namespace citymesh::log
