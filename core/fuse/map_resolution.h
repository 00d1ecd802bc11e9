#pragma once
// The map's cell size when the user gives none. A fixed 0.5 m suits a survey vehicle 10 m above
// the seabed (tens of soundings per square metre) but leaves every cell of a ship's deep-water
// survey empty (EX1811: 1.2–2.3 km down, 432 beams a ping every 6 s: no 0.5 m cell gets the 3
// soundings a cell needs, and there is no map at all). The cell follows the
// soundings instead: the finest of finest_m · 2^k at which an average cell of the swept area
// holds twice `min_soundings` (twice: soundings thin out towards the swath's edges).
#include "core/submaps/sounding_footprint.h"

namespace bathyslam {

double auto_map_resolution(const SweptArea& swept, int min_soundings, double finest_m = 0.5);
double auto_map_resolution(const Survey& survey, int min_soundings, double finest_m = 0.5);

}  // namespace bathyslam
