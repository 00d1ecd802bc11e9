#include "core/fuse/map_resolution.h"

#include <algorithm>

namespace bathyslam {

double auto_map_resolution(const SweptArea& swept, int min_soundings, double finest_m) {
  const double density = swept.density_per_m2();
  if (!(density > 0)) return finest_m;
  const double cell_area = 2.0 * std::max(min_soundings, 1) / density;
  double resolution = finest_m;
  while (resolution * resolution < cell_area && resolution < 1e4) resolution *= 2;
  return resolution;
}

double auto_map_resolution(const Survey& survey, int min_soundings, double finest_m) {
  return auto_map_resolution(swept_area(survey), min_soundings, finest_m);
}

}  // namespace bathyslam
