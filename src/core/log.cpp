// SPDX-License-Identifier: MIT
// The only source that includes spdlog: a stderr logger, plain or JSON lines.
#include "citymesh/core/log.h"

#include <spdlog/sinks/base_sink.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <array>
#include <cstdio>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>

#include "citymesh/core/error.h"

namespace citymesh::log {

namespace {

/// One JSON object per line; the message is escaped properly (a pattern string would not).
class JsonStderrSink final : public spdlog::sinks::base_sink<std::mutex> {
 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    const auto since_epoch = msg.time.time_since_epoch();
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(since_epoch).count();
    nlohmann::json line{{"time_ms", ms},
                        {"level", spdlog::level::to_string_view(msg.level).data()},
                        {"msg", std::string(msg.payload.data(), msg.payload.size())}};
    const std::string text = line.dump() + "\n";
    std::fwrite(text.data(), 1, text.size(), stderr);
  }
  void flush_() override { std::fflush(stderr); }
};

spdlog::level::level_enum to_spdlog(Level level) {
  switch (level) {
    case Level::trace: return spdlog::level::trace;
    case Level::debug: return spdlog::level::debug;
    case Level::info: return spdlog::level::info;
    case Level::warn: return spdlog::level::warn;
    case Level::error: return spdlog::level::err;
    case Level::off: return spdlog::level::off;
  }
  return spdlog::level::info;
}

std::shared_ptr<spdlog::logger>& logger() {
  static std::shared_ptr<spdlog::logger> instance = [] {
    auto l = std::make_shared<spdlog::logger>("citymesh", std::make_shared<spdlog::sinks::stderr_sink_mt>());
    l->set_pattern("%^%l%$: %v");
    l->set_level(spdlog::level::info);
    return l;
  }();
  return instance;
}

}  // namespace

Level parse_level(std::string_view name) {
  constexpr std::array<std::pair<std::string_view, Level>, 6> names{
      {{"trace", Level::trace}, {"debug", Level::debug}, {"info", Level::info},
       {"warn", Level::warn}, {"error", Level::error}, {"off", Level::off}}};
  for (const auto& [n, l] : names) {
    if (n == name) return l;
  }
  throw UsageError(fmt::format("--log-level: unknown level '{}' (trace, debug, info, warn, error, off)", name));
}

void configure(Level level, Format format) {
  spdlog::sink_ptr sink;
  if (format == Format::json) {
    sink = std::make_shared<JsonStderrSink>();
  } else {
    sink = std::make_shared<spdlog::sinks::stderr_sink_mt>();
  }
  auto l = std::make_shared<spdlog::logger>("citymesh", sink);
  if (format == Format::text) l->set_pattern("%^%l%$: %v");
  l->set_level(to_spdlog(level));
  l->flush_on(spdlog::level::trace);
  logger() = std::move(l);
}

void write(Level level, std::string_view message) { logger()->log(to_spdlog(level), message); }

bool enabled(Level level) { return logger()->should_log(to_spdlog(level)); }

}  // namespace citymesh::log
