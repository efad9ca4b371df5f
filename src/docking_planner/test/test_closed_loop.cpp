// Closed loop in a kinematic world: an omni chaser that integrates the commanded twist perfectly,
// a target robot that turns in place with the docking port 0.15 m ahead of its centre, and a
// "perfect" estimator that still behaves like the cameras: it sees the port only inside the
// camera's field of view, gives the port's orientation only within 2 m and when the face is turned
// less than 75 deg from the camera (position only otherwise, like the disparity detector), loses the
// target when the camera is closer than 0.25 m to it, and delivers each estimate 0.1 s late. One
// variant adds Gaussian noise (fixed seed) to the estimates.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <deque>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "docking_planner/docking_planner.h"
#include "shipped_config.h"

using namespace docking_planner;

namespace {

constexpr double kDt = 0.05;              // planner cycle, 20 Hz
constexpr int kSubsteps = 10;             // integration steps per cycle
constexpr double kPortOffset = 0.15;      // port ahead of the target robot's centre
constexpr double kCameraX = 0.10;         // camera on base_link x
constexpr double kMonoRange = 2.0;        // orientation only within this range
constexpr double kFaceVisibleAngle = 75.0 * M_PI / 180.0;
constexpr double kBlindCameraRange = 0.25;
constexpr int kLatencyCycles = 2;         // estimates arrive 0.1 s after their stamp
constexpr int kEstimateEvery = 2;         // estimator at 10 Hz

struct Scenario {
  std::string name;
  double start_direction_rad;  // where the chaser starts, seen from the port
  double port_turn_rad;        // port axis relative to the line port -> chaser at t = 0
  double chaser_heading_off_rad;  // chaser heading relative to facing the port
  double target_rate_radps;
  double position_noise_m{0.0};   // per axis, times (1 + range in m): grows with range like stereo
  double yaw_noise_rad{0.0};
  Vec2 target_velocity{0.0, 0.0};  // drift of the target robot's centre, m/s
};

struct World {
  Pose2D chaser;
  Vec2 target_centre{0.0, 0.0};
  double target_yaw0{0.0};
  double target_rate{0.0};
  Vec2 target_velocity{0.0, 0.0};

  Pose2D port(double t) const {
    const double yaw = target_yaw0 + target_rate * t;
    const Vec2 centre = target_centre + target_velocity * t;
    return Pose2D{centre.x() + kPortOffset * std::cos(yaw), centre.y() + kPortOffset * std::sin(yaw), wrapAngle(yaw)};
  }
};

struct Result {
  bool docked{false};
  double time_s{0.0};
  double tip_error_m{0.0};
  double yaw_error_rad{0.0};
  std::vector<DockingPhase> states;
  std::string last_reason;
  bool used_odometry_finish{false};
  double max_speed{0.0};
  double max_yaw_rate{0.0};
  double min_port_distance_outside_final{1e9};
};

// What the camera would report at time t, or invalid.
TargetObservation observe(const World& w, double t, const Scenario& s, double config_fov, std::mt19937& rng) {
  TargetObservation o;
  o.stamp_s = t;
  const Pose2D port = w.port(t);
  const Vec2 camera = w.chaser.position() + kCameraX * unitAt(w.chaser.yaw);
  const Vec2 to_port = port.position() - camera;
  const double bearing = wrapAngle(std::atan2(to_port.y(), to_port.x()) - w.chaser.yaw);
  if (std::abs(bearing) > config_fov || to_port.norm() < kBlindCameraRange) {
    o.valid = false;
    o.status = "not in view";
    return o;
  }
  o.valid = true;
  o.pose = port;
  o.source = to_port.norm() < kMonoRange ? 1 : 0;
  const double face_angle = wrapAngle(std::atan2(-to_port.y(), -to_port.x()) - port.yaw);
  o.orientation_valid = to_port.norm() < kMonoRange && std::abs(face_angle) < kFaceVisibleAngle;
  std::normal_distribution<double> unit(0.0, 1.0);
  const double sigma_p = s.position_noise_m * (1.0 + to_port.norm());
  o.pose.x += sigma_p * unit(rng);
  o.pose.y += sigma_p * unit(rng);
  o.pose.yaw = wrapAngle(o.pose.yaw + s.yaw_noise_rad * unit(rng));
  return o;
}

// PLANNER_TRACE=<file>: every cycle's output of every scenario appended to <file> (state, command, goal
// distance, reason; full precision), so that a restructuring of the planner can be shown to change no
// output (compare the files written before and after).
void trace(const std::string& scenario, double t, const PlannerOutput& out) {
  const char* path = std::getenv("PLANNER_TRACE");
  if (path == nullptr || *path == '\0') return;
  std::ofstream file(path, std::ios::app);
  file << std::setprecision(17) << scenario << ' ' << t << ' ' << stateName(out.state) << ' ' << out.command.vx << ' '
       << out.command.vy << ' ' << out.command.wz << ' ' << out.goal_distance_m << ' ' << out.on_odometry << ' '
       << out.reason << '\n';
}

Result run(const Scenario& s) {
  PlannerConfig config = shippedConfig();
  DockingPlanner planner{config, shippedProbeX()};
  if (!planner.start(0.0, DockingLimits{}, nullptr)) return Result{};
  World w;
  w.target_rate = s.target_rate_radps;
  w.target_velocity = s.target_velocity;
  // Port at t = 0 near the origin; the chaser 4 m from it.
  w.target_yaw0 = s.start_direction_rad + s.port_turn_rad;
  const Pose2D port0 = w.port(0.0);
  const Vec2 start = port0.position() + 4.0 * unitAt(s.start_direction_rad);
  w.chaser = Pose2D{start.x(), start.y(), wrapAngle(s.start_direction_rad + M_PI + s.chaser_heading_off_rad)};

  Result r;
  std::deque<TargetObservation> in_flight;
  std::mt19937 rng(42);  // fixed seed: the same noise every run
  const double fov = config.law.camera_half_fov_rad;
  for (int cycle = 0; cycle < static_cast<int>(240.0 / kDt); ++cycle) {
    const double t = cycle * kDt;
    if (cycle % kEstimateEvery == 0) in_flight.push_back(observe(w, t, s, fov, rng));
    while (!in_flight.empty() && in_flight.front().stamp_s <= t - kLatencyCycles * kDt + 1e-9) {
      planner.addObservation(in_flight.front());
      in_flight.pop_front();
    }
    ChaserOdometry odom;
    odom.stamp_s = t;
    odom.pose = w.chaser;
    planner.notePerception(t, false);
    const PlannerOutput out = planner.update(t, odom);
    trace(s.name, t, out);
    if (r.states.empty() || r.states.back() != out.state) r.states.push_back(out.state);
    r.last_reason = out.reason;
    r.used_odometry_finish = r.used_odometry_finish || out.on_odometry;
    r.max_speed = std::max(r.max_speed, std::hypot(out.command.vx, out.command.vy));
    r.max_yaw_rate = std::max(r.max_yaw_rate, std::abs(out.command.wz));
    if (out.state != DockingPhase::kFinal && out.state != DockingPhase::kDocked) {
      r.min_port_distance_outside_final =
          std::min(r.min_port_distance_outside_final, (w.chaser.position() - w.port(t).position()).norm());
    }
    if (out.state == DockingPhase::kDocked) {
      const Pose2D port = w.port(t);
      const Vec2 tip = w.chaser.position() + shippedProbeX() * unitAt(w.chaser.yaw);
      r.docked = true;
      r.time_s = t;
      r.tip_error_m = (tip - port.position()).norm();
      r.yaw_error_rad = wrapAngle(w.chaser.yaw - (port.yaw + M_PI));
      return r;
    }
    // Perfect integration of the body twist over the cycle.
    const double h = kDt / kSubsteps;
    for (int i = 0; i < kSubsteps; ++i) {
      const double yaw_mid = w.chaser.yaw + 0.5 * out.command.wz * h;
      w.chaser.x += (std::cos(yaw_mid) * out.command.vx - std::sin(yaw_mid) * out.command.vy) * h;
      w.chaser.y += (std::sin(yaw_mid) * out.command.vx + std::cos(yaw_mid) * out.command.vy) * h;
      w.chaser.yaw = wrapAngle(w.chaser.yaw + out.command.wz * h);
    }
  }
  return r;
}

std::string describe(const Result& r) {
  std::ostringstream os;
  os << "states:";
  for (DockingPhase p : r.states) os << " " << stateName(p);
  os << " | last reason: " << r.last_reason << " | t=" << r.time_s << " s tip=" << r.tip_error_m * 1000.0
     << " mm yaw=" << r.yaw_error_rad * 180.0 / M_PI << " deg";
  return os.str();
}

bool visited(const Result& r, DockingPhase p) {
  for (DockingPhase s : r.states)
    if (s == p) return true;
  return false;
}

void expectDocked(const Scenario& s, bool expect_no_abort, double tip_tolerance_m = 0.01) {
  SCOPED_TRACE(s.name);
  const Result r = run(s);
  std::cout << "[ closed loop ] " << s.name << ": " << describe(r) << "\n";
  ASSERT_TRUE(r.docked) << describe(r);
  EXPECT_LE(r.tip_error_m, tip_tolerance_m) << describe(r);         // goal: 1 cm
  EXPECT_LE(std::abs(r.yaw_error_rad), M_PI / 180.0) << describe(r);  // goal: 1 deg
  EXPECT_TRUE(visited(r, DockingPhase::kApproach)) << describe(r);
  EXPECT_TRUE(visited(r, DockingPhase::kFinal)) << describe(r);
  // The cameras go blind at 0.25 m: the last centimetres are always on odometry.
  EXPECT_TRUE(r.used_odometry_finish) << describe(r);
  // Within what omni_base accepts (0.4 m/s, 1.5 rad/s).
  EXPECT_LE(r.max_speed, 0.4 + 1e-9);
  EXPECT_LE(r.max_yaw_rate, 1.5 + 1e-9);
  // Outside FINAL the chaser stays out of the safe circle (minus its tolerance, plus some slack for
  // the circle moving with a rotating target).
  EXPECT_GE(r.min_port_distance_outside_final, 0.6 - 0.08) << describe(r);
  if (expect_no_abort) {
    EXPECT_FALSE(visited(r, DockingPhase::kAbort)) << describe(r);
  }
}

constexpr double kDeg = M_PI / 180.0;
constexpr double kThreeDegPerS = 3.0 * kDeg;

}  // namespace

TEST(ClosedLoop, StillTargetPortFacingTheChaser) {
  expectDocked({"still, facing", 0.0, 0.0, 0.0, 0.0}, true);
}

TEST(ClosedLoop, StillTargetPortTurnedAway) {
  expectDocked({"still, port turned 60 deg", 0.7, 60.0 * kDeg, 0.0, 0.0}, true);
  expectDocked({"still, port turned -70 deg", -2.0, -70.0 * kDeg, 0.0, 0.0}, true);
}

TEST(ClosedLoop, StillTargetPortFacingAwayNeedsTheOrbit) {
  // The face cannot be seen from the start or from the circle on the line of sight: the chaser
  // reaches the circle on position only, then orbits until the face is in view.
  expectDocked({"still, port turned 120 deg", 2.5, 120.0 * kDeg, 0.0, 0.0}, true);
}

TEST(ClosedLoop, StillTargetOutOfViewAtStartIsFoundBySearching) {
  expectDocked({"still, chaser looking away", 1.0, 30.0 * kDeg, 100.0 * kDeg, 0.0}, true);
}

TEST(ClosedLoop, RotatingTargetThreeDegPerSecond) {
  expectDocked({"rotating +3 deg/s, port turned 45 deg", 0.0, 45.0 * kDeg, 0.0, kThreeDegPerS}, false);
  expectDocked({"rotating -3 deg/s, port facing", 1.5, 0.0, 0.0, -kThreeDegPerS}, false);
  expectDocked({"rotating +3 deg/s, port turned -60 deg, heading off 20 deg", -1.0, -60.0 * kDeg, 20.0 * kDeg,
                kThreeDegPerS},
               false);
}

TEST(ClosedLoop, NoisyEstimates) {
  Scenario still{"still, noisy (2 mm, 0.3 deg)", 0.7, 50.0 * kDeg, 0.0, 0.0};
  still.position_noise_m = 0.002;
  still.yaw_noise_rad = 0.3 * kDeg;
  expectDocked(still, false);
  Scenario rotating{"rotating 3 deg/s, noisy (2 mm, 0.3 deg)", -0.5, -40.0 * kDeg, 0.0, kThreeDegPerS};
  rotating.position_noise_m = 0.002;
  rotating.yaw_noise_rad = 0.3 * kDeg;
  expectDocked(rotating, false);
}

TEST(ClosedLoop, DriftingTargetIsAKnownLimit) {
  // The track models no drift (README "Known limits"): the blind finish does not follow a drifting target
  // (if this starts passing the goal, a drift model may be worth its keys).
  Scenario drifting{"drifting 3 cm/s", 0.3, 30.0 * kDeg, 0.0, 2.0 * kDeg};
  drifting.target_velocity = Vec2(0.0, 0.03);
  const Result r = run(drifting);
  std::cout << "[ closed loop ] " << drifting.name << ": " << describe(r) << "\n";
  ASSERT_TRUE(r.docked) << describe(r);  // it still ends in DOCKED against its own (held) estimate
  EXPECT_GT(r.tip_error_m, 0.01) << describe(r);
}
