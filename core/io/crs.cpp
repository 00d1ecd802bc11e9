#include "core/io/crs.h"

#include <charconv>
#include <memory>

#include <proj.h>

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
    return "'" + std::string(crs) + "' is not of the form EPSG:<code>";
  }
  ProjContext context;
  PjPtr pj(proj_create(context.ctx, std::string(crs).c_str()));
  if (!pj) return "'" + std::string(crs) + "' is not a CRS that PROJ knows";
  if (proj_get_type(pj.get()) != PJ_TYPE_PROJECTED_CRS) {
    return "'" + std::string(crs) + "' (" + proj_get_name(pj.get()) +
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

}  // namespace bathyslam
