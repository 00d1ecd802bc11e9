#pragma once
// Why a registration is not a graph edge, as a kind (for counting and storing) and the numbers
// behind it (for people).
#include <string>

namespace bathyslam {

// Why a registration is not an edge: one of the registration tests, the DR gate, or the back
// end (it was accepted, then left out).
enum class RejectionKind {
  kNone,
  kLoopWithoutFeatures,  // a loop closure on the direct path
  kNoOverlap,
  kNotConverged,
  kInlierRatio,
  kOverlapMse,
  kOverlapPoints,
  kCompetitor,           // RANSAC found a distinct alternative nearly as good
  kNotUnique,            // the terrain fits another offset nearly as well
  kTranslation,          // moved too far from dead reckoning
  kImplausible,          // the DR gate
  kInconsistent,         // the back end's pairwise consistency
  kSafetyNet,            // dropped by the safety net, or dead reckoning published
};
// Stable short names ("inlier ratio"): report keys and the stored column.
std::string to_string(RejectionKind kind);
RejectionKind parse_rejection_kind(const std::string& text);  // throws std::invalid_argument

struct Rejection {
  RejectionKind kind = RejectionKind::kNone;
  std::string detail;  // the numbers behind it, for people
  bool rejected() const { return kind != RejectionKind::kNone; }
  // "inlier ratio: 0.21 < 0.25"; empty when not rejected.
  std::string text() const {
    if (!rejected()) return "";
    return detail.empty() ? to_string(kind) : to_string(kind) + ": " + detail;
  }
};

}  // namespace bathyslam
