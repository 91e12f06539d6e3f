// SPDX-License-Identifier: MIT
#include "citymesh/core/progress.h"

#include <fmt/format.h>

#include <algorithm>
#include <utility>

#include "citymesh/core/log.h"
#include "citymesh/core/process_memory.h"

namespace citymesh {

StageProgress::StageProgress(StageProgressParams params) : params_(std::move(params)) {
  if (!params_.say) params_.say = [](const std::string& line) { log::info("{}", line); };
}

void StageProgress::advance(std::uint64_t n, std::uint64_t work) {
  const std::lock_guard lock(mutex_);
  done_ = std::min(params_.total, done_ + n);
  done_work_ = std::min(params_.total_work, done_work_ + work);
  const bool last = done_ == params_.total;
  if (last ? !last_said_ : since_line_.seconds() >= params_.interval) say_line();
}

void StageProgress::finish() {
  const std::lock_guard lock(mutex_);
  done_ = params_.total;
  done_work_ = params_.total_work;
  if (!last_said_) say_line();
}

std::uint64_t StageProgress::done() const {
  const std::lock_guard lock(mutex_);
  return done_;
}

std::uint64_t StageProgress::done_work() const {
  const std::lock_guard lock(mutex_);
  return done_work_;
}

void StageProgress::say_line() {
  since_line_.restart();
  last_said_ = done_ == params_.total;
  const double elapsed = clock_.seconds();
  const bool by_work = params_.total_work > 0 && done_work_ > 0 && done_ < params_.total;
  const std::uint64_t done = by_work ? done_work_ : done_;
  const std::uint64_t total = by_work ? params_.total_work : params_.total;
  const double eta = done > 0 ? elapsed / static_cast<double>(done) * static_cast<double>(total - done) : 0.0;
  params_.say(fmt::format("{} {}/{}, ETA {:.0f} s, memory {:.0f} MiB", params_.stage, done_, params_.total, eta,
                          static_cast<double>(resident_bytes()) / (1 << 20)));
}

}  // namespace citymesh
