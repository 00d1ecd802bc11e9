// libFuzzer target for the GSF reader: any bytes must end in records or a GsfError, never a
// crash, a hang, a leak or a sanitizer report. Built and run by scripts/fuzz-sonar.sh gsf.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/io/gsf/gsf_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  bathyslam::MemorySource source(std::string_view(reinterpret_cast<const char*>(data), size));
  bathyslam::gsf::Reader reader(source, "fuzz.gsf");
  try {
    std::size_t beams = 0;
    while (const auto record = reader.next()) {
      // Touch the decoded arrays so that the sanitizers see every value the reader produced.
      if (const auto* ping = std::get_if<bathyslam::gsf::Ping>(&*record)) {
        for (std::size_t b = 0; b < ping->depth_m.size(); ++b) beams += ping->beam_rejected(b) ? 0 : 1;
      }
    }
    return static_cast<int>(beams & 0);
  } catch (const bathyslam::gsf::GsfError&) {
    return 0;  // damage, reported with record and offset: what the reader must do
  }
}
