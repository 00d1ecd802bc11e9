#pragma once
// register (MCHS): the observability switch between direct GICP and feature-aided registration
// (TSD keypoints -> matching -> adaptive RANSAC -> GICP refinement), per submap pair.
#include <atomic>
#include <string>
#include <vector>

#include "core/features/submap_features.h"
#include "core/matching/adaptive_ransac.h"
#include "core/matching/feature_matching.h"
#include "core/register/gicp.h"
#include "core/register/gicp_cloud.h"
#include "core/register/uniqueness.h"
#include "core/register/registration_information.h"
#include "core/submaps/submap.h"
#include "core/types/fields.h"

namespace bathyslam {

struct SwitchConfig {
  double min_feature_density = 0.005;  // Table 1 (a): keypoints per valid cell of the pair

  template <typename Field>
  void fields(Field&& field) {
    field("min_feature_density", min_feature_density, 0, 1);
  }
};

// Keypoints over valid cells of the two submaps together.
double feature_density(const SubmapFeatures& a, const SubmapFeatures& b);

enum class RegistrationPath { kDirect, kFeatureAided };
std::string to_string(RegistrationPath path);
RegistrationPath parse_registration_path(const std::string& text);  // throws std::invalid_argument

struct CoarseToFineConfig {
  SwitchConfig switching;
  MatchConfig matching;
  RansacConfig ransac;
  GicpConfig gicp;
  double crop_margin_m = 1.0;
  // Probed about either path's answer: the feature-aided path's acceptance and the direct
  // path's depth information use it.
  UniquenessConfig uniqueness;
  // The feature-aided path starts GICP within centimetres to a metre of the answer on textured
  // ground, where registering about the centroids with a refining pass at this gate reaches
  // a few centimetres and a tenth of a degree instead of Table 1's ~0.2 m and ~0.8 deg
  // (gicp_test.cpp). 0: refine exactly as the direct path registers.
  double feature_refine_correspondence_m = 1.0;
  // The direct path starts GICP at dead reckoning's guess and stops in the basin it starts in; on
  // a periodic seabed a guess more than half a wavelength off is a neighbouring trough. Where the
  // uniqueness probe about the answer finds another basin that fits clearly better (distinctness
  // under `restart_below_distinctness`), GICP starts again there, and the better-fitting answer
  // is kept, up to `best_basin_restarts` times. Which of several troughs is the truth is still
  // judged as before (alias rule, DR gate, PCM). 0 restarts: the answer from the guess stands.
  int best_basin_restarts = 2;
  // 0.5: the other basin's RMS misfit under 0.7x the answer's, the mirror of
  // quality.widen_min_distinctness. At 1, sounding noise alone sends half the answers on a
  // featureless bottom elsewhere, and their depth, roll and pitch then come from the wrong place.
  double restart_below_distinctness = 0.5;
  // And only from an answer that sits in a basin of the terrain: its misfit at most this share of
  // the typical offset's (Uniqueness::typical_cost_m2). Where the answer fits no better than a
  // random offset (a flat bottom, an overlap the drift within the submaps has bent), a better
  // fit elsewhere is noise, and moving there took depth, roll and pitch from 15-30 m away
  // (`small` flat and sand waves).
  double restart_max_answer_share = 0.25;
  template <typename Field>
  void fields(Field&& field) {
    nested("switching", switching, field);
    nested("matching", matching, field);
    nested("ransac", ransac, field);
    nested("gicp", gicp, field);
    field("crop_margin_m", crop_margin_m, 0, 1e5);
    nested("uniqueness", uniqueness, field);
    field("feature_refine_correspondence_m", feature_refine_correspondence_m, 0, 1e5);
    field("best_basin_restarts", best_basin_restarts, 0, 10);
    field("restart_below_distinctness", restart_below_distinctness, 0, 1);
    field("restart_max_answer_share", restart_max_answer_share, 0, 1);
  }
};

struct PairRegistration {
  RegistrationPath path = RegistrationPath::kDirect;
  std::string why;  // the switch's decision in words
  double feature_density = 0;
  int matches = 0;
  int ransac_inliers = 0;
  // RANSAC's best distinct alternative (feature-aided path): its support and separation.
  int competitor_inliers = 0;
  double competitor_separation_m = 0;
  // RANSAC's inlier share on the feature-aided path; GICP's fitness (share of source points
  // with a target point within the gate) on the direct path.
  double inlier_ratio = 0;
  Eigen::Isometry3d coarse = Eigen::Isometry3d::Identity();  // where GICP started
  Registration registration;
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();  // centroid of the source overlap, source frame
  Uniqueness uniqueness;  // whether another offset fits nearly as well, and the relief near the answer
  // Of the GICP cost at the result, about `anchor`, in the target frame; empty (no
  // correspondences) unless asked for or without a registration.
  GicpHessian hessian;
};

// A pair's two submaps as the chosen GICP reads them: ours (GicpConfig::engine 1) on submaps
// prepared once (from a GicpCloudCache: prepared_pair), PCL's on the filtered clouds
// (pcl_pair). `cancel` ends our registration within an iteration (null: never); PCL's GICP
// ignores it.
struct PairClouds {
  const GicpCloud* prepared_target = nullptr;  // ours: both set
  const GicpCloud* prepared_source = nullptr;
  const Cloud* target = nullptr;  // PCL's: both set
  const Cloud* source = nullptr;
  const std::atomic<bool>* cancel = nullptr;
};

// The pair's submaps from `cache`, prepared on first use, for our GICP.
PairClouds prepared_pair(GicpCloudCache& cache, int target, int source, const std::atomic<bool>* cancel = nullptr);

// The pair's filtered clouds, for PCL's GICP.
inline PairClouds pcl_pair(const Cloud& target, const Cloud& source) { return {nullptr, nullptr, &target, &source}; }

// A pair registered once, outside a job (tests, benchmarks): its clouds as `gicp`'s engine reads
// them, ours prepared now and held here.
struct OneOffPair {
  std::shared_ptr<const GicpCloud> target, source;
  PairClouds clouds;
};
OneOffPair one_off_pair(const Cloud& target, const Cloud& source, const GicpConfig& gicp);

// The coarse half: the switch's decision and, on the feature-aided path, RANSAC's estimate, so
// where GICP starts and with which settings. No GICP runs here.
struct CoarseStart {
  RegistrationPath path = RegistrationPath::kDirect;
  std::string why;
  double feature_density = 0;
  int matches = 0;  // also on the direct path when too few
  int ransac_inliers = 0, competitor_inliers = 0;  // feature-aided path only
  double competitor_separation_m = 0, ransac_inlier_ratio = 0;
  Eigen::Isometry3d start = Eigen::Isometry3d::Identity();  // the guess on the direct path
  GicpConfig gicp;  // Table 1's, or the feature-aided refinement's
};

CoarseStart coarse_start(const SubmapFeatures& target_features, const SubmapFeatures& source_features,
                         const Eigen::Isometry3d& guess, const CoarseToFineConfig& config, uint64_t seed);

// The fine half: GICP from the coarse start, with the uniqueness probe about its answer; on the
// direct path, GICP again from a basin the probe finds fitting clearly better (best_basin_restarts).
PairRegistration register_from_start(const CoarseStart& coarse, const PairClouds& clouds,
                                     const SubmapFeatures& target_features, const SubmapFeatures& source_features,
                                     const CoarseToFineConfig& config, bool with_hessian = false);

// A pair left unregistered after the coarse half: its switch decision, and `guess` as its answer,
// not converged and with no overlap measured.
PairRegistration unregistered(const CoarseStart& coarse, const Eigen::Isometry3d& guess);

// Both halves. `guess`: the DR-predicted pose of source in target. `seed` makes RANSAC
// reproducible per pair.
// `with_hessian`: also the GICP cost's Hessian at the result (PairRegistration::hessian), for
// quality.information_from_hessian; it costs about as much again as the registration, so only
// the information that needs it asks.
PairRegistration register_coarse_to_fine(const PairClouds& clouds, const SubmapFeatures& target_features,
                                         const SubmapFeatures& source_features, const Eigen::Isometry3d& guess,
                                         const CoarseToFineConfig& config, uint64_t seed, bool with_hessian = false);

// What the overlap of two prepared submaps observes at `source_to_target`, without registering:
// its quality, its anchor and the GICP cost's Hessian there, on the direct path. At the truth
// this is the information the seabed supports (bench_oracle_graph --observable).
PairRegistration observe_at(const GicpCloud& target, const GicpCloud& source, const Eigen::Isometry3d& source_to_target,
                            const GicpConfig& gicp, double crop_margin_m);

// Direct GICP on the clouds' overlap under `guess`, with the source overlap's centroid and, if
// `with_hessian`, the cost's Hessian there; by ours where `clouds` are prepared, else by PCL's.
PairRegistration register_direct(const PairClouds& clouds, const Eigen::Isometry3d& guess, const GicpConfig& gicp,
                                 double crop_margin_m, bool with_hessian = false);

}  // namespace bathyslam
