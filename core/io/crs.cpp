#include "core/io/crs.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <memory>

#include <proj.h>

#include "core/io/problem.h"

namespace bathyslam {
namespace {

// PROJ contexts are not thread-safe; each call gets its own.
struct ProjContext {
  PJ_CONTEXT* ctx = proj_context_create();
  ProjContext() { proj_log_level(ctx, PJ_LOG_NONE); }
  ~ProjContext() { proj_context_destroy(ctx); }
};

struct PjDeleter {
  void operator()(PJ* pj) const { proj_destroy(pj); }
};
using PjPtr = std::unique_ptr<PJ, PjDeleter>;

bool is_epsg_code(std::string_view crs) {
  constexpr std::string_view kPrefix = "EPSG:";
  if (crs.substr(0, kPrefix.size()) != kPrefix) return false;
  const std::string_view digits = crs.substr(kPrefix.size());
  unsigned code = 0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), code);
  return !digits.empty() && ec == std::errc() && end == digits.data() + digits.size();
}

}  // namespace

std::optional<std::string> crs_problem(std::string_view crs) {
  if (!is_epsg_code(crs)) {
    return quoted_input(crs) + " is not of the form EPSG:<code>";
  }
  ProjContext context;
  PjPtr pj(proj_create(context.ctx, std::string(crs).c_str()));
  if (!pj) return quoted_input(crs) + " is not a CRS that PROJ knows";
  if (proj_get_type(pj.get()) != PJ_TYPE_PROJECTED_CRS) {
    return quoted_input(crs) + " (" + proj_get_name(pj.get()) +
           ") is not a projected CRS; the map needs metric easting/northing";
  }
  return std::nullopt;
}

std::string crs_wkt(std::string_view crs) {
  ProjContext context;
  PjPtr pj(proj_create(context.ctx, std::string(crs).c_str()));
  if (!pj) return {};
  const char* wkt = proj_as_wkt(context.ctx, pj.get(), PJ_WKT2_2019, nullptr);
  return wkt != nullptr ? wkt : "";
}

std::string utm_crs_of(double longitude_deg, double latitude_deg) {
  // Zones are 6 degrees wide from 180 W; the longitude is wrapped so that 180 E falls in zone 1.
  const double wrapped = std::fmod(std::fmod(longitude_deg + 180.0, 360.0) + 360.0, 360.0);
  const int zone = std::min(60, static_cast<int>(wrapped / 6.0) + 1);
  return "EPSG:" + std::to_string((latitude_deg >= 0 ? 32600 : 32700) + zone);
}

struct GeographicProjection::Impl {
  ProjContext context;
  PjPtr transform;
};

GeographicProjection::GeographicProjection(std::string_view crs) : impl_(std::make_unique<Impl>()), crs_(crs) {
  PjPtr raw(proj_create_crs_to_crs(impl_->context.ctx, "EPSG:4326", crs_.c_str(), nullptr));
  // EPSG:4326 is latitude first; normalising makes both ends x = longitude/easting.
  if (raw) impl_->transform.reset(proj_normalize_for_visualization(impl_->context.ctx, raw.get()));
  if (!impl_->transform) {
    throw std::runtime_error("PROJ cannot transform WGS 84 longitude/latitude to '" + crs_ + "'");
  }
}

GeographicProjection::~GeographicProjection() = default;

GeographicProjection::EastNorth GeographicProjection::forward(double longitude_deg, double latitude_deg) const {
  const PJ_COORD out = proj_trans(impl_->transform.get(), PJ_FWD, proj_coord(longitude_deg, latitude_deg, 0, 0));
  return {out.xy.x, out.xy.y};
}

GeographicProjection::LonLat GeographicProjection::inverse(double easting, double northing) const {
  const PJ_COORD out = proj_trans(impl_->transform.get(), PJ_INV, proj_coord(easting, northing, 0, 0));
  return {out.lp.lam, out.lp.phi};
}

}  // namespace bathyslam
