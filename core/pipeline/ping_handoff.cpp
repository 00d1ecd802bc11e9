#include "core/pipeline/ping_handoff.h"

#include <algorithm>
#include <utility>

namespace bathyslam {

PingHandoff::PingHandoff(PingSink& sink, std::size_t block_beams, std::size_t queued_blocks)
    : sink_(sink),
      block_beams_(std::max<std::size_t>(block_beams, 1)),
      queued_blocks_(std::max<std::size_t>(queued_blocks, 1)),
      thread_([this] { hand_on(); }) {}

PingHandoff::~PingHandoff() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    queued_.clear();
  }
  changed_.notify_all();
  thread_.join();
}

void PingHandoff::begin(const Survey& survey) {
  wait_until_handed_on();
  sink_.begin(survey);
}

void PingHandoff::ping(double time, std::span<const Beam> beams) {
  rethrow_if_failed();
  filling_.pings.push_back({time, filling_.beams.size(), beams.size()});
  filling_.beams.insert(filling_.beams.end(), beams.begin(), beams.end());
  if (filling_.beams.size() >= block_beams_ || filling_.pings.size() >= block_beams_) send(std::exchange(filling_, {}));
}

void PingHandoff::finish() { wait_until_handed_on(); }

void PingHandoff::send(Block block) {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return queued_.size() < queued_blocks_ || failure_; });
  if (failure_) std::rethrow_exception(failure_);
  queued_.push_back(std::move(block));
  changed_.notify_all();
}

void PingHandoff::wait_until_handed_on() {
  if (!filling_.pings.empty()) send(std::exchange(filling_, {}));
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return (queued_.empty() && !busy_) || failure_; });
  if (failure_) std::rethrow_exception(failure_);
}

void PingHandoff::rethrow_if_failed() {
  std::lock_guard lock(mutex_);
  if (failure_) std::rethrow_exception(failure_);
}

void PingHandoff::hand_on() {
  for (;;) {
    Block block;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [&] { return !queued_.empty() || stopping_; });
      if (stopping_) return;
      if (failure_) {  // the reader stops at its next ping; nothing after the failure reaches the sink
        queued_.clear();
        continue;
      }
      block = std::move(queued_.front());
      queued_.pop_front();
      busy_ = true;
    }
    changed_.notify_all();
    try {
      for (const Block::PingAt& p : block.pings) {
        sink_.ping(p.time, std::span<const Beam>(block.beams).subspan(p.first_beam, p.beam_count));
      }
    } catch (...) {
      std::lock_guard lock(mutex_);
      failure_ = std::current_exception();
    }
    {
      std::lock_guard lock(mutex_);
      busy_ = false;
    }
    changed_.notify_all();
  }
}

}  // namespace bathyslam
