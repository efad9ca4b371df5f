// Ground truth: the relative velocities published with each image agree with the poses' derivatives.
#include <gtest/gtest.h>

#include <cmath>

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

// A rolled target (scenario target.roll_deg) turns about its port's axis: the port stays where the upright
// target has it, pointing the same way, and the face's up axis turns by the roll; the truth says so.
TEST(Simulation, ARolledTargetTurnsAboutItsPortAxis) {
  const std::string upright_text = docking_sim_test::scenarioText(1.5, 0.1, 170.0);
  std::string rolled_text = upright_text;
  rolled_text.replace(rolled_text.find("    motion:"), 0, "    roll_deg: 30.0\n");
  docking_sim::Simulation upright(docking_sim_test::files(docking_sim_test::writeTempFile("upright", upright_text)));
  docking_sim::Simulation rolled(docking_sim_test::files(docking_sim_test::writeTempFile("rolled", rolled_text)));
  const Eigen::Isometry3d a = upright.worldTPort(), b = rolled.worldTPort();
  EXPECT_LT((a.translation() - b.translation()).norm(), 1e-12);
  EXPECT_LT((a.linear().col(0) - b.linear().col(0)).norm(), 1e-12);
  EXPECT_NEAR(std::acos(a.linear().col(2).dot(b.linear().col(2))), 30.0 * M_PI / 180.0, 1e-9);
  const auto camera = docking_sim::RobotModel::kStereoLeft;
  const Eigen::AngleAxisd relative(upright.truthInCamera(camera).camera_T_port.linear().transpose() *
                                   rolled.truthInCamera(camera).camera_T_port.linear());
  EXPECT_NEAR(relative.angle(), 30.0 * M_PI / 180.0, 1e-9);
  EXPECT_NEAR(std::abs(relative.axis().x()), 1.0, 1e-9);  // about the port's x
  const std::string too_far = upright_text.substr(0, upright_text.find("    motion:")) + "    roll_deg: 200.0\n";
  EXPECT_THROW(docking_sim::loadScenario(docking_sim_test::writeTempFile("roll200", too_far)), std::exception);
}

// A tilted camera head (scenario chaser.camera_tilt) turns every camera rigidly about the reference camera's
// centre: that camera sees the port at the same distance, rolled about its optical axis by the head's roll;
// the stereo pair keeps its relative pose (its calibration still holds).
TEST(Simulation, ATiltedCameraHeadRollsTheViewAndKeepsTheStereoPair) {
  const std::string level_text = docking_sim_test::scenarioText(1.5, 0.1, 170.0);
  std::string tilted_text = level_text;
  const std::string chaser = "  chaser: {x_m: 0.0, y_m: 0.0, yaw_deg: 0.0}\n";
  tilted_text.replace(tilted_text.find(chaser), chaser.size(),
                      "  chaser:\n    x_m: 0.0\n    y_m: 0.0\n    yaw_deg: 0.0\n"
                      "    camera_tilt: {roll_deg: 20.0, pitch_deg: 0.0}\n");
  docking_sim::Simulation level(docking_sim_test::files(docking_sim_test::writeTempFile("level", level_text)));
  docking_sim::Simulation tilted(docking_sim_test::files(docking_sim_test::writeTempFile("tilted", tilted_text)));
  const auto left = docking_sim::RobotModel::kStereoLeft;
  const Eigen::Vector3d a = level.truthInCamera(left).camera_T_port.translation();
  const Eigen::Vector3d b = tilted.truthInCamera(left).camera_T_port.translation();
  EXPECT_NEAR(a.norm(), b.norm(), 1e-9);
  EXPECT_NEAR(a.z(), b.z(), 1e-9);  // the optical axis is the robot's forward axis: roll keeps the depth
  const Eigen::Vector2d a_image = a.head<2>().normalized(), b_image = b.head<2>().normalized();
  EXPECT_NEAR(std::acos(a_image.dot(b_image)), 20.0 * M_PI / 180.0, 1e-9);
  const auto right = docking_sim::RobotModel::kStereoRight;
  const Eigen::Isometry3d pair_level = level.baseTCamera(left).inverse() * level.baseTCamera(right);
  const Eigen::Isometry3d pair_tilted = tilted.baseTCamera(left).inverse() * tilted.baseTCamera(right);
  EXPECT_LT((pair_level.matrix() - pair_tilted.matrix()).norm(), 1e-12);
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
