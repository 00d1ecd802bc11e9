// libFuzzer target for the Kongsberg .all reader: any bytes must end in datagrams or an AllError,
// never a crash, a hang, a leak or a sanitizer report. Built and run by scripts/fuzz-sonar.sh all.
// Each intact frame's checksum is set right before reading: a mutated body would otherwise stop
// at the checksum and the decoders behind it would never be reached.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/io/kongsberg/all_datagrams.h"

namespace {

void fix_checksums(std::string& b) {
  std::size_t o = 0;
  while (o + 4 <= b.size()) {
    std::uint32_t n = 0;
    for (int i = 3; i >= 0; --i) n = (n << 8) | static_cast<unsigned char>(b[o + i]);
    if (n < 19 || n > b.size() - o - 4) return;
    std::uint16_t sum = 0;
    for (std::size_t i = o + 5; i < o + 4 + n - 3; ++i) sum = static_cast<std::uint16_t>(sum + static_cast<unsigned char>(b[i]));
    b[o + 4 + n - 2] = static_cast<char>(sum & 0xff);
    b[o + 4 + n - 1] = static_cast<char>(sum >> 8);
    o += 4 + n;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  fix_checksums(bytes);
  bathyslam::MemorySource source(bytes);
  bathyslam::kongsberg::Reader reader(source, "fuzz.all");
  try {
    std::size_t valid = 0;
    while (const auto datagram = reader.next()) {
      // Touch the decoded values so that the sanitizers see every one the reader produced.
      if (const auto* ping = std::get_if<bathyslam::kongsberg::DepthPing>(&*datagram)) {
        for (const auto& b : ping->beams) valid += b.valid() ? 1 : 0;
      }
    }
    return static_cast<int>(valid & 0);
  } catch (const bathyslam::kongsberg::AllError&) {
    return 0;  // damage, reported with file, offset and field: what the reader must do
  }
}
