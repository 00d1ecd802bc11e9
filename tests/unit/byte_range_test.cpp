// What the HTTP endpoint answers to a Range header (server/http/byte_range.h).
#include "server/http/byte_range.h"

#include <gtest/gtest.h>

namespace bathyslam::server::http {
namespace {

void expect(std::string_view header, std::int64_t size, RangeAnswer::Kind kind, std::int64_t offset, std::int64_t length) {
  const RangeAnswer a = answer_range(header, size);
  EXPECT_EQ(a.kind, kind) << header;
  EXPECT_EQ(a.offset, offset) << header;
  EXPECT_EQ(a.length, length) << header;
}

TEST(ByteRange, OneRangeIsServedClampedToTheFile) {
  expect("bytes=0-99", 1000, RangeAnswer::kPartial, 0, 100);
  expect("bytes=990-2000", 1000, RangeAnswer::kPartial, 990, 10);
  expect("bytes=10-", 1000, RangeAnswer::kPartial, 10, 990);
  expect("bytes=-1", 1000, RangeAnswer::kPartial, 999, 1);
  expect("bytes=-5000", 1000, RangeAnswer::kPartial, 0, 1000);
  expect("bytes= 5-6 ", 1000, RangeAnswer::kPartial, 5, 2);
}

TEST(ByteRange, ARangeBeyondTheEndIsRefused) {
  expect("bytes=1000-", 1000, RangeAnswer::kUnsatisfiable, 0, 0);
  expect("bytes=1000-1001", 1000, RangeAnswer::kUnsatisfiable, 0, 0);
  expect("bytes=-0", 1000, RangeAnswer::kUnsatisfiable, 0, 0);
  expect("bytes=0-0", 0, RangeAnswer::kUnsatisfiable, 0, 0);
}

TEST(ByteRange, AnythingElseGetsTheWholeFile) {
  expect("", 1000, RangeAnswer::kWhole, 0, 1000);
  expect("bytes=0-9,5-20", 1000, RangeAnswer::kWhole, 0, 1000);  // several: whole, as the RFC allows
  expect("bytes=9-5", 1000, RangeAnswer::kWhole, 0, 1000);       // not the RFC's syntax: ignored
  expect("bytes=abc", 1000, RangeAnswer::kWhole, 0, 1000);
  expect("bytes=-", 1000, RangeAnswer::kWhole, 0, 1000);
  expect("items=0-9", 1000, RangeAnswer::kWhole, 0, 1000);
  expect("bytes=99999999999999999999-", 1000, RangeAnswer::kWhole, 0, 1000);
}

}  // namespace
}  // namespace bathyslam::server::http
