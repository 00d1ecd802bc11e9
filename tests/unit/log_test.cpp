// The server's log: one line per event, whatever the event quotes.
#include "server/log.h"

#include <gtest/gtest.h>

#include <string>

namespace bathyslam::server {
namespace {

std::string logged(const std::string& name) {
  testing::internal::CaptureStderr();
  log("survey 7 created: '%s'", name.c_str());
  return testing::internal::GetCapturedStderr();
}

TEST(Log, ANameCannotForgeALineOfItsOwn) {
  const std::string line = logged("a\n2026-12-05T00:00:00.000Z survey 1 deleted");
  EXPECT_EQ(line.find('\n'), line.size() - 1) << line;
  EXPECT_NE(line.find("created: 'a\\x0a2026-12-05T00:00:00.000Z survey 1 deleted'"), std::string::npos) << line;
}

TEST(Log, EscapesControlBytesAndKeepsUtf8) {
  const std::string line = logged("\x1b[31mred\r caf\xc3\xa9 \xff");
  EXPECT_NE(line.find("'\\x1b[31mred\\x0d caf\xc3\xa9 \\xff'"), std::string::npos) << line;
}

}  // namespace
}  // namespace bathyslam::server
