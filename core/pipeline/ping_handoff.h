#pragma once
// A reader parses pings on one core while another makes submaps of the ones before: the sink is
// fed on a thread of its own, in blocks of pings. On `lake` the reading (pings.csv's text) and
// the submaps' making (georeferencing, gridding) each took about half of the serial "submaps"
// stage (docs/slam-every-seabed.md, "Speed: the serial parts around the registrations"). The
// sink sees the same pings in the same order as it would unpiped, so what it makes is the same
// to the bit.
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

#include "core/io/bundle.h"

namespace bathyslam {

class PingHandoff : public PingSink {
 public:
  // At most `queued_blocks` (at least 1) full blocks of about `block_beams` beams, or as many
  // pings, wait for the sink: memory stays bounded whatever the reader's pace, empty pings too.
  explicit PingHandoff(PingSink& sink, std::size_t block_beams = 1 << 16, std::size_t queued_blocks = 4);
  // Stops the sink's thread; pings not yet handed on are dropped (an exception is on its way).
  ~PingHandoff() override;
  PingHandoff(const PingHandoff&) = delete;
  PingHandoff& operator=(const PingHandoff&) = delete;

  // Handed on once every earlier ping has been (begin is called before any ping).
  void begin(const Survey& survey) override;
  // Copies the ping; throws what the sink threw on an earlier one, so the reading stops there.
  void ping(double time, std::span<const Beam> beams) override;
  // Returns once the sink has seen every ping; throws what it threw. Call after the last ping.
  void finish();

 private:
  struct Block {
    struct PingAt {
      double time;
      std::size_t first_beam, beam_count;
    };
    std::vector<PingAt> pings;
    std::vector<Beam> beams;
  };
  void hand_on();  // the sink's thread
  void send(Block block);
  void wait_until_handed_on();
  void rethrow_if_failed();

  PingSink& sink_;
  std::size_t block_beams_, queued_blocks_;
  Block filling_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Block> queued_;
  bool busy_ = false;      // the sink's thread holds a block
  bool stopping_ = false;
  std::exception_ptr failure_;
  std::thread thread_;
};

}  // namespace bathyslam
