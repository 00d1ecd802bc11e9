#pragma once
// Corrected navigation put back into a GSF file the way MB-System's navigation adjustment does:
// every record copied as it is, only each ping header's position and heading replaced, so the
// file keeps everything it held (all beams and flags, attitude, sound velocity, amplitudes,
// sensor-specific data) and opens in any GSF tool.
#include <cstdint>
#include <filesystem>
#include <string_view>
#include <vector>

#include "core/types/survey.h"

namespace bathyslam::gsf {

struct RewriteCount {
  std::uint64_t records = 0;
  std::uint64_t pings = 0;
  std::uint64_t rewritten = 0;  // pings inside `nav`'s time span; the others are copied unchanged
};

// Copies `input` to `output` with `nav` (projected in `crs`) interpolated at each ping: latitude,
// longitude and heading replaced. Depths are left as they are (GSF depths are referenced to the
// surface, and SLAM's vertical correction is centimetres), as are roll and pitch. Throws GsfError
// for a damaged input, std::runtime_error for an unusable CRS or output.
RewriteCount rewrite_navigation(const std::filesystem::path& input, const std::filesystem::path& output,
                                const std::vector<NavSample>& nav, std::string_view crs);

}  // namespace bathyslam::gsf
