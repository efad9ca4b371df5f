// The inner pattern against truth, on images drawn by the simulator's own renderer (docking_sim_core):
// config/target.yaml's target (face texture, inner pattern print) seen by the left camera from where
// the chaser is in the last 0.3 m of the final approach, down to contact (camera 8 cm from the face),
// sharp and defocused (a fixed-focus lens at 8 cm: a few px of blur), with sensor noise.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "docking_perception/mono/inner_pattern_detector.h"
#include "docking_perception/mono/mono_pose_estimator.h"
#include "docking_perception/mono/target_model.h"
#include "docking_sim/configs.h"
#include "docking_sim/renderer.h"
#include "docking_sim/scene.h"

namespace mono = docking_perception::mono;

namespace {

constexpr int kWidth = 640, kHeight = 480;
constexpr double kFocal = 550.0;

docking_sim::CameraCalibration pinhole() {
  docking_sim::CameraCalibration cal;
  cal.width = kWidth;
  cal.height = kHeight;
  cal.K = cv::Matx33d(kFocal, 0, 319.5, 0, kFocal, 239.5, 0, 0, 1);
  cal.D = {0, 0, 0, 0, 0};
  cal.P = cv::Matx34d(kFocal, 0, 319.5, 0, 0, kFocal, 239.5, 0, 0, 0, 1, 0);
  return cal;
}

mono::CameraIntrinsics intrinsics() {
  mono::CameraIntrinsics c;
  c.fx = c.fy = kFocal;
  c.cx = 319.5;
  c.cy = 239.5;
  c.width = kWidth;
  c.height = kHeight;
  return c;
}

// The left camera in frame `target` (the port) with the chaser's probe tip `tip_m` from the port,
// `lateral_m` to the viewer's right of the port axis and the chaser turned by `yaw_rad` (about z):
// robot.yaml puts the camera 0.08 m behind the tip and 0.05 m left of it.
Eigen::Isometry3d portTCamera(double tip_m, double lateral_m, double yaw_rad) {
  Eigen::Isometry3d port_T_base = Eigen::Isometry3d::Identity();
  // base x looks along -x of the port, base y = -y of the port (the chaser faces the face).
  port_T_base.linear() = Eigen::AngleAxisd(M_PI + yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  port_T_base.translation() = Eigen::Vector3d(tip_m, lateral_m, 0.0) +
                              port_T_base.linear() * Eigen::Vector3d(-0.18, 0.0, 0.0);
  Eigen::Isometry3d base_T_camera = Eigen::Isometry3d::Identity();
  Eigen::Matrix3d R;  // optical x = -base y, y = -base z, z = base x
  R.col(0) = -Eigen::Vector3d::UnitY();
  R.col(1) = -Eigen::Vector3d::UnitZ();
  R.col(2) = Eigen::Vector3d::UnitX();
  base_T_camera.linear() = R;
  base_T_camera.translation() = Eigen::Vector3d(0.10, 0.05, 0.0);  // at the port's height
  return port_T_base * base_T_camera;
}

struct Rendered {
  cv::Mat gray;
  Eigen::Isometry3d camera_T_target;
};

class InnerPatternSim : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string config = CONFIG_DIR;
    settings_ = docking_sim::loadSimSettings(config + "/sim.yaml");
    target_ = docking_sim::loadTargetModel(config + "/target.yaml");
    ASSERT_TRUE(target_.inner_pattern.present) << "config/target.yaml has no inner_pattern";
    model_ = mono::TargetModel::loadFromYaml(config + "/target.yaml");
    ASSERT_TRUE(model_.hasInnerPattern());
    lighting_ = settings_.lighting.at("nominal");
    scene_ = std::make_unique<docking_sim::Scene>(settings_, target_, lighting_, 7);
    scene_->update(Eigen::Isometry3d::Identity());
  }

  Rendered render(double tip_m, double lateral_m, double yaw_rad, double blur_sigma_px, uint64_t seed) {
    docking_sim::CameraEffects effects = settings_.visible_effects;
    effects.blur_sigma_px = blur_sigma_px;
    docking_sim::RenderOptions options;
    options.distortion = false;
    docking_sim::CameraRenderer renderer(pinhole(), docking_sim::Band::kVisible, effects, lighting_, seed, options);
    const Eigen::Isometry3d world_T_port = target_.robot_T_port;  // the target robot at the world origin
    const Eigen::Isometry3d port_T_camera = portTCamera(tip_m, lateral_m, yaw_rad);
    Rendered r;
    cv::cvtColor(renderer.render(*scene_, world_T_port * port_T_camera), r.gray, cv::COLOR_BGR2GRAY);
    r.camera_T_target = port_T_camera.inverse();
    return r;
  }

  docking_sim::SimSettings settings_;
  docking_sim::TargetModel target_;
  docking_sim::LightingScenario lighting_;
  std::unique_ptr<docking_sim::Scene> scene_;
  mono::TargetModel model_;
};

struct Errors {
  double position_m, angle_rad;
  Eigen::Matrix<double, 6, 1> normalized;  // error / sigma per axis
};

Errors errorsOf(const mono::PoseWithCovariance& pose, const Eigen::Isometry3d& truth) {
  Errors e;
  const Eigen::Vector3d dt = pose.translation - truth.translation();
  const Eigen::Vector3d dr = mono::rotationLog(pose.rotation * truth.linear().transpose());
  e.position_m = dt.norm();
  e.angle_rad = dr.norm();
  for (int i = 0; i < 3; ++i) {
    e.normalized(i) = dt(i) / std::sqrt(pose.covariance(i, i));
    e.normalized(i + 3) = dr(i) / std::sqrt(pose.covariance(i + 3, i + 3));
  }
  return e;
}

// Tip 0 (contact, camera 8 cm from the face) to 0.32 m (camera 0.4 m), on the axis and off it, sharp
// (0.6 px) and defocused (2.5 px: the C270's fixed focus at 8-15 cm), noise from the nominal scenario.
TEST_F(InnerPatternSim, PoseAgainstTruthToContact) {
  mono::InnerPatternDetector detector(model_.innerPattern());
  const std::vector<double> tips = {0.0, 0.01, 0.03, 0.06, 0.1, 0.15, 0.22, 0.32};
  const std::vector<std::array<double, 2>> offsets = {{0.0, 0.0}, {0.012, 0.03}, {-0.015, -0.04}};
  int views = 0, within_3_sigma = 0, axes = 0;
  uint64_t seed = 11;
  for (const double blur : {0.6, 2.5}) {
    for (const double tip : tips) {
      for (const auto& off : offsets) {
        const Rendered r = render(tip, off[0], off[1], blur, ++seed);
        const mono::InnerPatternResult result = detector.detect(r.gray, intrinsics(), nullptr);
        const double camera_range = 0.08 + tip;
        ASSERT_TRUE(result.valid) << "tip " << tip << " m, blur " << blur << " px, offset " << off[0] << " m "
                                  << off[1] << " rad: " << result.status;
        const Errors e = errorsOf(result.pose, r.camera_T_target);
        std::printf("tip %.2f m blur %.1f off %+.3f m %+.2f rad: %2d pts, rms %.2f px, %.2f mm, %.3f deg, %.1f ms\n",
                    tip, blur, off[0], off[1], result.pose_points, result.reprojection_rms_px, e.position_m * 1e3,
                    e.angle_rad * 180 / M_PI, result.processing_time_ms);
        // The last 6 cm (camera within 0.14 m of the face): 1 mm and 1 deg. Farther the 4 cm tag fixes
        // its position well but its tilt only to a few degrees (the covariance says so, checked below),
        // and a tilt error moves the port by a few mm: 3 % of the range.
        if (tip <= 0.06 + 1e-9) {
          EXPECT_LT(e.position_m, 0.001) << "tip " << tip << " blur " << blur;
          EXPECT_LT(e.angle_rad * 180.0 / M_PI, 1.0) << "tip " << tip << " blur " << blur;
        }
        EXPECT_LT(e.position_m, 0.03 * camera_range) << "tip " << tip << " blur " << blur;
        ++views;
        for (int i = 0; i < 6; ++i, ++axes) within_3_sigma += std::abs(e.normalized(i)) <= 3.0 ? 1 : 0;
      }
    }
  }
  std::printf("%d views, %d of %d axis errors within 3 sigma\n", views, within_3_sigma, axes);
  EXPECT_GE(within_3_sigma, static_cast<int>(0.95 * axes)) << "the covariance understates the errors";
}

// The mono pose node's estimator: along an approach from 0.45 m to contact, the face's pose hands over
// to the inner pattern's before the face is lost, and every valid pose is near the truth.
TEST_F(InnerPatternSim, EstimatorKeepsThePoseToContact) {
  mono::MonoPoseParams params;
  params.inner_pattern.enabled = true;
  mono::MonoPoseEstimator estimator(model_, intrinsics(), params);
  int inner = 0, valid = 0, frames = 0, within_3_sigma = 0, axes = 0;
  double stamp = 0.0;
  for (double tip = 0.37; tip >= -1e-9; tip -= 0.01, stamp += 0.2) {
    const Rendered r = render(tip, 0.004, 0.01, 1.0, 100 + frames);
    const mono::MonoPoseResult result = estimator.process(r.gray, stamp);
    ++frames;
    if (!result.valid) {
      ADD_FAILURE() << "tip " << tip << " m: no pose: " << result.status << " / " << result.inner_pattern_status;
      continue;
    }
    ++valid;
    inner += result.solver == mono::kInnerPatternSolverName ? 1 : 0;
    const Errors e = errorsOf(result.pose, r.camera_T_target);
    std::printf("tip %.2f m: %s, %.2f mm, %.2f deg, %.1f ms (face + tag)\n", tip, result.solver.c_str(),
                e.position_m * 1e3, e.angle_rad * 180 / M_PI, result.processing_time_ms);
    EXPECT_LT(e.position_m, 0.03 * (0.08 + tip)) << "tip " << tip << " (" << result.solver << ")";
    if (tip <= 0.04) {
      EXPECT_LT(e.angle_rad * 180.0 / M_PI, 1.0) << "tip " << tip << " (" << result.solver << ")";
    }
    for (int i = 0; i < 6; ++i, ++axes) within_3_sigma += std::abs(e.normalized(i)) <= 3.0 ? 1 : 0;
  }
  std::printf("%d frames, %d valid, %d from the inner pattern; %d of %d axis errors within 3 sigma\n", frames,
              valid, inner, within_3_sigma, axes);
  EXPECT_GT(inner, 0);
  EXPECT_GE(within_3_sigma, static_cast<int>(0.95 * axes));
}

// Near contact the face no longer fits the image: once its search fails while the tag gives the pose, it
// is searched again only every kFaceRetryEvery-th image, and the tag's pose stands in between (the failing
// face search was the chain's worst latency).
TEST_F(InnerPatternSim, FaceSearchedEveryNthImageOnceTheTagCarriesThePose) {
  constexpr int every = mono::MonoPoseEstimator::kFaceRetryEvery;
  mono::MonoPoseParams params;
  params.inner_pattern.enabled = true;
  mono::MonoPoseEstimator estimator(model_, intrinsics(), params);
  int skipped = 0, from_tag = 0, frames = 0;
  double stamp = 0.0;
  // From 0.3 m of tip (the face's pose) to contact at 5 mm a frame (15 Hz): inside ~0.17 m of camera
  // range the face fails.
  double cpu_ms = 0.0;
  for (double tip = 0.30; tip >= -1e-9; tip -= 0.005, stamp += 1.0 / 15.0) {
    const Rendered r = render(tip, 0.004, 0.01, 1.0, 300 + frames);
    const mono::MonoPoseResult result = estimator.process(r.gray, stamp);
    ++frames;
    ASSERT_TRUE(result.valid) << "tip " << tip << ": " << result.status << " / " << result.inner_pattern_status;
    EXPECT_LT(errorsOf(result.pose, r.camera_T_target).position_m, 0.03 * (0.08 + tip)) << "tip " << tip;
    skipped += result.face_search_skipped ? 1 : 0;
    from_tag += result.solver == mono::kInnerPatternSolverName ? 1 : 0;
    cpu_ms += result.processing_time_ms;
  }
  std::printf("face searched every %d images: %d frames, %d from the tag, %d face searches skipped, %.1f ms CPU a frame\n",
              every, frames, from_tag, skipped, cpu_ms / frames);
  // Once the face fails for good, four of every five images skip it.
  EXPECT_GE(skipped, (from_tag - every) * (every - 1) / every);
  EXPECT_LT(skipped, from_tag);
  // 17 of 61 with the shipped configuration.
  EXPECT_GT(from_tag, 10) << "the approach must reach where the face fails";
}

// Without the hook (inner_pattern_enabled false) the face alone loses the target near contact: the
// situation the inner pattern is for (if this ever passes, the blind zone moved and the test should too).
TEST_F(InnerPatternSim, FaceAloneIsLostAtContact) {
  mono::MonoPoseParams params;
  params.inner_pattern.enabled = false;
  mono::MonoPoseEstimator estimator(model_, intrinsics(), params);
  const Rendered r = render(0.0, 0.0, 0.0, 1.0, 5);
  const mono::MonoPoseResult result = estimator.process(r.gray, 0.0);
  if (result.valid) {
    const Errors e = errorsOf(result.pose, r.camera_T_target);
    std::printf("face at contact: valid, %.1f mm, %.2f deg off\n", e.position_m * 1e3, e.angle_rad * 180 / M_PI);
  }
  EXPECT_FALSE(result.valid) << "the face alone gave a pose at contact";
}

// A single tag image decides IPPE's two poses only near contact: at 0.25-0.45 m the 4 cm tag's other
// pose, 5-13 deg away, fits nearly as well. The fit's covariance alone (the detector's) claimed such
// poses 10-13 deg off with 3 deg sigmas; the estimator's covariance model (modelPnpCovariance, as for
// the face) adds the undecided alternative, so no claimed orientation is that far off and the errors
// stay within 3 sigma. No history here: every view is a first pose (the worst case). With the fit's
// covariance alone, these 60 views gave 21 claimed orientations, two of them 12 deg off.
TEST_F(InnerPatternSim, AnUndecidedTagPoseClaimsNoOrientationItCannotBack) {
  mono::InnerPatternDetector detector(model_.innerPattern());
  mono::ConsistencyParams consistency;
  consistency.max_ambiguity_deg = 8.0;  // config/mono_pose_visible.yaml
  int views = 0, claimed = 0, claimed_far_off = 0, axes = 0, within_3_sigma = 0;
  uint64_t seed = 1000;
  for (const double blur : {1.0, 2.0}) {
    for (double tip = 0.18; tip <= 0.385; tip += 0.04) {
      for (const double yaw : {-0.25, -0.1, 0.0, 0.1, 0.25}) {
        const Rendered r = render(tip, 0.0, yaw, blur, ++seed);
        mono::InnerPatternResult result = detector.detect(r.gray, intrinsics(), nullptr);
        ASSERT_TRUE(result.valid) << "tip " << tip << " yaw " << yaw << ": " << result.status;
        const double ambiguity_deg = mono::modelPnpCovariance(
            intrinsics(), result.pnp, mono::OrientationHistory(), result.model_points, result.reprojection_rms_px,
            result.reprojection_rms_px, mono::InnerPatternDetector::kMinPixelSigmaPx, 0.0, consistency, &result.pose);
        std::string note;
        const bool claim = ambiguity_deg <= consistency.max_ambiguity_deg &&
                           mono::orientationClaimed(result.pose, consistency, &note);
        const Errors e = errorsOf(result.pose, r.camera_T_target);
        ++views;
        claimed += claim ? 1 : 0;
        if (claim && e.angle_rad * 180.0 / M_PI > 10.0) {
          ++claimed_far_off;
          std::printf("tip %.2f yaw %+.2f blur %.1f: claimed, %.1f deg off\n", tip, yaw, blur, e.angle_rad * 180 / M_PI);
        }
        for (int i = 0; i < 6; ++i, ++axes) within_3_sigma += std::abs(e.normalized(i)) <= 3.0 ? 1 : 0;
      }
    }
  }
  std::printf("%d views, %d orientations claimed, %d of them > 10 deg off; %d of %d axis errors within 3 sigma\n", views,
              claimed, claimed_far_off, within_3_sigma, axes);
  EXPECT_EQ(claimed_far_off, 0);
  EXPECT_GE(within_3_sigma, static_cast<int>(0.95 * axes)) << "the covariance understates the errors";
}

}  // namespace
