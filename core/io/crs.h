#pragma once
// Checks that a survey's CRS is one the map can be built in.
#include <optional>
#include <string>
#include <string_view>

namespace bathyslam {

// Returns why `crs` is unusable, or nothing when it is an "EPSG:<code>" that PROJ knows as a
// projected CRS (the map frame is metric east/north).
std::optional<std::string> crs_problem(std::string_view crs);

// The CRS's WKT2 description as PROJ gives it; empty when PROJ does not know it.
std::string crs_wkt(std::string_view crs);

}  // namespace bathyslam
