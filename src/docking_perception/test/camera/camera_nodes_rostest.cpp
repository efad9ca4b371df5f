// Node-level tests of the camera nodes, run by rostest (camera_sequence.test, camera_failures.test,
// camera_frames.test pick their cases with --gtest_filter). Expected values are read from the YAML
// files with yaml-cpp, independently of the camera_info_manager the nodes use.
#include <docking_msgs/names.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_ros/transform_listener.h>
#include <yaml-cpp/yaml.h>

#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace topics = docking_msgs::topics;
namespace frames = docking_msgs::frames;

namespace {

std::string requiredTestParam(const std::string& name) {
  std::string value;
  if (!ros::NodeHandle("~").getParam(name, value)) ADD_FAILURE() << "test parameter ~" << name << " missing";
  return value;
}

// Spins until `done` holds or `timeout_s` (ROS time) passes; returns done().
bool spinUntil(const std::function<bool()>& done, double timeout_s) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (ros::ok() && ros::WallTime::now() < deadline) {
    ros::spinOnce();
    if (done()) return true;
    ros::WallDuration(0.01).sleep();
  }
  return done();
}

// Everything received on one camera's image_raw and camera_info.
struct CameraRecorder {
  std::mutex mutex;
  std::vector<sensor_msgs::Image> images;
  std::vector<sensor_msgs::CameraInfo> infos;
  ros::Subscriber image_sub;
  ros::Subscriber info_sub;

  CameraRecorder(ros::NodeHandle& nh, const std::string& image_topic) {
    const std::string info_topic = ros::names::parentNamespace(image_topic) + "/camera_info";
    image_sub = nh.subscribe<sensor_msgs::Image>(image_topic, 50, [this](const sensor_msgs::ImageConstPtr& msg) {
      std::lock_guard<std::mutex> lock(mutex);
      images.push_back(*msg);
    });
    info_sub = nh.subscribe<sensor_msgs::CameraInfo>(info_topic, 50, [this](const sensor_msgs::CameraInfoConstPtr& msg) {
      std::lock_guard<std::mutex> lock(mutex);
      infos.push_back(*msg);
    });
  }
  size_t count() {
    std::lock_guard<std::mutex> lock(mutex);
    return std::min(images.size(), infos.size());
  }
};

std::vector<double> yamlNumbers(const YAML::Node& node) { return node["data"].as<std::vector<double>>(); }

// The camera_info published must carry exactly the calibration file's numbers.
void expectInfoMatchesCalibration(const sensor_msgs::CameraInfo& info, const std::string& calibration_path,
                                  const std::string& frame_id) {
  SCOPED_TRACE(calibration_path);
  const YAML::Node calibration = YAML::LoadFile(calibration_path);
  EXPECT_EQ(info.header.frame_id, frame_id);
  EXPECT_EQ(info.width, calibration["image_width"].as<unsigned>());
  EXPECT_EQ(info.height, calibration["image_height"].as<unsigned>());
  EXPECT_EQ(info.distortion_model, calibration["distortion_model"].as<std::string>());
  const auto k = yamlNumbers(calibration["camera_matrix"]);
  const auto d = yamlNumbers(calibration["distortion_coefficients"]);
  const auto r = yamlNumbers(calibration["rectification_matrix"]);
  const auto p = yamlNumbers(calibration["projection_matrix"]);
  ASSERT_EQ(k.size(), 9u);
  ASSERT_EQ(d.size(), info.D.size());
  for (size_t i = 0; i < 9; ++i) EXPECT_DOUBLE_EQ(info.K[i], k[i]) << "K[" << i << "]";
  for (size_t i = 0; i < d.size(); ++i) EXPECT_DOUBLE_EQ(info.D[i], d[i]) << "D[" << i << "]";
  for (size_t i = 0; i < 9; ++i) EXPECT_DOUBLE_EQ(info.R[i], r[i]) << "R[" << i << "]";
  for (size_t i = 0; i < 12; ++i) EXPECT_DOUBLE_EQ(info.P[i], p[i]) << "P[" << i << "]";
}

uint8_t channelAt(const sensor_msgs::Image& image, int row, int col, int channel) {
  const int channels = image.encoding == "bgr8" ? 3 : 1;
  return image.data[static_cast<size_t>(row) * image.step + static_cast<size_t>(col * channels + channel)];
}

// ---- camera_sequence.test: stereo_camera and ir_camera on committed PNG sequences ----

TEST(CameraSequence, StereoPairHasCalibratedInfoAndSharedIncreasingStamps) {
  ros::NodeHandle nh;
  CameraRecorder left(nh, topics::kStereoLeftImageRaw);
  CameraRecorder right(nh, topics::kStereoRightImageRaw);
  ASSERT_TRUE(spinUntil([&] { return left.count() >= 10 && right.count() >= 10; }, 60.0))
      << "left " << left.count() << ", right " << right.count() << " image+info pairs";

  std::lock_guard<std::mutex> lock_left(left.mutex);
  std::lock_guard<std::mutex> lock_right(right.mutex);
  expectInfoMatchesCalibration(left.infos.back(), requiredTestParam("left_calibration"), frames::kStereoLeftOptical);
  // Both of a pair in the left optical frame: stereo_image_proc (image_geometry::StereoCameraModel)
  // refuses a pair whose frames differ.
  expectInfoMatchesCalibration(right.infos.back(), requiredTestParam("right_calibration"),
                               frames::kStereoLeftOptical);

  // Every left image has a right image with the very same stamp (one stamp per grabbed pair) ...
  std::set<ros::Time> right_stamps;
  for (const auto& image : right.images) right_stamps.insert(image.header.stamp);
  ASSERT_FALSE(right.images.empty());
  const ros::Time first_right = right.images.front().header.stamp;
  size_t paired = 0;
  for (size_t i = 0; i + 1 < left.images.size(); ++i) {  // the last right image may still be in flight
    // The two subscriptions connect one after the other: pairs grabbed before the right one was
    // connected reached only the left recorder.
    if (left.images[i].header.stamp < first_right) continue;
    ++paired;
    EXPECT_EQ(right_stamps.count(left.images[i].header.stamp), 1u) << "left image " << i << " has no right twin";
  }
  EXPECT_GE(paired, 8u) << "too few left images after the right stream started";
  // ... and stamps increase, image and camera_info alike.
  for (const auto* camera : {&left, &right}) {
    for (size_t i = 1; i < camera->images.size(); ++i) {
      EXPECT_GT(camera->images[i].header.stamp, camera->images[i - 1].header.stamp) << "image " << i;
    }
    for (size_t i = 1; i < camera->infos.size(); ++i) {
      EXPECT_GT(camera->infos[i].header.stamp, camera->infos[i - 1].header.stamp) << "camera_info " << i;
    }
    std::set<ros::Time> image_stamps;
    for (const auto& image : camera->images) image_stamps.insert(image.header.stamp);
    for (const auto& info : camera->infos) EXPECT_EQ(image_stamps.count(info.header.stamp), 1u);
  }

  // The images are the files' content: bgr8 640x480, left and right not swapped, frames advancing
  // through the 4-image sequence and starting again (green channel = 10 * (index + 1)).
  for (const auto* camera : {&left, &right}) {
    const uint8_t expected_blue = camera == &left ? 40 : 200;
    for (const auto& image : camera->images) {
      ASSERT_EQ(image.encoding, "bgr8");
      ASSERT_EQ(image.width, 640u);
      ASSERT_EQ(image.height, 480u);
      EXPECT_EQ(channelAt(image, 10, 10, 0), expected_blue);
    }
    for (size_t i = 1; i < camera->images.size(); ++i) {
      const int previous = channelAt(camera->images[i - 1], 10, 10, 1);
      const int current = channelAt(camera->images[i], 10, 10, 1);
      EXPECT_EQ(current, previous == 40 ? 10 : previous + 10) << "image " << i;
    }
  }
}

TEST(CameraSequence, IrIsMonoWithItsCalibration) {
  ros::NodeHandle nh;
  CameraRecorder ir(nh, topics::kIrImageRaw);
  ASSERT_TRUE(spinUntil([&] { return ir.count() >= 5; }, 60.0)) << ir.count() << " IR image+info pairs";
  std::lock_guard<std::mutex> lock(ir.mutex);
  expectInfoMatchesCalibration(ir.infos.back(), requiredTestParam("ir_calibration"), frames::kIrOptical);
  for (const auto& image : ir.images) {
    ASSERT_EQ(image.encoding, "mono8");
    ASSERT_EQ(image.width, 640u);
    EXPECT_EQ(image.step, 640u);
    EXPECT_EQ(image.header.frame_id, frames::kIrOptical);
  }
  // Grey of the colour file's background (B 40, G 10..40, R 90): BT.601 luminance 37.4 .. 55.0.
  const int grey = channelAt(ir.images.front(), 10, 10, 0);
  EXPECT_GE(grey, 37);
  EXPECT_LE(grey, 55);
  // The white rectangle stays white.
  EXPECT_EQ(channelAt(ir.images.front(), 240, 300, 0), 255);
}

// ---- camera_failures.test: a missing device, a calibration of the wrong size ----

struct DiagnosticsRecorder {
  std::mutex mutex;
  std::vector<diagnostic_msgs::DiagnosticStatus> statuses;
  ros::Subscriber sub;
  explicit DiagnosticsRecorder(ros::NodeHandle& nh) {
    sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>("/diagnostics", 100,
                                                         [this](const diagnostic_msgs::DiagnosticArrayConstPtr& msg) {
                                                           std::lock_guard<std::mutex> lock(mutex);
                                                           for (const auto& s : msg->status) statuses.push_back(s);
                                                         });
  }
  // The last status whose name contains both parts.
  bool last(const std::string& node, const std::string& task, diagnostic_msgs::DiagnosticStatus* out) {
    std::lock_guard<std::mutex> lock(mutex);
    for (auto it = statuses.rbegin(); it != statuses.rend(); ++it) {
      if (it->name.find(node) != std::string::npos && it->name.find(task) != std::string::npos) {
        *out = *it;
        return true;
      }
    }
    return false;
  }
};

int valueAsInt(const diagnostic_msgs::DiagnosticStatus& status, const std::string& key) {
  for (const auto& kv : status.values) {
    if (kv.key == key) return std::stoi(kv.value);
  }
  return -1;
}

TEST(CameraFailures, MissingDeviceIsAnErrorAndTheNodeKeepsRetrying) {
  ros::NodeHandle nh;
  DiagnosticsRecorder diagnostics(nh);
  CameraRecorder right(nh, topics::kStereoRightImageRaw);
  const std::string device = requiredTestParam("missing_device");

  diagnostic_msgs::DiagnosticStatus status;
  auto failures_at_least = [&](int n) {
    return diagnostics.last("stereo_camera", "capture", &status) && valueAsInt(status, "consecutive failures") >= n;
  };
  ASSERT_TRUE(spinUntil([&] { return failures_at_least(3); }, 60.0)) << "no diagnostics with 3 failed attempts";
  EXPECT_EQ(status.level, diagnostic_msgs::DiagnosticStatus::ERROR);
  EXPECT_NE(status.message.find(device), std::string::npos) << status.message;
  EXPECT_EQ(status.hardware_id.find(device), 0u) << status.hardware_id;

  // Still alive and still trying after several retries.
  ASSERT_TRUE(spinUntil([&] { return failures_at_least(5); }, 60.0)) << "the node stopped retrying";
  EXPECT_EQ(status.level, diagnostic_msgs::DiagnosticStatus::ERROR);
  // Half a pair is no pair: the right camera (a good sequence) publishes nothing either.
  EXPECT_EQ(right.count(), 0u);
}

TEST(CameraFailures, CalibrationOfAnotherSizeIsRefused) {
  ros::NodeHandle nh;
  DiagnosticsRecorder diagnostics(nh);
  CameraRecorder ir(nh, topics::kIrImageRaw);
  diagnostic_msgs::DiagnosticStatus status;
  ASSERT_TRUE(spinUntil([&] {
    return diagnostics.last("ir_camera", "capture", &status) && valueAsInt(status, "frames refused") >= 3;
  }, 60.0)) << "no diagnostics reporting refused frames";
  EXPECT_EQ(status.level, diagnostic_msgs::DiagnosticStatus::ERROR);
  EXPECT_NE(status.message.find("ir.yaml"), std::string::npos) << status.message;
  EXPECT_NE(status.message.find("320x240"), std::string::npos) << status.message;
  EXPECT_NE(status.message.find("640x480"), std::string::npos) << status.message;
  EXPECT_EQ(valueAsInt(status, "frames published"), 0);
  spinUntil([] { return false; }, 1.0);
  EXPECT_EQ(ir.count(), 0u) << "images were published with a calibration of the wrong size";
}

// ---- camera_frames.test: the robot model's camera frames (description.launch) ----

TEST(CameraFrames, StaticTransformsMatchRobotYaml) {
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  const YAML::Node robot = YAML::LoadFile(requiredTestParam("robot_config"));
  const std::string base = robot["chaser"]["base_frame"].as<std::string>();
  ASSERT_EQ(base, frames::kBaseLink);
  int checked = 0;
  for (const auto& entry : robot["chaser"]["cameras"]) {
    const std::string frame = entry.second["frame_id"].as<std::string>();
    SCOPED_TRACE(frame);
    geometry_msgs::TransformStamped transform;
    ASSERT_TRUE(spinUntil([&] { return buffer.canTransform(base, frame, ros::Time(0)); }, 30.0))
        << "no transform " << base << " -> " << frame;
    transform = buffer.lookupTransform(base, frame, ros::Time(0));
    const auto xyz = entry.second["xyz_m"].as<std::vector<double>>();
    const auto rpy = entry.second["rpy_rad"].as<std::vector<double>>();
    EXPECT_NEAR(transform.transform.translation.x, xyz[0], 1e-6);  // URDF text: 1e-6 is plenty
    EXPECT_NEAR(transform.transform.translation.y, xyz[1], 1e-6);
    EXPECT_NEAR(transform.transform.translation.z, xyz[2], 1e-6);
    tf2::Quaternion expected;
    expected.setRPY(rpy[0], rpy[1], rpy[2]);  // tf2's fixed-axis RPY, as URDF
    const auto& q = transform.transform.rotation;
    const tf2::Quaternion actual(q.x, q.y, q.z, q.w);
    EXPECT_NEAR(std::abs(actual.dot(expected)), 1.0, 1e-9);
    // REP 103: these cameras look forward, so the optical z axis is base_link +x.
    const tf2::Vector3 optical_z = tf2::Matrix3x3(actual) * tf2::Vector3(0, 0, 1);
    EXPECT_NEAR(optical_z.x(), 1.0, 1e-6);
    ++checked;
  }
  EXPECT_EQ(checked, 3);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "camera_nodes_rostest");
  ros::NodeHandle nh;  // keeps the node up for the whole run
  return RUN_ALL_TESTS();
}
