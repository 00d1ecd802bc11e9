#pragma once
// register (own GICP): Anderson acceleration of a fixed-point iteration x ← G(x) (Walker and Ni
// 2011; for ICP, Pavlov et al. 2018, "AA-ICP"). GICP's associate-then-minimise loop is such an
// iteration, and on gentle terrain it crawls: step after step points the same way, each a few
// centimetres, for tens of iterations. Anderson mixes the last few G(x) so that the residuals
// G(x) - x cancel, which jumps along the crawl instead.
#include <deque>

#include <Eigen/Core>

namespace bathyslam {

class AndersonAcceleration {
 public:
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  explicit AndersonAcceleration(int depth) : depth_(depth) {}

  // Where to evaluate G next, given x and G(x): G(x) itself until there is a history, then the
  // mix. Coordinates should be of comparable units (the solver uses metres for both).
  Vector6d next(const Vector6d& x, const Vector6d& g);
  void reset() { history_.clear(); }

 private:
  struct Step {
    Vector6d g, f;  // G(x) and G(x) - x
  };
  int depth_;
  std::deque<Step> history_;
};

}  // namespace bathyslam
