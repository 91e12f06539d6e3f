// SPDX-License-Identifier: MIT
#include "work_schedule.h"

#include <fmt/format.h>

#include <algorithm>
#include <exception>
#include <stdexcept>

#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"

namespace citymesh::app {

WorkSchedule::WorkSchedule(std::vector<std::uint64_t> costs, const std::vector<std::vector<std::size_t>>& after,
                           const std::vector<std::uint8_t>& done)
    : costs_(std::move(costs)), dependents_(costs_.size()), waiting_(costs_.size(), 0) {
  if (after.size() != costs_.size() || done.size() != costs_.size()) {
    throw std::invalid_argument("WorkSchedule: costs, after and done differ in size");
  }
  for (std::size_t k = 0; k < costs_.size(); ++k) {
    if (done[k] != 0) {
      ++done_;
      continue;
    }
    for (const std::size_t d : after[k]) {
      if (d >= costs_.size() || d == k)
        throw std::invalid_argument(fmt::format("WorkSchedule: item {} waits for {}", k, d));
      if (done[d] != 0) continue;
      dependents_[d].push_back(k);
      ++waiting_[k];
    }
  }
  for (std::size_t k = 0; k < costs_.size(); ++k) {
    if (done[k] == 0 && waiting_[k] == 0) make_ready(k);
  }
}

std::optional<std::size_t> WorkSchedule::take() {
  if (ready_.empty()) return std::nullopt;
  const std::size_t item = ready_.begin()->second;
  ready_.erase(ready_.begin());
  ++in_flight_;
  return item;
}

void WorkSchedule::finish(std::size_t item) {
  --in_flight_;
  ++done_;
  for (const std::size_t d : dependents_[item]) {
    if (--waiting_[d] == 0) make_ready(d);
  }
}

LocalChannel::LocalChannel(WorkSchedule& schedule, std::function<void(std::size_t)> on_finish)
    : schedule_(schedule), on_finish_(std::move(on_finish)) {}

void LocalChannel::finish_locked(std::size_t item) {
  schedule_.finish(item);
  if (on_finish_) on_finish_(item);
}

WorkReply LocalChannel::step(std::optional<std::size_t> finished) {
  if (aborted_) throw ProcessingError("stopped: another worker failed");
  if (finished) {
    finish_locked(*finished);
    changed_.notify_all();
  }
  if (const std::optional<std::size_t> item = schedule_.take()) return {WorkReply::Kind::item, *item};
  if (schedule_.finished()) return {WorkReply::Kind::done, 0};
  // Nothing ready and nothing in flight that could make something ready: a cycle (a bug).
  if (schedule_.in_flight() == 0) throw ProcessingError("work schedule: items wait for each other in a cycle");
  return {WorkReply::Kind::wait, 0};
}

std::optional<std::size_t> LocalChannel::next(std::optional<std::size_t> finished) {
  std::unique_lock lock(mutex_);
  for (;;) {
    const WorkReply reply = step(finished);
    finished.reset();
    if (reply.kind == WorkReply::Kind::item) return reply.item;
    if (reply.kind == WorkReply::Kind::done) return std::nullopt;
    changed_.wait(lock);
  }
}

WorkReply LocalChannel::poll(std::optional<std::size_t> finished) {
  const std::lock_guard lock(mutex_);
  return step(finished);
}

void LocalChannel::abort() {
  {
    const std::lock_guard lock(mutex_);
    aborted_ = true;
  }
  changed_.notify_all();
}

void LocalChannel::start_loops(unsigned loops) {
  const std::lock_guard lock(mutex_);
  loops_ = loops;
}

LocalChannel::LoopTake LocalChannel::take_for_loop(unsigned max_loops) {
  const std::lock_guard lock(mutex_);
  if (aborted_) throw ProcessingError("stopped: another worker failed");
  LoopTake take;
  take.item = schedule_.take();
  if (take.item) {
    const unsigned room = max_loops > loops_ ? max_loops - loops_ : 0;
    take.more = static_cast<unsigned>(std::min<std::size_t>(schedule_.ready(), room));
    loops_ += take.more;
    return take;
  }
  --loops_;
  if (!schedule_.finished() && schedule_.in_flight() == 0) {
    throw ProcessingError("work schedule: items wait for each other in a cycle");
  }
  return take;
}

void LocalChannel::finish_for_loop(std::size_t item) {
  {
    const std::lock_guard lock(mutex_);
    finish_locked(item);
  }
  changed_.notify_all();
}

namespace {

/// Calls `work`; when it throws, stops every worker on `channel` first (the others must not
/// wait for an item that will never finish) and passes the exception on.
template <class Work>
auto aborting_on_failure(WorkChannel& channel, Work&& work) {
  try {
    return work();
  } catch (...) {
    channel.abort();
    throw;
  }
}

/// run_workers on this process's own schedule: loops that end when nothing is ready, started
/// again as items become ready, so that a thread with nothing to do helps the tiles in flight.
void run_loops(LocalChannel& channel, unsigned workers, const std::function<void(std::size_t)>& body) {
  channel.start_loops(workers);
  parallel_loops(workers, [&](const LoopSpawner& spawner) -> LoopWork {
    const LocalChannel::LoopTake take = aborting_on_failure(channel, [&] { return channel.take_for_loop(workers); });
    if (take.more > 0) spawner.spawn(take.more);
    if (!take.item) return {};
    return [&channel, &body, item = *take.item] {
      aborting_on_failure(channel, [&] { body(item); });
      channel.finish_for_loop(item);
    };
  });
}

}  // namespace

void run_workers(WorkChannel& channel, unsigned workers, const std::function<void(std::size_t)>& body) {
  if (auto* local = dynamic_cast<LocalChannel*>(&channel)) {
    run_loops(*local, std::max(workers, 1u), body);
    return;
  }
  parallel_workers(std::max(workers, 1u), [&](unsigned) {
    aborting_on_failure(channel, [&] {
      std::optional<std::size_t> item = channel.next(std::nullopt);
      while (item) {
        body(*item);
        item = channel.next(item);
      }
    });
  });
}

std::size_t batch_within(std::span<const std::uint64_t> bytes, std::size_t first, std::size_t most,
                         std::uint64_t room) {
  if (first >= bytes.size() || most == 0) return 0;
  std::uint64_t sum = bytes[first];
  std::size_t count = 1;
  while (count < most && first + count < bytes.size() && sum + bytes[first + count] <= room)
    sum += bytes[first + count++];
  return count;
}

}  // namespace citymesh::app
