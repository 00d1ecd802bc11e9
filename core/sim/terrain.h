#pragma once
// Simulated seabed sampled on a fine grid. The default is the paper's lakebed: flat regions and
// undulating regions (mounds, ridges, channels, fine roughness) alternating across the survey
// area. The other kinds each stress one weakness of registration (see TerrainKind).
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace bathyslam::sim {

enum class TerrainKind {
  kLake,        // the paper's lakebed (above)
  kSandWaves,   // periodic crests: registration aliases a wavelength away
  kBoulders,    // flat sand with sparse boulders: few features, each decisive
  kChannel,     // a flat plain cut by meandering channels: all relief in a narrow band
  kSlopeBreak,  // a gentle shelf breaking into a steeper slope: smooth, no features
  kFlat,        // flat mud: nearly featureless
  kMixed,       // ~100 m patches of the five kinds above
};
TerrainKind parse_terrain_kind(const std::string& name);  // throws std::invalid_argument
std::string to_string(TerrainKind kind);

// A closed interval that the seed draws a value from.
struct Range {
  double min = 0;
  double max = 0;
};

struct TerrainConfig {
  TerrainKind kind = TerrainKind::kLake;
  uint64_t seed = 1;
  double mean_depth_m = 10.0;
  double cell_m = 0.2;            // grid resolution of the sampled surface
  double region_size_m = 90.0;    // flat and rough regions alternate at about this scale
  double regional_relief_m = 1.0; // very gentle large-scale relief everywhere (lakebed slope)
  double flat_roughness_m = 0.01; // sediment texture of the flat lakebed
  // Rough regions: features per square metre and their sizes.
  double mound_density = 1.0 / 250.0;
  double ridge_density = 1.0 / 1500.0;
  double channel_density = 1.0 / 2500.0;
  double fine_roughness_m = 0.15;
  bool flat_only = false;         // a perfectly flat bottom at mean depth (sonar geometry tests)

  // Sand waves: one dominant sinusoidal train and up to two weaker, shorter ones. Wavelengths
  // span a submap's length (~20 m) from below and above, so an alignment one crest off is as
  // good as the right one and well inside the 30 m matching gate.
  Range sand_wavelength_m{8.0, 40.0};
  Range sand_wave_height_m{0.3, 1.5};     // crest to trough of the dominant train
  // Crests oblique to the east-west lines, either side of east: the swath sees both the period
  // and its sampling along track.
  Range sand_crest_angle_deg{20.0, 70.0};
  std::optional<double> sand_wavelength_fixed_m;    // the dominant wavelength, else drawn
  std::optional<double> sand_crest_angle_fixed_deg; // crests' direction, counter-clockwise from east
  // Megaripples riding on the waves: texture at the scale of the sonar footprint.
  Range megaripple_wavelength_m{1.0, 2.0};
  double megaripple_height_m = 0.04;
  // How far every sand-wave train has moved across its crests since the site's first survey
  // (site.h): a repeat survey finds the bedforms migrated, not the seabed's frame.
  double sand_migration_m = 0;

  // Boulders on flat sand: sparse enough that a submap holds a handful or none.
  Range boulder_area_m2{400.0, 1000.0};   // sea floor per boulder
  Range boulder_height_m{0.5, 2.0};       // capped by the diameter: no pillars
  Range boulder_diameter_m{1.0, 3.0};

  // Channels crossing a flat plain; one or two. Depth is capped at a quarter of the width so
  // the banks stay below ~50 degrees, as sediment banks do.
  Range channel_depth_m{3.0, 10.0};
  Range channel_width_m{20.0, 60.0};
  Range meander_wavelength_m{150.0, 400.0};

  // Slope break: shelf and slope gradients (rise over run), the slope at least 4x steeper, so
  // the change is the only feature. The slope drops a few metres and the shelf and the basin
  // below it level out ~100 m from it, keeping a 1 km survey between ~5 and ~15 m deep.
  Range shelf_gradient{0.01, 0.02};
  Range slope_gradient{0.05, 0.15};
  Range slope_drop_m{3.0, 6.0};
  Range break_angle_deg{20.0, 70.0};      // off east, either side: oblique to the lines
  // The break line's direction (counter-clockwise from east) through the area's centre, else
  // drawn; downslope is to its right.
  std::optional<double> break_angle_fixed_deg;

  // Mixed: square patches of this size, each of another kind, blended over ~30 m borders.
  double mixed_patch_m = 100.0;
};

// Axis-aligned area in the local map frame (metres east, north).
struct Area {
  Eigen::Vector2d min{0, 0};
  Eigen::Vector2d max{0, 0};
};

class Terrain {
 public:
  // Samples the terrain over `area` (and a little beyond, so rays near the edge still land).
  // `scale` makes the same seabed `scale` times larger in every direction, depth included: the
  // terrain of `config` over area / scale, stretched (a survey flown `scale` times higher).
  static Terrain generate(const TerrainConfig& config, const Area& area, double scale = 1);

  // Elevation (metres, negative below the datum) at a map-frame position, bilinear between
  // grid samples; clamps outside the sampled area.
  double elevation(double x, double y) const;
  // How rough the terrain is at (x, y): 0 on flat ground, 1 in undulating regions (lake),
  // on sand waves, boulders and channel floors.
  double roughness_weight(double x, double y) const;
  // The seabed changed by `delta_m(x, y)` metres of elevation (map frame) at every sample: a
  // repeat survey's site after scour, dredging or a dropped object (site.h).
  void change(const std::function<double(double x, double y)>& delta_m);
  // Largest surface slope (rise over run) anywhere; ray marching uses it as a safe step bound.
  double max_slope() const { return max_slope_; }
  Area area() const { return {scale_ * area_.min, scale_ * area_.max}; }

 private:
  void sample_lake(const TerrainConfig& config);
  void sample_seabed(const TerrainConfig& config, const Area& area);
  double steepest_slope() const;
  double sample(const std::vector<float>& grid, double x, double y) const;

  Area area_;
  double cell_m_ = 0.2;
  int cols_ = 0;
  int rows_ = 0;
  std::vector<float> elevation_;
  std::vector<float> roughness_;
  double max_slope_ = 1.0;
  double scale_ = 1;  // map frame over the sampled grid's frame, horizontally and vertically
};

}  // namespace bathyslam::sim
