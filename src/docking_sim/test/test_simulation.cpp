// Ground truth: the relative velocities published with each image agree with the poses' derivatives.
#include <gtest/gtest.h>

#include "docking_sim/simulation.h"
#include "omni_base/kinematics.h"
#include "test_helpers.h"

using docking_sim::RobotModel;

TEST(Simulation, TruthVelocityIsTheDerivativeOfTheTruthPose) {
  // A rotating target and a chaser that drives and turns: every term of the relative motion is live.
  const auto path = docking_sim_test::writeTempFile(
      "truth", docking_sim_test::scenarioText(2.0, 0.5, 150.0, 6.0));
  docking_sim::Simulation sim(docking_sim_test::files(path));
  const omni_base::OmniKinematics kin(docking_sim::loadOmniBaseModel(docking_sim_test::configDir() + "/omni_base.yaml").layout);
  const auto wheels = kin.inverse({0.15, 0.05, 0.4});
  for (int k = 0; k < 200; ++k) {  // 1 s: the motors reach their set-points
    sim.wheelCommand(true, wheels);
    sim.advance(0.005);
  }
  for (int cam : {RobotModel::kStereoLeft, RobotModel::kIr}) {
    const auto truth = sim.truthInCamera(cam);
    const double h = 1e-4;
    sim.wheelCommand(true, wheels);
    sim.advance(h);
    const auto later = sim.truthInCamera(cam);
    const Eigen::Vector3d velocity = (later.camera_T_port.translation() - truth.camera_T_port.translation()) / h;
    EXPECT_LT((velocity - truth.linear_m_s).norm(), 2e-3) << "camera " << cam;
    // Angular: R_later = R_now * exp(w_body h); in camera axes w = log(R_later R_now^T) / h.
    const Eigen::AngleAxisd delta(later.camera_T_port.linear() * truth.camera_T_port.linear().transpose());
    const Eigen::Vector3d omega = delta.axis() * delta.angle() / h;
    EXPECT_LT((omega - truth.angular_rad_s).norm(), 2e-3) << "camera " << cam;
    EXPECT_GT(truth.linear_m_s.norm(), 0.05);
    EXPECT_GT(truth.angular_rad_s.norm(), 0.1);
  }
}

TEST(Simulation, TargetFollowsItsScriptedMotion) {
  const auto path = docking_sim_test::writeTempFile(
      "motion", "scenario:\n  duration_s: 10\n  seed: 1\n  lighting: nominal\n"
                "  chaser: {x_m: 0.0, y_m: 0.0, yaw_deg: 0.0}\n"
                "  target:\n    x_m: 3.0\n    y_m: -1.0\n    yaw_deg: 90.0\n"
                "    motion: {yaw_rate_deg_s: 10.0, velocity_m_s: [0.05, 0.1]}\n");
  docking_sim::Simulation sim(docking_sim_test::files(path));
  for (int k = 0; k < 400; ++k) sim.advance(0.005);  // 2 s
  const Eigen::Isometry3d t = sim.worldTTargetRobot();
  EXPECT_NEAR(t.translation().x(), 3.1, 1e-9);
  EXPECT_NEAR(t.translation().y(), -0.8, 1e-9);
  EXPECT_NEAR(std::atan2(t.linear()(1, 0), t.linear()(0, 0)), (90.0 + 20.0) * M_PI / 180.0, 1e-9);
  // The port sits on the mount, at the configured height.
  EXPECT_NEAR(sim.worldTPort().translation().z(), sim.target().robot_T_port.translation().z(), 1e-12);
}
