// libFuzzer target for the XTF reader: any bytes must end in packets or an XtfError, never a
// crash, a hang, a leak or a sanitizer report. Built and run by scripts/fuzz-sonar.sh xtf.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/io/xtf/xtf_packets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  bathyslam::MemorySource source(bytes);
  try {
    bathyslam::xtf::Reader reader(source, "fuzz.xtf");
    std::size_t valid = 0;
    while (const auto packet = reader.next()) {
      // Touch the decoded values so that the sanitizers see every one the reader produced.
      if (const auto* ping = std::get_if<bathyslam::xtf::BathyPing>(&*packet)) {
        for (const auto& b : ping->beams) valid += b.valid() ? 1 : 0;
        valid += ping->header.position_usable() + ping->header.attitude_usable();
      }
    }
    return static_cast<int>(valid & 0);
  } catch (const bathyslam::xtf::XtfError&) {
    return 0;  // damage, reported with file, offset and field: what the reader must do
  }
}
