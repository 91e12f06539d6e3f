// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include "citymesh/core/error.h"
#include "citymesh/core/time.h"

namespace citymesh {
namespace {

using std::chrono::days;
using std::chrono::hours;
using std::chrono::milliseconds;

TEST(Iso8601, ParsesDatesAndZonesToTheSameInstant) {
  const TimePoint utc = parse_iso8601("2026-01-05T10:00:00Z", "t");
  EXPECT_EQ(parse_iso8601("2026-01-05T12:00:00+02:00", "t"), utc);
  EXPECT_EQ(parse_iso8601("2026-01-05T07:30:00-02:30", "t"), utc);
  EXPECT_EQ(parse_iso8601("2026-01-05T10:00Z", "t"), utc);
  EXPECT_EQ(parse_iso8601("2026-01-05", "t") + hours(10), utc);
  // 2026-01-05 is day 20458 of the Unix epoch (1970-01-01 + 20458 days).
  EXPECT_EQ(parse_iso8601("2026-01-05", "t").time_since_epoch(), days(20458));
}

TEST(Iso8601, FractionalSecondsAndLeapDay) {
  const TimePoint t = parse_iso8601("2024-02-29T23:59:59.250Z", "t");
  EXPECT_EQ(format_iso8601(t), "2024-02-29T23:59:59.250Z");
  EXPECT_EQ(parse_iso8601("2024-03-01T00:00:00Z", "t") - t, milliseconds(750));
}

TEST(Iso8601, FormatRoundTrips) {
  for (const char* s : {"1970-01-01T00:00:00Z", "2026-11-21T11:23:41Z", "2099-12-31T23:59:59Z"}) {
    EXPECT_EQ(format_iso8601(parse_iso8601(s, "t")), s);
  }
}

TEST(Iso8601, RefusesAmbiguousOrMalformedText) {
  for (const char* s : {"2026-01-05T10:00:00", "2026-02-30", "2026-1-5", "05/01/2026", "2026-01-05T25:00:00Z",
                        "2026-01-05T10:00:00Zjunk", "", "2026-01-05T10:00:00+2"}) {
    EXPECT_THROW(parse_iso8601(s, "t"), ConfigError) << s;
  }
}

TEST(Duration, ParsesUnitsAndFormatsShortest) {
  EXPECT_EQ(parse_duration("30d", "d"), days(30));
  EXPECT_EQ(parse_duration("12h", "d"), hours(12));
  EXPECT_EQ(parse_duration("1.5h", "d"), std::chrono::minutes(90));
  EXPECT_EQ(parse_duration("2w", "d"), days(14));
  EXPECT_EQ(format_duration(days(30)), "30d");
  EXPECT_EQ(format_duration(std::chrono::minutes(90)), "90min");
  EXPECT_EQ(format_duration(days(14)), "2w");
  for (const char* s : {"30", "30 days", "-1d", "d", "1y"}) EXPECT_THROW(parse_duration(s, "d"), ConfigError) << s;
}

TEST(ByteSize, ParsesBinaryAndDecimalUnits) {
  EXPECT_EQ(parse_byte_size("2GiB", "m"), 2ull << 30);
  EXPECT_EQ(parse_byte_size("512MiB", "m"), 512ull << 20);
  EXPECT_EQ(parse_byte_size("4GB", "m"), 4'000'000'000ull);
  EXPECT_EQ(parse_byte_size("100", "m"), 100u);
  EXPECT_EQ(format_byte_size(2ull << 30), "2GiB");
  EXPECT_EQ(format_byte_size(1536ull << 20), "1536MiB");
  EXPECT_EQ(format_byte_size(1000), "1000B");
  for (const char* s : {"2 gigs", "GiB", "-5MiB", "1e30B"}) EXPECT_THROW(parse_byte_size(s, "m"), ConfigError) << s;
}

}  // namespace
}  // namespace citymesh
