// SPDX-License-Identifier: MIT
// Locale-independent parsing and printing of dates, durations and byte sizes.
#include "citymesh/core/time.h"

#include <fmt/format.h>

#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <optional>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {

using namespace std::chrono;

[[noreturn]] void bad(std::string_view what, std::string_view text, std::string_view expected) {
  throw ConfigError(fmt::format("{}: cannot read '{}' ({})", what, text, expected));
}

/// Reads exactly `digits` decimal digits at `pos`.
std::optional<int> read_digits(std::string_view s, std::size_t pos, std::size_t digits) {
  if (pos + digits > s.size()) return std::nullopt;
  int value = 0;
  for (std::size_t i = pos; i < pos + digits; ++i) {
    if (s[i] < '0' || s[i] > '9') return std::nullopt;
    value = value * 10 + (s[i] - '0');
  }
  return value;
}

struct NumberAndUnit {
  double number = 0;
  std::string_view unit;
};

std::optional<NumberAndUnit> split_number(std::string_view text) {
  double number = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), number);
  if (ec != std::errc() || !std::isfinite(number) || number < 0) return std::nullopt;
  std::string_view unit(end, static_cast<std::size_t>(text.data() + text.size() - end));
  while (!unit.empty() && unit.front() == ' ') unit.remove_prefix(1);
  return NumberAndUnit{number, unit};
}

constexpr const char* kIsoForm = "expected YYYY-MM-DD or YYYY-MM-DDThh:mm:ss with Z or +hh:mm";

/// Parses the clock part "hh:mm[:ss[.fff]]" starting at `pos`; returns ms since midnight and
/// advances `pos`.
std::optional<std::int64_t> parse_clock(std::string_view s, std::size_t& pos) {
  auto hh = read_digits(s, pos, 2);
  auto mm = read_digits(s, pos + 3, 2);
  if (!hh || !mm || s[pos + 2] != ':' || *hh > 23 || *mm > 59) return std::nullopt;
  std::int64_t ms = (*hh * 3600LL + *mm * 60LL) * 1000;
  pos += 5;
  if (pos < s.size() && s[pos] == ':') {
    auto ss = read_digits(s, pos + 1, 2);
    if (!ss || *ss > 60) return std::nullopt;
    ms += *ss * 1000LL;
    pos += 3;
    if (pos < s.size() && s[pos] == '.') {
      ++pos;
      int scale = 100;
      std::size_t start = pos;
      while (pos < s.size() && s[pos] >= '0' && s[pos] <= '9') {
        ms += (s[pos] - '0') * scale;
        scale /= 10;
        ++pos;
      }
      if (pos == start) return std::nullopt;
    }
  }
  return ms;
}

/// Parses "Z", "+hh:mm" or "-hh:mm" at `pos`; returns the offset east of UTC in ms.
std::optional<std::int64_t> parse_zone(std::string_view s, std::size_t pos) {
  if (pos >= s.size()) return std::nullopt;
  if (s[pos] == 'Z' || s[pos] == 'z') return pos + 1 == s.size() ? std::optional<std::int64_t>(0) : std::nullopt;
  if (s[pos] != '+' && s[pos] != '-') return std::nullopt;
  auto hh = read_digits(s, pos + 1, 2);
  auto mm = read_digits(s, pos + 4, 2);
  if (!hh || !mm || s[pos + 3] != ':' || pos + 6 != s.size() || *hh > 23 || *mm > 59) return std::nullopt;
  std::int64_t offset = (*hh * 60LL + *mm) * 60'000LL;
  return s[pos] == '-' ? -offset : offset;
}

}  // namespace

TimePoint parse_iso8601(std::string_view text, std::string_view what) {
  auto y = read_digits(text, 0, 4);
  auto mo = read_digits(text, 5, 2);
  auto d = read_digits(text, 8, 2);
  if (!y || !mo || !d || text[4] != '-' || text[7] != '-') bad(what, text, kIsoForm);
  const year_month_day ymd{year{*y}, month{static_cast<unsigned>(*mo)}, day{static_cast<unsigned>(*d)}};
  if (!ymd.ok()) bad(what, text, "no such calendar date");
  TimePoint day_start = time_point_cast<milliseconds>(sys_days{ymd});
  if (text.size() == 10) return day_start;
  if (text[10] != 'T' && text[10] != 't' && text[10] != ' ') bad(what, text, kIsoForm);
  std::size_t pos = 11;
  auto clock = parse_clock(text, pos);
  if (!clock) bad(what, text, kIsoForm);
  auto zone = parse_zone(text, pos);
  if (!zone) bad(what, text, "a date-time needs a time zone: Z or +hh:mm");
  return day_start + milliseconds(*clock - *zone);
}

std::string format_iso8601(TimePoint t) {
  const auto day_start = floor<days>(t);
  const year_month_day ymd{day_start};
  const auto ms = (t - day_start).count();
  const auto h = ms / 3'600'000, m = ms / 60'000 % 60, s = ms / 1000 % 60, frac = ms % 1000;
  std::string out = fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}", static_cast<int>(ymd.year()),
                                static_cast<unsigned>(ymd.month()), static_cast<unsigned>(ymd.day()),
                                h, m, s);
  if (frac != 0) out += fmt::format(".{:03}", frac);
  return out + "Z";
}

namespace {
struct Unit {
  std::string_view name;
  double factor;
};
constexpr std::array<Unit, 6> kDurationUnits{
    {{"ms", 1}, {"s", 1e3}, {"min", 6e4}, {"h", 3.6e6}, {"d", 8.64e7}, {"w", 6.048e8}}};
constexpr std::array<Unit, 9> kSizeUnits{{{"B", 1},
                                          {"kB", 1e3},
                                          {"MB", 1e6},
                                          {"GB", 1e9},
                                          {"TB", 1e12},
                                          {"KiB", 1024.0},
                                          {"MiB", 1048576.0},
                                          {"GiB", 1073741824.0},
                                          {"TiB", 1099511627776.0}}};

template <std::size_t N>
std::optional<double> scaled(std::string_view text, const std::array<Unit, N>& units,
                             std::string_view default_unit) {
  auto parts = split_number(text);
  if (!parts) return std::nullopt;
  std::string_view unit = parts->unit.empty() ? default_unit : parts->unit;
  for (const Unit& u : units) {
    if (u.name == unit) return parts->number * u.factor;
  }
  return std::nullopt;
}
}  // namespace

Duration parse_duration(std::string_view text, std::string_view what) {
  auto ms = scaled(text, kDurationUnits, "");
  if (!ms || *ms > 1e15) bad(what, text, "expected a duration such as 30d, 12h, 45min, 90s");
  return Duration(static_cast<std::int64_t>(std::llround(*ms)));
}

std::string format_duration(Duration d) {
  const std::int64_t ms = d.count();
  for (auto it = kDurationUnits.rbegin(); it != kDurationUnits.rend(); ++it) {
    const auto f = static_cast<std::int64_t>(it->factor);
    if (ms != 0 && ms % f == 0) return fmt::format("{}{}", ms / f, it->name);
  }
  return fmt::format("{}ms", ms);
}

std::uint64_t parse_byte_size(std::string_view text, std::string_view what) {
  auto bytes = scaled(text, kSizeUnits, "B");
  if (!bytes || *bytes >= 1.8e19) bad(what, text, "expected a size such as 2GiB, 512MiB, 4GB");
  return static_cast<std::uint64_t>(std::llround(*bytes));
}

std::string format_byte_size(std::uint64_t bytes) {
  constexpr std::array<std::string_view, 5> names{"B", "KiB", "MiB", "GiB", "TiB"};
  std::size_t unit = 0;
  while (unit + 1 < names.size() && bytes != 0 && bytes % 1024 == 0) {
    bytes /= 1024;
    ++unit;
  }
  return fmt::format("{}{}", bytes, names[unit]);
}

}  // namespace citymesh
