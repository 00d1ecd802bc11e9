// libFuzzer target for the bundle reader's parsers: the first byte picks nav.csv, pings.csv or
// survey.json, the rest is the file. Every input must end in problems or a value, never a crash,
// a hang or a sanitizer report (scripts/fuzz-bundle.sh builds it with clang and runs it for a bounded time).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/io/bundle.h"
#include "core/io/csv.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace bathyslam;
  if (size == 0) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  ProblemList problems;
  MemorySource source(text);
  try {
    switch (data[0] % 3) {
      case 0: parse_nav_csv(source, kNavFile, problems); break;
      case 1: {
        std::vector<Ping> pings;
        std::vector<Beam> beams;
        parse_pings_csv(source, kPingsFile, TimeSpan{0, 1e10}, problems, pings, beams);
        break;
      }
      case 2: parse_survey_json(text, kSurveyJsonFile, problems); break;
    }
  } catch (const LineTooLong&) {
    // read_bundle turns this into a problem at the line
  }
  problems.take();
  return 0;
}
