#pragma once
// What the pipeline knows between two submaps: odometry from dead reckoning, or a registration
// of an adjacent survey line or a loop closure, with why it was refused if it was.
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/accept/rejection.h"
#include "core/graph/pose_graph.h"
#include "core/register/coarse_to_fine.h"
#include "core/register/gicp.h"
#include "core/register/uniqueness.h"

namespace bathyslam {

// kDatum: another survey's first submap held to the first survey's by both start fixes
// (GraphConfig::survey_starts), a prior as odometry is.
enum class ConstraintType { kOdometry, kAdjacent, kLoop, kDatum };
std::string to_string(ConstraintType type);
// Odometry and datum edges: the navigation's own word, not a registration.
inline bool from_navigation(ConstraintType type) { return type == ConstraintType::kOdometry || type == ConstraintType::kDatum; }
ConstraintType parse_constraint_type(const std::string& text);  // throws std::invalid_argument

// What the DR prior said of the uniqueness probe's alternative alignment (robust_backend.h,
// resolve_alias): nothing to say (the answer is unique, or the rule is off), dead reckoning
// rules it out, or it does not and the information along it was removed; or it does not and the
// graph of the registrations kept before it judged them instead (robustness.alias_from_graph).
enum class AliasResolution { kNone, kRuledOut, kInformationRemoved, kJudgedByGraph };
std::string to_string(AliasResolution resolution);

struct Constraint {
  ConstraintType type = ConstraintType::kOdometry;
  int from = 0, to = 0;
  Eigen::Isometry3d measured = Eigen::Isometry3d::Identity();  // `to` in the frame of `from`
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();  // registrations: overlap centroid, `to`'s frame
  // Registrations: the predicted pose of `to` in `from` the pair was registered from (the
  // feature-aided path starts GICP from RANSAC's estimate instead).
  Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
  Information6 information = Information6::Identity();
  // Registrations: the information the registration earned, before dead reckoning's judgement
  // (resolve_alias) took any away; judged again whenever the DR noise model changes.
  Information6 registered_information = Information6::Zero();
  RegistrationQuality quality;   // registrations only
  double overlap_fraction = 0;   // registrations only: footprint overlap at candidate time
  std::optional<RegistrationPath> path;  // registrations only
  std::string path_reason;       // the switch's decision in words
  double feature_density = 0;
  int matches = 0;
  double inlier_ratio = 0;
  int competitor_inliers = 0;    // RANSAC's best distinct alternative
  double competitor_separation_m = 0;
  Uniqueness uniqueness;         // the terrain probed around the answer (register/uniqueness.h)
  double dr_mahalanobis2 = -1;   // the DR gate's statistic (x, y, yaw); negative: not tested
  // Why the registration's horizontal answer is not the overlap's (register_pairs.cpp,
  // horizontal_doubt), its horizontal information removed; empty when nothing says so.
  std::string horizontal_doubt;
  // The doubt's scatter of other answers added to the answer's covariance (level frame, m²;
  // widened_by_doubt): zero when nothing widened it.
  Eigen::Matrix2d horizontal_spread = Eigen::Matrix2d::Zero();
  AliasResolution alias = AliasResolution::kNone;
  double alias_mahalanobis2 = -1;  // the nearest competitor's DR statistic; negative: not tested
  // The information the graph kept before it left the registration where dead reckoning left
  // its competitors open (robustness.alias_from_graph): it stands when DR's noise model changes.
  std::optional<Information6> graph_information;
  // The DR-plausible competitors' RMS distance from the answer along and across their main line.
  Eigen::Vector2d alias_spread_m = Eigen::Vector2d::Zero();
  Rejection rejection;           // by the registration tests or the DR gate
  Rejection exclusion;           // accepted, then left out of the graph by the back end
  bool accepted() const { return !rejection.rejected(); }
  bool in_graph() const { return accepted() && !exclusion.rejected(); }
  // Why it is not in the graph (empty when it is).
  const Rejection& why_not() const { return rejection.rejected() ? rejection : exclusion; }
};

// Whether `information` can bend the survey sideways or turn it: any of x, y and yaw. An edge
// without (a depth-only edge) cannot make the map horizontally wrong, whatever its error there.
bool carries_horizontal_information(const Information6& information);

// `information` with x, y and yaw taken out (rows and columns): depth, roll and pitch only.
Information6 without_horizontal(Information6 information);

// A horizontal offset in a registration's target frame (a probe's competitor, a start's shift)
// in its level frame, where the edge's residual and information lie.
inline Eigen::Vector2d level_offset(const Eigen::Matrix3d& level_from_target, const Eigen::Vector2d& offset) {
  return (level_from_target * Eigen::Vector3d(offset.x(), offset.y(), 0)).head<2>();
}

// Where else a registration's overlap put its answer, as horizontal offsets from it in the
// level frame (m): each start check's shift and where GICP landed from it, or the nearby better
// fit alone (register_pairs.cpp, horizontal_doubt).
struct OtherAnswers {
  std::vector<Eigen::Vector2d> shifts, landings;
  bool lost = false;  // a start did not converge
};

// A doubted answer's information, widened rather than removed (quality.doubt_widens): nothing
// along a direction GICP does not come back along from the other starts (a sand-wave crest, a
// flat's every direction), and the landings' scatter, given in `spread`, added to the covariance
// of the rest. Yaw out. A lost start leaves depth, roll and pitch only.
Information6 widened_by_doubt(Information6 information, const OtherAnswers& others, Eigen::Matrix2d& spread);

// `information` with the covariance `spread` (level frame, m²) added to what its own x, y block
// claims, and yaw out: an answer that may lie anywhere within `spread` of where it was found.
Information6 with_horizontal_spread(Information6 information, const Eigen::Matrix2d& spread);

// `information` with nothing known along the horizontal `direction` (level frame): the offset
// along it marginalised out, so that what is left holds whatever the offset there.
Information6 without_direction(const Information6& information, const Eigen::Vector2d& direction);

// Nothing known of the turn, marginalised as above: what x and y keep once yaw may be anything.
Information6 without_yaw(const Information6& information);

// The constraint as the pose graph's edge; registrations robust, the navigation's own not.
PoseGraphEdge graph_edge(const Constraint& c);

// Odometry constraints: consecutive submaps of one survey, DR relative pose, the graph's DR
// information (Table 1's by default); and each later survey's datum edge from node 0.
std::vector<Constraint> odometry_constraints(const std::vector<Eigen::Isometry3d>& dead_reckoning, const GraphConfig& graph);

}  // namespace bathyslam
