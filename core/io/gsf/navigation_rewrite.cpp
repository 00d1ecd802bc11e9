#include "core/io/gsf/navigation_rewrite.h"

#include <cmath>

#include "core/io/byte_source.h"
#include "core/io/crs.h"
#include "core/io/gsf/big_endian.h"
#include "core/io/gsf/gsf_reader.h"
#include "core/io/gsf/gsf_writer.h"
#include "core/sync/nav_interpolation.h"

namespace bathyslam::gsf {
namespace {

// Byte offsets in a ping record's data (Table 4-3): time 0, longitude 8, latitude 12, ..., heading 30.
constexpr std::size_t kLongitudeAt = 8;
constexpr std::size_t kLatitudeAt = 12;
constexpr std::size_t kHeadingAt = 30;

}  // namespace

RewriteCount rewrite_navigation(const std::filesystem::path& input, const std::filesystem::path& output,
                                const std::vector<NavSample>& nav, std::string_view crs) {
  const GeographicProjection projection(crs);
  FileSource source(input);
  Reader reader(source, input.string());
  RewriteCount count;
  if (!reader.next()) return count;  // an empty file throws; a header is always first
  Writer writer(output, reader.header().version);
  count.records = 1;
  while (const auto record = reader.next()) {
    ++count.records;
    std::vector<std::uint8_t> data = reader.record_data();
    if (const auto* ping = std::get_if<Ping>(&*record)) {
      ++count.pings;
      if (const auto at = interpolate_nav(nav, ping->time)) {
        const auto ll = projection.inverse(at->easting, at->northing);
        patch_u32(data, kLongitudeAt, static_cast<std::uint32_t>(static_cast<std::int32_t>(std::lround(ll.longitude_deg * 1e7))));
        patch_u32(data, kLatitudeAt, static_cast<std::uint32_t>(static_cast<std::int32_t>(std::lround(ll.latitude_deg * 1e7))));
        patch_u16(data, kHeadingAt, heading_field(at->heading_deg));
        ++count.rewritten;
      }
    }
    writer.write_raw(reader.record_id(), std::move(data));
  }
  writer.close();
  return count;
}

}  // namespace bathyslam::gsf
