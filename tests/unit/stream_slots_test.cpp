// Issue 37 fault 1: one tenant's open WatchJob streams are bounded, others' are not touched.
#include "server/services/stream_slots.h"

#include <gtest/gtest.h>

#include <vector>

namespace bathyslam::server {
namespace {

TEST(StreamSlots, ATenantHoldsAtMostItsLimitAndAnotherIsNotTouched) {
  StreamSlots slots(3);
  std::vector<StreamSlots::Slot> open;
  for (int i = 0; i < 3; ++i) {
    auto slot = slots.take(1);
    ASSERT_TRUE(slot) << "stream " << i;
    open.push_back(std::move(*slot));
  }
  EXPECT_FALSE(slots.take(1)) << "a fourth stream of tenant 1";
  EXPECT_TRUE(slots.take(2)) << "tenant 2 is not held back by tenant 1's streams";
}

TEST(StreamSlots, AClosedStreamGivesItsSlotBack) {
  StreamSlots slots(1);
  {
    const auto slot = slots.take(7);
    ASSERT_TRUE(slot);
    EXPECT_FALSE(slots.take(7));
  }
  EXPECT_TRUE(slots.take(7));
}

TEST(StreamSlots, ALimitBelowOneIsRefused) { EXPECT_THROW(StreamSlots(0), std::invalid_argument); }

}  // namespace
}  // namespace bathyslam::server
