#include "core/sim/terrain.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/sim/noise.h"
#include "core/sim/random.h"
#include "core/sim/seabed.h"

namespace bathyslam::sim {
namespace {

constexpr double kMarginM = 60.0;

constexpr TerrainKind kTerrainKinds[] = {TerrainKind::kLake,       TerrainKind::kSandWaves,
                                         TerrainKind::kBoulders,   TerrainKind::kChannel,
                                         TerrainKind::kSlopeBreak, TerrainKind::kFlat,
                                         TerrainKind::kMixed};

// An elongated Gaussian bump (ridge, or channel with negative height) or a round one (mound,
// where half_length is 0).
struct Feature {
  Eigen::Vector2d centre;
  Eigen::Vector2d direction{1, 0};
  double half_length = 0;
  double sigma = 1;
  double height = 0;

  double reach() const { return half_length + 3.0 * sigma; }
  double operator()(const Eigen::Vector2d& p) const {
    const Eigen::Vector2d d = p - centre;
    const double along = std::max(0.0, std::abs(d.dot(direction)) - half_length);
    const double across = d.x() * direction.y() - d.y() * direction.x();
    return height * std::exp(-(along * along + across * across) / (2 * sigma * sigma));
  }
};

std::vector<Feature> scatter_features(const TerrainConfig& config, const Area& area,
                                      std::mt19937_64& rng) {
  const double square_m = (area.max - area.min).prod();
  std::uniform_real_distribution<double> ux(area.min.x(), area.max.x());
  std::uniform_real_distribution<double> uy(area.min.y(), area.max.y());
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto between = [&](double a, double b) { return a + (b - a) * unit(rng); };
  auto direction = [&] {
    const double a = between(0, M_PI);
    return Eigen::Vector2d(std::cos(a), std::sin(a));
  };

  std::vector<Feature> features;
  const auto count = [&](double density) { return static_cast<int>(density * square_m); };
  for (int k = 0; k < count(config.mound_density); ++k) {
    const double sign = unit(rng) < 0.8 ? 1.0 : -1.0;  // mostly mounds, some pits
    features.push_back({{ux(rng), uy(rng)}, {1, 0}, 0.0, between(2, 7), sign * between(0.4, 2.0)});
  }
  for (int k = 0; k < count(config.ridge_density); ++k) {
    features.push_back({{ux(rng), uy(rng)}, direction(), between(10, 35), between(1.5, 4),
                        between(0.5, 1.5)});
  }
  for (int k = 0; k < count(config.channel_density); ++k) {
    features.push_back({{ux(rng), uy(rng)}, direction(), between(20, 50), between(2, 5),
                        -between(0.5, 1.5)});
  }
  return features;
}

}  // namespace

TerrainKind parse_terrain_kind(const std::string& name) {
  for (TerrainKind kind : kTerrainKinds) {
    if (to_string(kind) == name) return kind;
  }
  throw std::invalid_argument("unknown terrain '" + name +
                              "' (expected lake, sandwaves, boulders, channel, slopebreak, flat or mixed)");
}

std::string to_string(TerrainKind kind) {
  switch (kind) {
    case TerrainKind::kLake: return "lake";
    case TerrainKind::kSandWaves: return "sandwaves";
    case TerrainKind::kBoulders: return "boulders";
    case TerrainKind::kChannel: return "channel";
    case TerrainKind::kSlopeBreak: return "slopebreak";
    case TerrainKind::kFlat: return "flat";
    case TerrainKind::kMixed: return "mixed";
  }
  return "?";
}

Terrain Terrain::generate(const TerrainConfig& config, const Area& area, double scale) {
  Terrain t;
  t.scale_ = scale;
  t.area_ = {area.min.array() / scale - kMarginM, area.max.array() / scale + kMarginM};
  t.cell_m_ = config.cell_m;
  t.cols_ = static_cast<int>(std::ceil((t.area_.max.x() - t.area_.min.x()) / t.cell_m_)) + 1;
  t.rows_ = static_cast<int>(std::ceil((t.area_.max.y() - t.area_.min.y()) / t.cell_m_)) + 1;
  const std::size_t cells = static_cast<std::size_t>(t.cols_) * t.rows_;
  t.elevation_.assign(cells, static_cast<float>(-config.mean_depth_m));
  t.roughness_.assign(cells, 0.0f);
  if (config.flat_only) {
    t.max_slope_ = 0.0;
    return t;
  }
  if (config.kind == TerrainKind::kLake) {
    t.sample_lake(config);
  } else {
    t.sample_seabed(config, {area.min / scale, area.max / scale});
  }
  t.max_slope_ = t.steepest_slope();
  return t;
}

void Terrain::sample_lake(const TerrainConfig& config) {
  const std::size_t cells = elevation_.size();
  auto rng = make_rng(config.seed, kTerrainStream);
  // Rough and flat regions: a checkerboard of region-sized cells with some squares flipped, so
  // the pattern alternates but is not regular; smoothed into transitions a few tens of metres wide.
  const ValueNoise region_jitter(area_, config.region_size_m, 0.25, rng);
  auto region_weight = [&](double x, double y) {
    const double u = (x - area_.min.x()) / config.region_size_m;
    const double v = (y - area_.min.y()) / config.region_size_m;
    const double checker = 0.5 + 0.5 * std::sin(M_PI * u) * std::sin(M_PI * v);
    return smoothstep(0.35, 0.65, checker + region_jitter(x, y));
  };
  const ValueNoise regional(area_, 250.0, config.regional_relief_m, rng);
  const ValueNoise fine_coarse(area_, 3.0, config.fine_roughness_m, rng);
  const ValueNoise fine_detail(area_, 1.2, 0.5 * config.fine_roughness_m, rng);
  std::normal_distribution<float> sediment(0.0f, static_cast<float>(config.flat_roughness_m));

  // Relief of the rough regions before weighting: features splatted over their reach.
  std::vector<float> relief(cells, 0.0f);
  for (const Feature& f : scatter_features(config, area_, rng)) {
    const double r = f.reach();
    const int i0 = std::max(0, static_cast<int>((f.centre.x() - r - area_.min.x()) / cell_m_));
    const int i1 = std::min(cols_ - 1, static_cast<int>((f.centre.x() + r - area_.min.x()) / cell_m_));
    const int j0 = std::max(0, static_cast<int>((f.centre.y() - r - area_.min.y()) / cell_m_));
    const int j1 = std::min(rows_ - 1, static_cast<int>((f.centre.y() + r - area_.min.y()) / cell_m_));
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        const Eigen::Vector2d p(area_.min.x() + i * cell_m_, area_.min.y() + j * cell_m_);
        relief[static_cast<std::size_t>(j) * cols_ + i] += static_cast<float>(f(p));
      }
    }
  }

  for (int j = 0; j < rows_; ++j) {
    for (int i = 0; i < cols_; ++i) {
      const double x = area_.min.x() + i * cell_m_, y = area_.min.y() + j * cell_m_;
      const std::size_t c = static_cast<std::size_t>(j) * cols_ + i;
      const double w = region_weight(x, y);
      const double rough = relief[c] + fine_coarse(x, y) + fine_detail(x, y);
      roughness_[c] = static_cast<float>(w);
      elevation_[c] = static_cast<float>(-config.mean_depth_m + regional(x, y) + w * rough) +
                        sediment(rng);
    }
  }
}

void Terrain::sample_seabed(const TerrainConfig& config, const Area& area) {
  auto rng = make_rng(config.seed, kTerrainStream);
  const std::unique_ptr<Seabed> seabed = make_seabed(config.kind, config, area, rng);
  seabed->migrate_sand_waves(config.sand_migration_m);  // after centring: the mean stays
#pragma omp parallel for schedule(dynamic, 16)
  for (int j = 0; j < rows_; ++j) {
    for (int i = 0; i < cols_; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * cols_ + i;
      const Ground g = seabed->at({area_.min.x() + i * cell_m_, area_.min.y() + j * cell_m_});
      roughness_[c] = static_cast<float>(g.roughness);
      elevation_[c] = static_cast<float>(-config.mean_depth_m + g.height);
    }
  }
  // Sediment texture drawn in grid order, apart from the parallel loop: the same bytes whatever
  // the thread count.
  std::normal_distribution<float> sediment(0.0f, static_cast<float>(config.flat_roughness_m));
  for (float& e : elevation_) e += sediment(rng);
}

void Terrain::change(const std::function<double(double x, double y)>& delta_m) {
  for (int j = 0; j < rows_; ++j) {
    for (int i = 0; i < cols_; ++i) {
      const double x = scale_ * (area_.min.x() + i * cell_m_), y = scale_ * (area_.min.y() + j * cell_m_);
      elevation_[static_cast<std::size_t>(j) * cols_ + i] += static_cast<float>(delta_m(x, y) / scale_);
    }
  }
  max_slope_ = steepest_slope();
}

// Steepest per-axis slope; the directional slope of the bilinear surface is at most their sum.
double Terrain::steepest_slope() const {
  float steepest = 0;
  for (int j = 0; j + 1 < rows_; ++j) {
    for (int i = 0; i + 1 < cols_; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * cols_ + i;
      steepest = std::max({steepest, std::abs(elevation_[c + 1] - elevation_[c]),
                           std::abs(elevation_[c + cols_] - elevation_[c])});
    }
  }
  return 2.0 * steepest / cell_m_;
}

double Terrain::sample(const std::vector<float>& grid, double x, double y) const {
  const double u = std::clamp((x - area_.min.x()) / cell_m_, 0.0, cols_ - 1.0001);
  const double v = std::clamp((y - area_.min.y()) / cell_m_, 0.0, rows_ - 1.0001);
  const int i = static_cast<int>(u), j = static_cast<int>(v);
  const double fu = u - i, fv = v - j;
  const float* row = grid.data() + static_cast<std::size_t>(j) * cols_ + i;
  return (1 - fv) * ((1 - fu) * row[0] + fu * row[1]) +
         fv * ((1 - fu) * row[cols_] + fu * row[cols_ + 1]);
}

double Terrain::elevation(double x, double y) const { return scale_ * sample(elevation_, x / scale_, y / scale_); }

double Terrain::roughness_weight(double x, double y) const { return sample(roughness_, x / scale_, y / scale_); }

}  // namespace bathyslam::sim
