// Anderson acceleration (register/anderson.h) on fixed-point iterations whose answer is known.
#include "core/register/anderson.h"

#include <gtest/gtest.h>

namespace bathyslam {
namespace {

using Vector6d = AndersonAcceleration::Vector6d;

// Steps until |x - x*| < 1e-8 of x ← G(x) = x* + A (x - x*), a slow linear contraction (a crawl:
// eigenvalues up to 0.97), plainly or accelerated.
int steps_to_converge(bool accelerate) {
  Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Zero();
  a.diagonal() << 0.97, 0.9, 0.8, 0.5, 0.3, 0.1;
  a(0, 1) = 0.05;
  const Vector6d fixed = (Vector6d() << 1, -2, 0.5, 3, 0, -1).finished();
  AndersonAcceleration anderson(5);
  Vector6d x = Vector6d::Zero();
  for (int k = 1; k <= 2000; ++k) {
    const Vector6d g = fixed + a * (x - fixed);
    x = accelerate ? anderson.next(x, g) : g;
    if ((x - fixed).norm() < 1e-8) return k;
  }
  return 2000;
}

TEST(AndersonAcceleration, ReachesTheFixedPointOfACrawlInFarFewerSteps) {
  const int plain = steps_to_converge(false), accelerated = steps_to_converge(true);
  EXPECT_GT(plain, 500);
  EXPECT_LT(accelerated, 30) << "plain: " << plain;
}

TEST(AndersonAcceleration, FirstStepIsThePlainOneAndResetForgets) {
  AndersonAcceleration anderson(3);
  const Vector6d x = Vector6d::Zero(), g = Vector6d::Constant(1.0);
  EXPECT_EQ(anderson.next(x, g), g);
  anderson.next(g, Vector6d::Constant(1.5));
  anderson.reset();
  EXPECT_EQ(anderson.next(g, Vector6d::Constant(2.0)), Vector6d::Constant(2.0));
}

}  // namespace
}  // namespace bathyslam
