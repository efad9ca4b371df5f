#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "omni_base/kinematics.h"

using omni_base::OmniKinematics;
using omni_base::Twist2D;
using omni_base::WheelLayout;

namespace {

double deg(double d) { return d * M_PI / 180.0; }

WheelLayout paperLayout() { return WheelLayout{{0.0, deg(120), deg(240)}, 0.10, 0.024}; }

}  // namespace

TEST(OmniKinematics, ForwardOfInverseIsIdentityForRandomTwistsAndLayouts) {
  const std::vector<WheelLayout> layouts = {
      paperLayout(),
      WheelLayout{{deg(90), deg(210), deg(330)}, 0.15, 0.03},          // wheels rotated by 90 deg
      WheelLayout{{deg(45), deg(135), deg(225), deg(315)}, 0.2, 0.05},  // four-wheel X layout
      WheelLayout{{deg(0), deg(100), deg(250)}, 0.12, 0.024},           // uneven spacing
      WheelLayout{{deg(0), deg(72), deg(144), deg(216), deg(288)}, 0.3, 0.04},
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> v(-1.0, 1.0);
  for (const auto& layout : layouts) {
    const OmniKinematics k(layout);
    for (int i = 0; i < 200; ++i) {
      const Twist2D t{v(rng), v(rng), 3.0 * v(rng)};
      const auto wheels = k.inverse(t);
      ASSERT_EQ(wheels.size(), layout.drive_angles_rad.size());
      const Twist2D back = k.forward(wheels);
      EXPECT_NEAR(back.vx, t.vx, 1e-9);
      EXPECT_NEAR(back.vy, t.vy, 1e-9);
      EXPECT_NEAR(back.wz, t.wz, 1e-9);
    }
  }
}

TEST(OmniKinematics, WheelSignsForPureMotions) {
  const OmniKinematics k(paperLayout());
  const double r = 0.024;
  const double L = 0.10;
  // Pure +x: wheel 0 drives along x (full speed forward), wheels 1 and 2 at cos(120) = -1/2.
  auto w = k.inverse(Twist2D{0.24, 0.0, 0.0});
  EXPECT_NEAR(w[0], 0.24 / r, 1e-9);
  EXPECT_NEAR(w[1], -0.12 / r, 1e-9);
  EXPECT_NEAR(w[2], -0.12 / r, 1e-9);
  // Pure +y: wheel 0 does not turn, wheel 1 forward (sin 120 > 0), wheel 2 backward.
  w = k.inverse(Twist2D{0.0, 0.24, 0.0});
  EXPECT_NEAR(w[0], 0.0, 1e-9);
  EXPECT_GT(w[1], 0.0);
  EXPECT_LT(w[2], 0.0);
  EXPECT_NEAR(w[1], 0.24 * std::sqrt(3.0) / 2.0 / r, 1e-9);
  // Pure +yaw: every wheel turns forward at L * wz / r.
  w = k.inverse(Twist2D{0.0, 0.0, 1.0});
  for (double wi : w) EXPECT_NEAR(wi, L / r, 1e-9);
}

TEST(OmniKinematics, RejectsLayoutsThatCannotMoveInThePlane) {
  EXPECT_THROW(OmniKinematics(WheelLayout{{0.0, deg(120)}, 0.1, 0.024}), std::invalid_argument);
  EXPECT_THROW(OmniKinematics(WheelLayout{{0.0, 0.0, M_PI}, 0.1, 0.024}), std::invalid_argument);
  EXPECT_THROW(OmniKinematics(WheelLayout{{0.0, deg(120), deg(240)}, 0.0, 0.024}), std::invalid_argument);
  EXPECT_THROW(OmniKinematics(WheelLayout{{0.0, deg(120), deg(240)}, 0.1, -1.0}), std::invalid_argument);
  EXPECT_THROW(OmniKinematics(WheelLayout{{0.0, NAN, deg(240)}, 0.1, 0.024}), std::invalid_argument);
}

TEST(OmniKinematics, ForwardRejectsWrongWheelCount) {
  const OmniKinematics k(paperLayout());
  EXPECT_THROW(k.forward({1.0, 2.0}), std::invalid_argument);
}
