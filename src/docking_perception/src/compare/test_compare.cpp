// Tests of the comparison tools: the sequence reader, the shipped mono settings they read, the tag texture and
// AprilTag's pose carried into frame `target` on synthetic views with a known answer.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <utility>
#include <vector>

#include <set>
#include <yaml-cpp/yaml.h>

#include "docking_perception/mono/mono_pose_estimator.h"
#include "docking_settings/yaml_loader.h"
#include "error_stats.h"
#include "sequence_io.h"
#include "synthetic_tag_view.h"
#include "tag_pose.h"

namespace cmp = docking_perception::compare;
namespace mono = docking_perception::mono;

namespace {

// A scratch folder under the system's temporary directory, removed at the end of the test.
struct TempFolder {
  explicit TempFolder(const std::string& name)
      : path((std::filesystem::temp_directory_path() / ("test_compare_" + name + "_" + std::to_string(::getpid())))
                 .string()) {
    std::filesystem::create_directories(path);
  }
  ~TempFolder() { std::filesystem::remove_all(path); }
  std::string path;
};

// A face turned towards the camera (x_target = -z_camera), yawed by yaw_rad about the face's vertical.
Eigen::Isometry3d facePose(const Eigen::Vector3d& position, double yaw_rad) {
  Eigen::Matrix3d facing;
  facing << 0, 1, 0, 0, 0, -1, -1, 0, 0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = facing * Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = position;
  return T;
}

mono::CameraIntrinsics camera640() {
  mono::CameraIntrinsics c;
  c.fx = c.fy = 550.0;
  c.cx = 319.5;
  c.cy = 239.5;
  c.width = 640;
  c.height = 480;
  return c;
}

const char* kSequenceJson = R"({
  "scenario": "test", "target": "t.yaml", "camera": "stereo_left", "rectification": "none",
  "intrinsics": {"width": 640, "height": 480, "fx": 550, "fy": 551, "cx": 319.5, "cy": 239.5},
  "dt_s": 0.0333333333,
  "frames": [
    {"index": 0, "stamp_s": 1.5, "image": "left_rect_0000.png", "position_m": [0.1, -0.2, 1.25],
     "rotation": [0, 1, 0, 0, 0, -1, -1, 0, 0], "quaternion_xyzw": [0, 0, 0, 1],
     "linear_m_s": [0.01, 0, -0.002], "angular_rad_s": [0, -0.05, 0]},
    {"index": 1, "stamp_s": 1.5333333333, "image": "left_rect_0001.png", "position_m": [0.1, -0.2, 1.24],
     "rotation": [1, 0, 0, 0, 1, 0, 0, 0, 1], "quaternion_xyzw": [0, 0, 0, 1],
     "linear_m_s": [0, 0, 0], "angular_rad_s": [0, 0, 0]}
  ]
})";

}  // namespace

TEST(SequenceReader, ReadsTheFormatSimRenderWrites) {
  const TempFolder temp("seq");
  const std::string& folder = temp.path;
  std::ofstream(folder + "/sequence.json") << kSequenceJson;
  const cmp::Sequence seq = cmp::readSequence(folder);
  EXPECT_EQ(seq.scenario, "test");
  EXPECT_DOUBLE_EQ(seq.camera.fy, 551.0);
  EXPECT_EQ(seq.camera.width, 640);
  ASSERT_EQ(seq.frames.size(), 2u);
  EXPECT_DOUBLE_EQ(seq.frames[0].stamp_s, 1.5);
  EXPECT_EQ(seq.frames[1].image_path, folder + "/left_rect_0001.png");
  EXPECT_DOUBLE_EQ(seq.frames[0].position_m.z(), 1.25);
  EXPECT_DOUBLE_EQ(seq.frames[0].rotation(2, 0), -1.0);  // row-major
  EXPECT_DOUBLE_EQ(seq.frames[0].rotation(0, 1), 1.0);
  EXPECT_DOUBLE_EQ(seq.frames[0].angular_rad_s.y(), -0.05);
  std::string reason;
  EXPECT_TRUE(cmp::sameTrajectory(seq, seq, 1e-9, 1e-9, &reason));
  cmp::Sequence moved = seq;
  moved.frames[1].position_m.x() += 1e-3;
  EXPECT_FALSE(cmp::sameTrajectory(seq, moved, 1e-6, 1e-6, &reason));
  EXPECT_NE(reason.find("frame 1"), std::string::npos);
}

TEST(SequenceReader, NamesTheBadField) {
  const TempFolder temp("bad");
  const std::string& folder = temp.path;
  std::string text = kSequenceJson;
  text.replace(text.find("[1, 0, 0, 0, 1, 0, 0, 0, 1]"), 27, "[1, 0, 0, 0, 1, 0, 0, 0, 2]");
  std::ofstream(folder + "/sequence.json") << text;
  try {
    cmp::readSequence(folder);
    FAIL() << "a scaled rotation was accepted";
  } catch (const cmp::SequenceError& e) {
    EXPECT_NE(std::string(e.what()).find("frames[1].rotation"), std::string::npos) << e.what();
  }
  EXPECT_THROW(cmp::readSequence(folder + "/missing"), cmp::SequenceError);
}

// The tools read config/mono_pose_<mode>.yaml as the node does: the declared defaults with the file's
// overrides (docking_settings::shippedSettings). The IR file makes an IR estimator.
TEST(MonoParams, ShippedFilesGiveEachInstanceItsMode) {
  const auto visible =
      docking_settings::shippedSettings<mono::MonoPoseNodeSettings>(std::string(CONFIG_DIR) + "/mono_pose_visible.yaml");
  const auto ir = docking_settings::shippedSettings<mono::MonoPoseNodeSettings>(std::string(CONFIG_DIR) + "/mono_pose_ir.yaml");
  EXPECT_EQ(mono::modeOf(visible.core), mono::MonoMode::kVisible);
  EXPECT_EQ(mono::modeOf(ir.core), mono::MonoMode::kIr);
  EXPECT_NO_THROW(mono::validate(visible.core));
  EXPECT_NO_THROW(mono::validate(ir.core));
}

// A value its declaration refuses, a wrong type and a key nobody reads are refused, naming the key.
TEST(MonoParams, AFileWithABadValueIsRefusedNamingTheKey) {
  const TempFolder temp("params");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"far_throttle_max_rate_hz: -1.0", "far_throttle_max_rate_hz"},
      {"min_inliers: many", "min_inliers"},
      {"led_threshold: 300", "led_threshold"},
      {"no_such_setting: 1", "no_such_setting"}};
  for (const auto& [line, key] : cases) {
    const std::string path = temp.path + "/p.yaml";
    std::ofstream(path) << line << "\n";
    try {
      docking_settings::shippedSettings<mono::MonoPoseNodeSettings>(path);
      ADD_FAILURE() << line << ": accepted";
    } catch (const docking_settings::ConfigError& e) {
      EXPECT_NE(e.key().find(key), std::string::npos) << e.what();
    }
  }
}

TEST(Stats, Percentile) {
  EXPECT_DOUBLE_EQ(cmp::percentile({3, 1, 2}, 0.5), 2.0);
  EXPECT_DOUBLE_EQ(cmp::percentile({0, 10}, 0.95), 9.5);
  EXPECT_TRUE(std::isnan(cmp::percentile({}, 0.5)));
}

TEST(TagTexture, BlackBorderAndWhiteRingWhereTheSpecPutsThem) {
  cmp::TagSpec spec;
  spec.size_m = 0.16;  // 8 cells of 20 mm; with the white ring 0.2 m
  spec.center_m = Eigen::Vector3d(0.0, 0.03, -0.01);
  const cv::Mat t = cmp::makeTagTexture(spec, 0.30, 0.24, 1000.0, 25, 240);  // 300 x 240 px
  ASSERT_EQ(t.cols, 300);
  ASSERT_EQ(t.rows, 240);
  // Tag centre at u = (0.03 + 0.15) * 1000 = 180, v = (0.12 + 0.01) * 1000 = 130.
  EXPECT_EQ(t.at<uint8_t>(130, 180 - 75), 25);   // black border cell (left), 75 mm from the centre
  EXPECT_EQ(t.at<uint8_t>(130, 180 + 75), 25);   // right
  EXPECT_EQ(t.at<uint8_t>(130 - 75, 180), 25);   // top
  EXPECT_EQ(t.at<uint8_t>(130, 180 - 90), 240);  // white ring, 90 mm
  EXPECT_EQ(t.at<uint8_t>(130, 180 + 115), 240); // outside the tag
}

TEST(TagPose, TargetTTagAxes) {
  cmp::TagSpec spec;
  spec.center_m = Eigen::Vector3d(0, 0.05, 0.02);
  const Eigen::Isometry3d T = cmp::targetTTag(spec);
  EXPECT_NEAR(T.linear().determinant(), 1.0, 1e-12);
  // The tag's z points into the face (-x of `target`), its x to the viewer's right (+y), y down (-z).
  EXPECT_TRUE((T.linear() * Eigen::Vector3d::UnitZ()).isApprox(-Eigen::Vector3d::UnitX()));
  EXPECT_TRUE((T.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_TRUE((T * Eigen::Vector3d::Zero()).isApprox(spec.center_m));
}

// AprilTag on a synthetic view with a known answer: the pose of `target` (not of the tag) must come
// back within a few millimetres and a degree, off-centre tag and yawed face included.
TEST(TagPose, AprilTagRecoversTheTargetPoseOnSyntheticViews) {
  cmp::TagSpec spec;
  spec.size_m = 0.16;
  spec.center_m = Eigen::Vector3d(0.0, 0.04, -0.01);
  const cv::Mat texture = cmp::makeTagTexture(spec, 0.30, 0.24, 2000.0);
  const mono::CameraIntrinsics camera = camera640();
  cmp::TagDetector detector(spec, 1, 2.0);
  struct Case {
    Eigen::Vector3d position;
    double yaw_deg;
  };
  for (const Case& c : {Case{{0.0, 0.0, 0.5}, 0.0}, Case{{0.05, -0.03, 0.8}, 30.0}, Case{{-0.1, 0.02, 1.2}, -25.0}}) {
    const Eigen::Isometry3d truth = facePose(c.position, c.yaw_deg * M_PI / 180.0);
    const cv::Mat image = cmp::renderFaceView(texture, 0.30, 0.24, camera, truth);
    const cmp::TagResult r = detector.detect(image, camera);
    ASSERT_TRUE(r.found) << r.status << " at " << c.position.transpose();
    const double range = c.position.norm();
    EXPECT_LT((r.camera_T_target.translation() - truth.translation()).norm(), 0.005 * range)
        << r.camera_T_target.translation().transpose() << " vs " << truth.translation().transpose();
    EXPECT_LT(cmp::rotationErrorDeg(r.camera_T_target.linear(), truth.linear()), 1.0);
  }
  // No tag: not found, with the reason.
  const cv::Mat empty(480, 640, CV_8UC1, cv::Scalar(120));
  const cmp::TagResult none = detector.detect(empty, camera);
  EXPECT_FALSE(none.found);
  EXPECT_FALSE(none.status.empty());
}
