#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "core/pipeline/ping_handoff.h"

namespace bathyslam {
namespace {

struct SeenPing {
  double time;
  std::vector<Beam> beams;
};

// Keeps what it is handed; throws on the ping at `fail_at` if given.
class RecordingSink : public PingSink {
 public:
  explicit RecordingSink(int fail_at = -1) : fail_at_(fail_at) {}
  void begin(const Survey& survey) override {
    began_before_pings = pings.empty();
    nav_samples = survey.nav.size();
  }
  void ping(double time, std::span<const Beam> beams) override {
    if (!failed_ && static_cast<int>(pings.size()) == fail_at_) {
      failed_ = true;  // once: a ping handed on after the failure would be kept, and counted
      throw std::runtime_error("sink failed at ping " + std::to_string(fail_at_));
    }
    pings.push_back({time, std::vector<Beam>(beams.begin(), beams.end())});
  }
  bool began_before_pings = false;
  std::size_t nav_samples = 0;
  std::vector<SeenPing> pings;

 private:
  int fail_at_;
  bool failed_ = false;
};

std::vector<Beam> beams_of_ping(int p) {
  std::vector<Beam> beams;
  for (int b = 0; b < 1 + p % 7; ++b) beams.push_back({static_cast<uint32_t>(b), 0.5f * p, 0.25f * b, 10.0f + p + b});
  return beams;
}

TEST(PingHandoff, HandsOnEveryPingInOrderWithItsBeams) {
  RecordingSink sink;
  Survey survey;
  survey.nav.resize(3);
  {
    // Blocks of ~5 beams, two queued: many blocks, and the reader waits on the sink.
    PingHandoff handoff(sink, 5, 2);
    handoff.begin(survey);
    for (int p = 0; p < 500; ++p) {
      const std::vector<Beam> beams = beams_of_ping(p);
      handoff.ping(0.1 * p, beams);
    }
    handoff.ping(60.0, {});  // a ping without beams is handed on too
    handoff.finish();
    ASSERT_EQ(sink.pings.size(), 501u);  // all of them by the time finish returns
  }
  EXPECT_TRUE(sink.began_before_pings);
  EXPECT_EQ(sink.nav_samples, 3u);
  for (int p = 0; p < 500; ++p) {
    ASSERT_EQ(sink.pings[p].time, 0.1 * p);
    const std::vector<Beam> expected = beams_of_ping(p);
    ASSERT_EQ(sink.pings[p].beams.size(), expected.size()) << "ping " << p;
    for (std::size_t b = 0; b < expected.size(); ++b) {
      EXPECT_EQ(sink.pings[p].beams[b].index, expected[b].index);
      EXPECT_EQ(sink.pings[p].beams[b].down, expected[b].down);
    }
  }
  EXPECT_TRUE(sink.pings[500].beams.empty());
}

TEST(PingHandoff, TheSinksFailureReachesTheReaderAndNothingAfterItReachesTheSink) {
  RecordingSink sink(/*fail_at=*/40);
  PingHandoff handoff(sink, 3, 1);
  handoff.begin(Survey{});
  bool thrown = false;
  try {
    for (int p = 0; p < 10000; ++p) handoff.ping(p, beams_of_ping(p));
    handoff.finish();
  } catch (const std::runtime_error& e) {
    thrown = true;
    EXPECT_STREQ(e.what(), "sink failed at ping 40");
  }
  EXPECT_TRUE(thrown);
  EXPECT_EQ(sink.pings.size(), 40u);
}

TEST(PingHandoff, AReaderThatStopsEarlyLeavesWithoutWaitingForTheRest) {
  RecordingSink sink;
  {
    PingHandoff handoff(sink, 4, 8);
    handoff.begin(Survey{});
    for (int p = 0; p < 100; ++p) handoff.ping(p, beams_of_ping(p));
    // No finish: the reader threw. The destructor stops the sink's thread and returns.
  }
  EXPECT_LE(sink.pings.size(), 100u);
  for (std::size_t p = 0; p < sink.pings.size(); ++p) EXPECT_EQ(sink.pings[p].time, static_cast<double>(p));
}

}  // namespace
}  // namespace bathyslam
