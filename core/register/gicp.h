#pragma once
// register (direct path): GICP between two submaps, initialised from dead reckoning, with the
// quality measures that acceptance and the information matrices use.
#include <cstddef>

#include <Eigen/Geometry>

#include "core/filter/voxel_filter.h"

namespace bathyslam {

struct GicpConfig {  // Table 1 (c)
  double max_correspondence_m = 3.0;
  int max_iterations = 300;
  double convergence = 1e-3;  // transformation epsilon
  int neighbours = 20;        // for the point covariances
  // Large-offset mode (off in the `gicp` baseline). GICP turns the source about its frame's
  // origin, tens of metres from an adjacent line's overlap, so yaw and translation are nearly the
  // same motion and the solver stops short of the minimum; `about_centroid` registers about the
  // clouds' centroids instead, and a second pass with a tighter gate and convergence removes the
  // bias that the 3 m gate's noise and swath edges leave (~0.2 m, ~0.8 deg; gicp_test.cpp). From
  // a 2 m, 3 deg error this recovers textured pairs to a few centimetres, but from dead reckoning
  // on flat pairs it lets yaw slide where nothing constrains it, which costs the `gicp` baseline
  // (docs/slam-core.md, "Departures from Table 1"); the feature-aided path starts it close instead.
  bool about_centroid = false;
  double refine_correspondence_m = 0.0;  // 0: no second pass
  double refine_convergence = 1e-6;
  // Which GICP registers: 0 PCL's GeneralizedIterativeClosestPoint (the reference, kept for the
  // benchmark and as a setting), 1 ours (gicp_solver.h) on submaps prepared once
  // (gicp_cloud.h), same parameters and rule, registering a sample of the soundings
  // (soundings_per_sample); more accurate than PCL's and 5.7x faster per pair on `lake`, 2.0x
  // on every sounding (docs/performance.md).
  int engine = 1;
  // Ours only: directions (rotations in metres at the overlap) that the terrain observes less
  // than this share of the best-observed one keep the guess's value instead of sliding on the
  // plane covariances' pull along the seabed (gicp_solver.cpp, observed_step). On `lake` the
  // flattest direct pairs show ~1e-4, textured ones 2e-3 and more (docs/performance.md).
  double min_observed_share = 0.0005;
  // Ours only: a pass that turns the source further than this from where it started has left the
  // basin it started in and ends, not converged. GICP starts within dead reckoning's few degrees
  // of heading error or at RANSAC's estimate, so it refines by degrees; on a pair whose
  // terrain does not hold it, it can spin on for hundreds of iterations (seen on `lake`: 110 deg
  // after 300) towards an answer acceptance refuses anyway. 180: no limit.
  double max_turn_deg = 30.0;
  // Ours only: a pass whose mean cost per correspondence has not fallen by 1 % over this many
  // iterations ends there, as at the iteration limit (converged, in PCL's sense). Such a pass is
  // sliding along what the terrain does not hold, by decimetres an iteration (seen on `lake`: a
  // pair started 12 m off took 300 iterations to lower its cost by 12 %, every point searched
  // again each time, to an answer 11 m off); more iterations move it, hardly fitting it better.
  // 40, not 20: at 20 `lake` seed 1's consistency RMSE rose 16 %, at 40 it did not move
  // (docs/performance.md). 0: never.
  int stall_iterations = 40;
  // Ours only: GICP registers one sounding in this many, spread evenly (the one nearest the
  // centre of each column of a grid sized to hold this many a column), each with its plane from
  // its k nearest soundings of all; the quality is still measured on every sounding
  // (gicp_cloud.h says why a sample registers as well). 1: every sounding.
  double soundings_per_sample = 3;
  // Threads inside one registration (ours only). The pipeline registers pairs in parallel
  // instead, so 1 there; the benchmark measures both.
  int threads = 1;

  template <typename Field>
  void fields(Field&& field) {
    field("max_correspondence_m", max_correspondence_m, 0.01, 1e5);
    field("max_iterations", max_iterations, 1, 10000);
    field("convergence", convergence, 1e-12, 1);
    field("neighbours", neighbours, 3, 200);
    field("about_centroid", about_centroid, 0, 1);
    field("refine_correspondence_m", refine_correspondence_m, 0, 1e5);
    field("refine_convergence", refine_convergence, 1e-12, 1);
    field("engine", engine, 0, 1);
    field("min_observed_share", min_observed_share, 0, 1);
    field("max_turn_deg", max_turn_deg, 0, 180);
    field("stall_iterations", stall_iterations, 0, 10000);
    field("soundings_per_sample", soundings_per_sample, 1, 100);
    field("threads", threads, 1, 1024);
  }
};

// Whether `config` registers with our GICP (engine 1) rather than PCL's: the one place that
// reads the engine (the pipeline's Plan asks it once; one-off registrations too).
inline bool uses_own_gicp(const GicpConfig& config) { return config.engine == 1; }

struct RegistrationQuality {
  bool converged = false;
  double fitness = 0;              // overlap_points over all source points (Open3D's fitness)
  std::size_t overlap_points = 0;  // source points with a target point within max_correspondence
  double overlap_mse_m2 = 0;     // mean squared distance over those points
};

struct Registration {
  Eigen::Isometry3d source_to_target = Eigen::Isometry3d::Identity();
  RegistrationQuality quality;
};

// Both clouds in their own (centred) submap frames; `guess` maps source into target. Quality is
// measured at `max_correspondence_m` whatever pass produced the transform.
Registration register_gicp(const Cloud::ConstPtr& target, const Cloud::ConstPtr& source,
                           const Eigen::Isometry3d& guess, const GicpConfig& config = {});

// The points of `cloud` that fall inside the horizontal bounding box of `other` once moved by
// `cloud_to_other`, widened by `margin_m`. Registering only the DR-predicted overlap keeps the
// swath edges from pulling the clouds together in flat regions.
Cloud::Ptr crop_to_overlap(const Cloud& cloud, const Cloud& other, const Eigen::Isometry3d& cloud_to_other,
                           double margin_m);

// `registered` with its roll and pitch replaced by those of `guess` (dead reckoning measures
// them far better than a strip of overlap does), re-anchored so that it still moves the
// overlap's centroid (`anchor`, source frame) exactly where `registered` does. Without the
// re-anchoring, a small roll error about the source's origin, 20 m from the overlap, would
// become a decimetre of false heave.
Eigen::Isometry3d keep_dr_roll_pitch(const Eigen::Isometry3d& registered, const Eigen::Isometry3d& guess,
                                     const Eigen::Vector3d& anchor);

// Mean of a cloud's points (zero for an empty cloud), summed in double.
Eigen::Vector3d centroid(const Cloud& cloud);

// Overlap of `source` (moved by `source_to_target`) with `target`.
RegistrationQuality overlap_quality(const Cloud& target, const Cloud& source,
                                    const Eigen::Isometry3d& source_to_target, double max_distance_m);

}  // namespace bathyslam
