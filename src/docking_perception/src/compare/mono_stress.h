// Stress harness of the monocular pose (issue 11): the target rendered by docking_sim's renderer at
// 0.4-2 m, on and off axis and turned, over a tidy or a busy (cluttered) room, then degraded the way
// real cameras and scenes degrade it: Gaussian defocus, linear motion blur in a random direction,
// sensor noise, a saturated specular blob on the face, a card hiding part of the face, and (IR) a
// reflection blob next to one LED. Every estimate is scored against the truth, including its
// covariance (per-axis normalised errors). ROS-free; everything is seeded.
//
// Used by the stress_mono tool (tables over seed ranges) and by the gtests (a few fixed seeds).
#pragma once

#include <Eigen/Core>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "docking_perception/mono/mono_pose_estimator.h"

namespace docking_perception {
namespace stress {

// One condition of the harness. Blur and noise in output pixels / 8-bit levels.
struct StressCondition {
  std::string name;
  bool infrared = false;
  bool clutter = false;          // busy textured surfaces behind and beside the target
  double defocus_sigma_px = 0.0;
  double motion_length_px = 0.0; // linear blur, direction drawn per frame
  double motion_max_angle_deg = 90.0;  // the direction is drawn within +-this of the image rows (90: any);
                                       // robots on a floor that yaw and drive smear along the rows
  double noise_sigma = 2.0;
  bool specular = false;         // saturated blob on the face
  bool occlusion = false;        // a card over part of the face (IR: over one LED)
  bool reflection = false;       // IR: a bright blob next to one LED (merges with it)
  bool region_hint = false;      // the estimator gets a region hint per frame (the face's box, shifted by
                                 // up to 15 % of its size and grown by 30 %: a disparity detector's guess)
  double min_range_m = 0.4;
  double max_range_m = 2.0;
  double max_roll_deg = 10.0;    // the face turned in the image plane up to +-this (a level floor: a few deg;
                                 // a tilted mount, a print glued at an angle or orbit: any, 180)
};

// The harness's conditions (visible and IR), in report order.
std::vector<StressCondition> standardConditions();

// Where the target is for one trial: camera <- target, drawn from a seed.
struct TrialPose {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

// A camera image with its truth.
struct StressFrame {
  cv::Mat gray;
  TrialPose truth;
};

// Renders frames of one target model through docking_sim's renderer (pinhole 640x480, f = 550 px,
// the stereo_left intrinsics of synthetic tests).
class StressRenderer {
 public:
  explicit StressRenderer(const mono::TargetModel& model);
  ~StressRenderer();
  const mono::CameraIntrinsics& camera() const { return camera_; }
  const mono::TargetModel& model() const { return model_; }

  // A pose inside the condition's range with the whole face in view (margin 8 px), yaw up to 35 deg,
  // pitch up to 10 deg, roll up to the condition's max_roll_deg, off-axis up to the image border.
  TrialPose drawPose(const StressCondition& condition, uint64_t seed) const;
  // One degraded frame; frame_seed varies noise, blur direction, blob and card placement.
  StressFrame render(const StressCondition& condition, const TrialPose& pose, uint64_t scene_seed,
                     uint64_t frame_seed) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  mono::TargetModel model_;
  mono::CameraIntrinsics camera_;
};

// The error of one estimate against the truth.
struct EstimateScore {
  bool valid = false;
  mono::RejectReason reason = mono::RejectReason::kNone;
  double range_m = 0.0;
  double position_error_pct = 0.0;     // of the true range
  double orientation_error_deg = 0.0;
  double normalized[6] = {0, 0, 0, 0, 0, 0};  // error / sigma: x, y, z, rot x, rot y, rot z (camera frame)
  bool orientation_claimed = false;    // valid with its orientation (not withheld)
  bool confident_wrong = false;        // valid and > 5 % of range or (claimed and) > 10 deg off
  double cpu_ms = 0.0;
};
EstimateScore scoreEstimate(const mono::MonoPoseResult& result, const TrialPose& truth);

// Aggregates of one condition.
struct ConditionSummary {
  std::string name;
  int frames = 0;
  int valid = 0;
  int cold_frames = 0;                 // first frame of a trial (no tracking yet)
  int cold_valid = 0;
  double median_position_pct = 0.0;
  double median_orientation_deg = 0.0;
  double coverage[6] = {0, 0, 0, 0, 0, 0};  // within 3 sigma per axis: of the valid (position) / claimed (rotation)
  int confident_wrong = 0;
  int orientation_withheld = 0;        // valid estimates without a claimed orientation
  std::map<std::string, int> reasons;  // invalid estimates by reason code name
  double cpu_ms_median = 0.0;
};
ConditionSummary summarize(const std::string& name, const std::vector<EstimateScore>& scores,
                           const std::vector<bool>& cold);

// Runs one condition: for each trial seed a fresh estimator sees frames_per_trial frames of one pose
// (independent noise / blur direction per frame; the first is a cold start, later ones track).
ConditionSummary runCondition(const StressRenderer& renderer, const StressCondition& condition,
                              const mono::MonoPoseParams& params, uint64_t first_seed, int trials,
                              int frames_per_trial, std::vector<EstimateScore>* scores = nullptr);

// The hint a disparity detector would give for a pose: the face's box, shifted and grown (seeded).
cv::Rect noisyFaceBox(const mono::TargetModel& model, const mono::CameraIntrinsics& camera, const TrialPose& pose,
                      uint64_t seed);

// A busy texture (many FAST corners): random rectangles, discs, bars and text-like strokes. Exposed for
// tests (size: power of two).
cv::Mat makeBusyTexture(uint64_t seed, int size = 512);

}  // namespace stress
}  // namespace docking_perception
