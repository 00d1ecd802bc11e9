#pragma once
// Checks that a survey's CRS is one the map can be built in.
#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace bathyslam {

// Returns why `crs` is unusable, or nothing when it is an "EPSG:<code>" that PROJ knows as a
// projected CRS (the map frame is metric east/north).
std::optional<std::string> crs_problem(std::string_view crs);

// The CRS's WKT2 description as PROJ gives it; empty when PROJ does not know it.
std::string crs_wkt(std::string_view crs);

// The WGS 84 UTM zone holding a longitude/latitude, as "EPSG:326zz" (north) or "EPSG:327zz"
// (south): the CRS a survey recorded in geographic coordinates is mapped in by default.
std::string utm_crs_of(double longitude_deg, double latitude_deg);

// Converts WGS 84 longitude/latitude to easting/northing of a projected CRS and back, through
// one PROJ transformation created once (creating it is far slower than using it). Not
// thread-safe: one per thread.
class GeographicProjection {
 public:
  // Throws std::runtime_error when PROJ cannot transform between WGS 84 and `crs`.
  explicit GeographicProjection(std::string_view crs);
  ~GeographicProjection();
  GeographicProjection(const GeographicProjection&) = delete;
  GeographicProjection& operator=(const GeographicProjection&) = delete;

  struct EastNorth {
    double easting = 0, northing = 0;
  };
  struct LonLat {
    double longitude_deg = 0, latitude_deg = 0;
  };
  EastNorth forward(double longitude_deg, double latitude_deg) const;
  LonLat inverse(double easting, double northing) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string crs_;
};

}  // namespace bathyslam
