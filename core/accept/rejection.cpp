#include "core/accept/rejection.h"

#include <array>
#include <stdexcept>
#include <utility>

namespace bathyslam {
namespace {

constexpr std::array<std::pair<RejectionKind, const char*>, 13> kNames{{
    {RejectionKind::kNone, "none"},
    {RejectionKind::kLoopWithoutFeatures, "loop closure without features"},
    {RejectionKind::kNoOverlap, "no overlapping points"},
    {RejectionKind::kNotConverged, "GICP did not converge"},
    {RejectionKind::kInlierRatio, "inlier ratio"},
    {RejectionKind::kOverlapMse, "overlap MSE"},
    {RejectionKind::kOverlapPoints, "overlap points"},
    {RejectionKind::kCompetitor, "ambiguous: competing alignment"},
    {RejectionKind::kNotUnique, "ambiguous: terrain not unique"},
    {RejectionKind::kTranslation, "translation from dead reckoning"},
    {RejectionKind::kImplausible, "implausible against dead reckoning"},
    {RejectionKind::kInconsistent, "inconsistent with the other registrations"},
    {RejectionKind::kSafetyNet, "safety net"},
}};

}  // namespace

std::string to_string(RejectionKind kind) {
  for (const auto& [k, name] : kNames) {
    if (k == kind) return name;
  }
  return "?";
}

RejectionKind parse_rejection_kind(const std::string& text) {
  for (const auto& [k, name] : kNames) {
    if (text == name) return k;
  }
  throw std::invalid_argument("rejection kind '" + text + "' is not known to this version of the core");
}

}  // namespace bathyslam
