#include "core/sim/seabed.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/sim/noise.h"

namespace bathyslam::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

double draw(const Range& range, std::mt19937_64& rng) {
  return std::uniform_real_distribution<double>(range.min, range.max)(rng);
}

bool coin(std::mt19937_64& rng) { return std::bernoulli_distribution(0.5)(rng); }

// An angle off east, either side of it: how oblique a linear feature is to the east-west lines.
double draw_oblique_angle(const Range& range_deg, std::mt19937_64& rng) {
  const double sign = coin(rng) ? 1.0 : -1.0;
  return sign * draw(range_deg, rng) * kDeg;
}

Eigen::Vector2d direction(double angle_rad) { return {std::cos(angle_rad), std::sin(angle_rad)}; }

Eigen::Vector2d left_of(const Eigen::Vector2d& d) { return {-d.y(), d.x()}; }

Eigen::Vector2d centre_of(const Area& area) { return 0.5 * (area.min + area.max); }

// The gentle large-scale relief every kind but the slope break keeps (a lakebed's slope).
ValueNoise regional_relief(const TerrainConfig& config, const Area& area, std::mt19937_64& rng) {
  return ValueNoise(area, 250.0, config.regional_relief_m, rng);
}

// Parallel sinusoidal crests whose phase wanders slowly along them, so crests are not ruler
// straight.
struct WaveTrain {
  Eigen::Vector2d across{0, 1};  // unit, perpendicular to the crests
  double wavelength_m = 10;
  double height_m = 1;           // crest to trough
  double phase = 0;
  double sinuosity_rad = 0;
  double sinuosity_wavelength_m = 100;
  double sinuosity_phase = 0;
  double migration_m = 0;  // moved across the crests, downstream (`across`), since the first survey

  static WaveTrain draw_train(double crest_angle, double wavelength_m, double height_m,
                              std::mt19937_64& rng) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    WaveTrain w;
    w.across = left_of(direction(crest_angle));
    w.wavelength_m = wavelength_m;
    w.height_m = height_m;
    w.phase = 2 * M_PI * unit(rng);
    w.sinuosity_rad = 0.15 + 0.25 * unit(rng);
    w.sinuosity_wavelength_m = 80.0 + 120.0 * unit(rng);
    w.sinuosity_phase = 2 * M_PI * unit(rng);
    return w;
  }

  double operator()(const Eigen::Vector2d& p) const {
    const double along = p.dot(Eigen::Vector2d(across.y(), -across.x()));
    const double wander =
        sinuosity_rad * std::sin(2 * M_PI * along / sinuosity_wavelength_m + sinuosity_phase);
    return 0.5 * height_m * std::cos(2 * M_PI * (p.dot(across) - migration_m) / wavelength_m + phase + wander);
  }
};

class SandWaves final : public Seabed {
 public:
  SandWaves(const TerrainConfig& config, const Area& area, std::mt19937_64& rng)
      : regional_(regional_relief(config, area, rng)) {
    // Drawn even when fixed, so fixing them leaves the rest of the seabed as the seed made it.
    const double drawn_angle = draw_oblique_angle(config.sand_crest_angle_deg, rng);
    const double drawn_wavelength = draw(config.sand_wavelength_m, rng);
    const double crest = config.sand_crest_angle_fixed_deg
                             ? *config.sand_crest_angle_fixed_deg * kDeg : drawn_angle;
    const double wavelength = config.sand_wavelength_fixed_m.value_or(drawn_wavelength);
    const double height = draw(config.sand_wave_height_m, rng);
    trains_.push_back(WaveTrain::draw_train(crest, wavelength, height, rng));
    // Weaker, shorter trains on the dominant one, crests nearly parallel to its own: they
    // break the perfect period without hiding it.
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const int secondary = std::uniform_int_distribution<int>(0, 2)(rng);
    for (int k = 0; k < secondary; ++k) {
      const double angle = crest + (unit(rng) - 0.5) * 20.0 * kDeg;
      trains_.push_back(WaveTrain::draw_train(angle, wavelength * (0.35 + 0.35 * unit(rng)),
                                              height * (0.15 + 0.2 * unit(rng)), rng));
    }
    const double ripple_angle = crest + (unit(rng) - 0.5) * 40.0 * kDeg;
    trains_.push_back(WaveTrain::draw_train(ripple_angle, draw(config.megaripple_wavelength_m, rng),
                                            config.megaripple_height_m, rng));
  }

  void migrate_sand_waves(double distance_m) override {
    for (WaveTrain& train : trains_) train.migration_m = distance_m;
  }

  Ground at(const Eigen::Vector2d& p) const override {
    double h = regional_(p.x(), p.y());
    for (const WaveTrain& w : trains_) h += w(p);
    return {h, 1.0};
  }

 private:
  ValueNoise regional_;
  std::vector<WaveTrain> trains_;
};

class Boulders final : public Seabed {
 public:
  Boulders(const TerrainConfig& config, const Area& area, std::mt19937_64& rng)
      : regional_(regional_relief(config, area, rng)), origin_(area.min) {
    cols_ = static_cast<int>(std::ceil((area.max.x() - area.min.x()) / kBucketM)) + 1;
    rows_ = static_cast<int>(std::ceil((area.max.y() - area.min.y()) / kBucketM)) + 1;
    buckets_.resize(static_cast<std::size_t>(cols_) * rows_);
    std::uniform_real_distribution<double> x(area.min.x(), area.max.x()), y(area.min.y(), area.max.y());
    const auto count = static_cast<int>((area.max - area.min).prod() / draw(config.boulder_area_m2, rng));
    for (int k = 0; k < count; ++k) {
      const Eigen::Vector2d centre(x(rng), y(rng));
      const double diameter = draw(config.boulder_diameter_m, rng);
      const Range height{config.boulder_height_m.min, std::min(config.boulder_height_m.max, diameter)};
      add({centre, 0.5 * diameter, draw(height, rng)});
    }
  }

  Ground at(const Eigen::Vector2d& p) const override {
    Ground g{regional_(p.x(), p.y()), 0.0};
    const int i = bucket_col(p.x()), j = bucket_row(p.y());
    if (i < 0 || j < 0 || i >= cols_ || j >= rows_) return g;
    for (const Boulder& b : buckets_[static_cast<std::size_t>(j) * cols_ + i]) {
      const double u2 = (p - b.centre).squaredNorm() / (b.radius * b.radius);
      if (u2 >= 1.0) continue;
      // A smooth dome, level with the sand at its rim: sphere tracing needs bounded slopes.
      g.height += b.height * (1.0 - u2) * (1.0 - u2);
      g.roughness = 1.0;
    }
    return g;
  }

 private:
  struct Boulder {
    Eigen::Vector2d centre;
    double radius;
    double height;
  };
  static constexpr double kBucketM = 4.0;

  int bucket_col(double x) const { return static_cast<int>(std::floor((x - origin_.x()) / kBucketM)); }
  int bucket_row(double y) const { return static_cast<int>(std::floor((y - origin_.y()) / kBucketM)); }

  // Into every bucket its footprint touches, so a lookup reads one bucket.
  void add(const Boulder& b) {
    const int i0 = std::max(0, bucket_col(b.centre.x() - b.radius));
    const int i1 = std::min(cols_ - 1, bucket_col(b.centre.x() + b.radius));
    const int j0 = std::max(0, bucket_row(b.centre.y() - b.radius));
    const int j1 = std::min(rows_ - 1, bucket_row(b.centre.y() + b.radius));
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) buckets_[static_cast<std::size_t>(j) * cols_ + i].push_back(b);
    }
  }

  ValueNoise regional_;
  Eigen::Vector2d origin_;
  int cols_ = 0, rows_ = 0;
  std::vector<std::vector<Boulder>> buckets_;
};

// A channel's centreline wanders about a straight course by two sinusoids; its cross-section
// has a flat floor and banks that rise over the outer 70 % of the half-width.
struct ChannelPath {
  Eigen::Vector2d origin;
  Eigen::Vector2d along;
  double half_width_m = 10;
  double depth_m = 3;
  std::array<double, 2> amplitude{}, wavenumber{}, phase{};

  static ChannelPath draw_path(const TerrainConfig& config, const Area& area, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    ChannelPath c;
    // Through the middle half of the area, any course: it crosses the whole area.
    const Eigen::Vector2d size = area.max - area.min;
    c.origin = area.min + Eigen::Vector2d(size.x() * (0.25 + 0.5 * unit(rng)),
                                          size.y() * (0.25 + 0.5 * unit(rng)));
    c.along = direction(M_PI * unit(rng));
    const double width = draw(config.channel_width_m, rng);
    c.half_width_m = 0.5 * width;
    c.depth_m = draw({config.channel_depth_m.min, std::min(config.channel_depth_m.max, 0.25 * width)}, rng);
    // Amplitude times wavenumber is the meander's steepest angle to the course: below ~40 deg.
    const double wavelength = draw(config.meander_wavelength_m, rng);
    c.wavenumber = {2 * M_PI / wavelength, 2 * M_PI / (wavelength * (0.3 + 0.2 * unit(rng)))};
    c.amplitude = {(0.3 + 0.5 * unit(rng)) / c.wavenumber[0], 0.2 * unit(rng) / c.wavenumber[1]};
    c.phase = {2 * M_PI * unit(rng), 2 * M_PI * unit(rng)};
    return c;
  }

  // 1 on the floor, 0 beyond the banks.
  double inside(const Eigen::Vector2d& p) const {
    const Eigen::Vector2d d = p - origin;
    const double s = d.dot(along), across = d.dot(left_of(along));
    double offset = 0, slope = 0;
    for (std::size_t k = 0; k < amplitude.size(); ++k) {
      offset += amplitude[k] * std::sin(wavenumber[k] * s + phase[k]);
      slope += amplitude[k] * wavenumber[k] * std::cos(wavenumber[k] * s + phase[k]);
    }
    // Offset across the course, shortened where the centreline runs oblique to it.
    const double distance = std::abs(across - offset) / std::sqrt(1.0 + slope * slope);
    return 1.0 - smoothstep(0.3 * half_width_m, half_width_m, distance);
  }
};

class Channel final : public Seabed {
 public:
  Channel(const TerrainConfig& config, const Area& area, std::mt19937_64& rng)
      : regional_(regional_relief(config, area, rng)),
        fine_coarse_(area, 3.0, config.fine_roughness_m, rng),
        fine_detail_(area, 1.2, 0.5 * config.fine_roughness_m, rng) {
    const int count = coin(rng) ? 1 : 2;
    for (int k = 0; k < count; ++k) paths_.push_back(ChannelPath::draw_path(config, area, rng));
  }

  Ground at(const Eigen::Vector2d& p) const override {
    double cut = 0, inside = 0;
    for (const ChannelPath& c : paths_) {
      const double w = c.inside(p);
      cut = std::max(cut, w * c.depth_m);  // where channels meet, the deeper one
      inside = std::max(inside, w);
    }
    const double rough = fine_coarse_(p.x(), p.y()) + fine_detail_(p.x(), p.y());
    return {regional_(p.x(), p.y()) - cut + inside * rough, inside};
  }

 private:
  ValueNoise regional_, fine_coarse_, fine_detail_;
  std::vector<ChannelPath> paths_;
};

class SlopeBreak final : public Seabed {
 public:
  SlopeBreak(const TerrainConfig& config, const Area& area, std::mt19937_64& rng)
      : origin_(centre_of(area)) {
    // Which side the shelf lies on is drawn too: the break line's direction spans all angles.
    const double drawn = draw_oblique_angle(config.break_angle_deg, rng) + (coin(rng) ? M_PI : 0.0);
    const double angle = config.break_angle_fixed_deg ? *config.break_angle_fixed_deg * kDeg : drawn;
    const Eigen::Vector2d line = direction(angle);
    downslope_ = {line.y(), -line.x()};  // to the line's right
    const double shelf = draw(config.shelf_gradient, rng);
    const Range steeper{std::max(config.slope_gradient.min, 4.0 * shelf),
                        std::max(config.slope_gradient.max, 4.0 * shelf)};
    const double slope = draw(steeper, rng);
    tabulate(shelf, slope, draw(config.slope_drop_m, rng), (area.max - area.min).norm());
  }

  Ground at(const Eigen::Vector2d& p) const override {
    const double u = std::clamp(((p - origin_).dot(downslope_) + reach_m_) / kStepM, 0.0,
                                static_cast<double>(profile_.size()) - 1.001);
    const auto i = static_cast<std::size_t>(u);
    return {profile_[i] + (u - i) * (profile_[i + 1] - profile_[i]), 0.0};
  }

 private:
  static constexpr double kStepM = 0.5;
  static constexpr double kBreakHalfWidthM = 3.0;  // the break is sharp at the swath's scale
  static constexpr double kLevelFromM = 100.0;     // the shelf and the basin level out from here
  static constexpr double kLevelOverM = 50.0;

  // Height across the break, integrated from the gradient: the shelf's, the slope's between the
  // break (s = 0) and its toe, the shelf's again below the toe; levelling out far from both.
  void tabulate(double shelf, double slope, double drop_m, double area_diagonal_m) {
    const double toe = drop_m / slope;
    auto gradient = [&](double s) {
      const double steep = smoothstep(-kBreakHalfWidthM, kBreakHalfWidthM, s) -
                           smoothstep(toe - kBreakHalfWidthM, toe + kBreakHalfWidthM, s);
      const double away = std::max({0.0, -s, s - toe});
      const double level = 1.0 - smoothstep(kLevelFromM, kLevelFromM + kLevelOverM, away);
      return shelf * level + (slope - shelf) * steep;
    };
    reach_m_ = area_diagonal_m + kLevelFromM;
    const auto n = static_cast<std::size_t>(std::ceil(2 * reach_m_ / kStepM)) + 1;
    profile_.assign(n, 0.0);
    for (std::size_t i = 1; i < n; ++i) {
      const double s = -reach_m_ + i * kStepM;
      profile_[i] = profile_[i - 1] - 0.5 * kStepM * (gradient(s - kStepM) + gradient(s));
    }
  }

  Eigen::Vector2d origin_;
  Eigen::Vector2d downslope_;
  double reach_m_ = 0;
  std::vector<double> profile_;
};

class Flat final : public Seabed {
 public:
  Flat(const TerrainConfig& config, const Area& area, std::mt19937_64& rng)
      : regional_(regional_relief(config, area, rng)) {}
  Ground at(const Eigen::Vector2d& p) const override { return {regional_(p.x(), p.y()), 0.0}; }

 private:
  ValueNoise regional_;
};

// Square patches, each a seabed of its own laid out over it, so every kind shows its character
// within a patch; neighbours blend over a band at their border.
class Mixed final : public Seabed {
 public:
  Mixed(const TerrainConfig& config, const Area& area, std::mt19937_64& rng)
      : origin_(area.min),
        jitter_u_(area, config.mixed_patch_m, kJitter, rng),
        jitter_v_(area, config.mixed_patch_m, kJitter, rng) {
    std::array<TerrainKind, 5> kinds{TerrainKind::kSandWaves, TerrainKind::kBoulders,
                                     TerrainKind::kChannel, TerrainKind::kSlopeBreak,
                                     TerrainKind::kFlat};
    std::shuffle(kinds.begin(), kinds.end(), rng);
    const Eigen::Vector2d size = area.max - area.min;
    cols_ = std::max(1, static_cast<int>(std::lround(size.x() / config.mixed_patch_m)));
    rows_ = std::max(1, static_cast<int>(std::lround(size.y() / config.mixed_patch_m)));
    patch_ = {size.x() / cols_, size.y() / rows_};
    for (int j = 0; j < rows_; ++j) {
      for (int i = 0; i < cols_; ++i) {
        // Steps of 1 along a row and 2 up a column, modulo 5: no two neighbours share a kind.
        const TerrainKind kind = kinds[static_cast<std::size_t>((i + 2 * j) % 5)];
        const Eigen::Vector2d low = origin_ + Eigen::Vector2d(i * patch_.x(), j * patch_.y());
        const Area patch{low.array() - kBand * patch_.array(), (low + patch_).array() + kBand * patch_.array()};
        patches_.push_back(make_seabed(kind, config, patch, rng));
      }
    }
  }

  Ground at(const Eigen::Vector2d& p) const override {
    // Patch centres sit at half-integer (u, v); between two centres, each weighs 1 up to the
    // border band.
    const double u = (p.x() - origin_.x()) / patch_.x() + jitter_u_(p.x(), p.y()) - 0.5;
    const double v = (p.y() - origin_.y()) / patch_.y() + jitter_v_(p.x(), p.y()) - 0.5;
    const double i0 = std::floor(u), j0 = std::floor(v);
    const double wu = smoothstep(0.5 - kBand, 0.5 + kBand, u - i0);
    const double wv = smoothstep(0.5 - kBand, 0.5 + kBand, v - j0);
    Ground sum;
    for (int dj = 0; dj < 2; ++dj) {
      for (int di = 0; di < 2; ++di) {
        const double w = (di ? wu : 1 - wu) * (dj ? wv : 1 - wv);
        if (w == 0) continue;
        const Ground g = patch(static_cast<int>(i0) + di, static_cast<int>(j0) + dj).at(p);
        sum.height += w * g.height;
        sum.roughness += w * g.roughness;
      }
    }
    return sum;
  }

  void migrate_sand_waves(double distance_m) override {
    for (auto& patch : patches_) patch->migrate_sand_waves(distance_m);
  }

 private:
  static constexpr double kJitter = 0.1;  // patch borders wander by ~a tenth of a patch
  static constexpr double kBand = 0.15;   // half the border band, in patches

  const Seabed& patch(int i, int j) const {
    i = std::clamp(i, 0, cols_ - 1);
    j = std::clamp(j, 0, rows_ - 1);
    return *patches_[static_cast<std::size_t>(j) * cols_ + i];
  }

  Eigen::Vector2d origin_;
  Eigen::Vector2d patch_{100, 100};
  int cols_ = 1, rows_ = 1;
  ValueNoise jitter_u_, jitter_v_;
  std::vector<std::unique_ptr<Seabed>> patches_;
};

// Shifted so that its mean height over an area is zero: every kind keeps the mean depth.
class Centred final : public Seabed {
 public:
  Centred(std::unique_ptr<Seabed> seabed, const Area& area) : seabed_(std::move(seabed)) {
    constexpr double kSampleM = 2.0;
    double sum = 0;
    long n = 0;
    for (double y = area.min.y(); y <= area.max.y(); y += kSampleM) {
      for (double x = area.min.x(); x <= area.max.x(); x += kSampleM, ++n) sum += seabed_->at({x, y}).height;
    }
    offset_ = n > 0 ? sum / n : 0.0;
  }

  Ground at(const Eigen::Vector2d& p) const override {
    Ground g = seabed_->at(p);
    g.height -= offset_;
    return g;
  }
  // The offset stays the one of the seabed as drawn: migration moves the bedforms, not the mean.
  void migrate_sand_waves(double distance_m) override { seabed_->migrate_sand_waves(distance_m); }

 private:
  std::unique_ptr<Seabed> seabed_;
  double offset_ = 0;
};

std::unique_ptr<Seabed> make_uncentred(TerrainKind kind, const TerrainConfig& config,
                                       const Area& area, std::mt19937_64& rng) {
  switch (kind) {
    case TerrainKind::kSandWaves: return std::make_unique<SandWaves>(config, area, rng);
    case TerrainKind::kBoulders: return std::make_unique<Boulders>(config, area, rng);
    case TerrainKind::kChannel: return std::make_unique<Channel>(config, area, rng);
    case TerrainKind::kSlopeBreak: return std::make_unique<SlopeBreak>(config, area, rng);
    case TerrainKind::kFlat: return std::make_unique<Flat>(config, area, rng);
    case TerrainKind::kMixed: return std::make_unique<Mixed>(config, area, rng);
    case TerrainKind::kLake: break;
  }
  throw std::invalid_argument("make_seabed: the lake is sampled by Terrain itself");
}

}  // namespace

std::unique_ptr<Seabed> make_seabed(TerrainKind kind, const TerrainConfig& config,
                                    const Area& area, std::mt19937_64& rng) {
  return std::make_unique<Centred>(make_uncentred(kind, config, area, rng), area);
}

}  // namespace bathyslam::sim
