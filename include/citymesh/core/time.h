// SPDX-License-Identifier: MIT
// UTC dates, durations and byte sizes as users write them in configs ("2026-01-05T10:00:00Z",
// "30d", "2GiB"), parsed and printed without depending on the locale.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>

namespace citymesh {

/// A UTC instant with millisecond resolution (acquisition dates).
using TimePoint = std::chrono::sys_time<std::chrono::milliseconds>;
/// A signed span of time with millisecond resolution (sustainability and the like).
using Duration = std::chrono::milliseconds;

/// Parses ISO 8601: "YYYY-MM-DD", "YYYY-MM-DDThh:mm[:ss[.fff]]" followed by "Z" or "+hh:mm"/
/// "-hh:mm" (a date-time without a zone is refused: acquisition dates must be unambiguous).
/// Throws ConfigError naming `what` on malformed text.
TimePoint parse_iso8601(std::string_view text, std::string_view what);
/// "2026-01-05T10:00:00Z" (milliseconds printed only when non-zero).
std::string format_iso8601(TimePoint t);

/// Parses "<number><unit>" with unit s, min, h, d or w ("30d", "12h", "1.5h").
/// Throws ConfigError naming `what`.
Duration parse_duration(std::string_view text, std::string_view what);
/// Shortest exact spelling: "30d", "12h", "90s", "1500ms".
std::string format_duration(Duration d);

/// Parses "<number>[unit]" with unit B, KiB, MiB, GiB, TiB, kB, MB, GB, TB ("2GiB", "512MiB").
/// Throws ConfigError naming `what`.
std::uint64_t parse_byte_size(std::string_view text, std::string_view what);
/// Shortest exact binary spelling: "2GiB", "1536MiB", "100B".
std::string format_byte_size(std::uint64_t bytes);

}  // namespace citymesh
