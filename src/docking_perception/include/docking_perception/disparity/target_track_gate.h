// Agreement with the tracked target for the disparity detector (ROS-free).
//
// A target-shaped blob can still be something else of the mockup's size (a box on a shelf). The
// target moves slowly and continuously: once it is tracked, a detection is accepted only inside a
// gate around the track's prediction (last confirmed position + velocity x elapsed time, widened by
// the relative speed the target can reach and by the detection's own depth noise). A detection outside
// the gate is reported invalid (TrackOutcome::kOffTrack) until the same new position has been seen
// `confirm_frames` frames in a row: then the track moves there (the target was really moved, or the
// first lock was wrong). Without a confirmed detection for 2 s the track is dropped and the
// next target-shaped detection starts a new one at once (the shape check alone guards acquisition).
#pragma once

#include <string>

#include <Eigen/Core>

#include "docking_perception/disparity/disparity_detector.h"
#include "docking_perception/disparity/disparity_detector_settings.h"

namespace docking_perception {
namespace disparity {

// TrackGateParams (track_* settings) are declared in settings/disparity_detector.yaml (generated header).

class TargetTrackGate {
 public:
  // Throws std::invalid_argument (docking_settings::ConfigError) naming the first setting not allowed.
  explicit TargetTrackGate(const TrackGateParams& params = TrackGateParams());
  void setParams(const TrackGateParams& params);
  const TrackGateParams& params() const { return params_; }

  // Where to look at `stamp_s` (invalid without a live track): pass it to DisparityDetector::detect.
  SearchHint hint(double stamp_s) const;

  // Checks a found detection at `stamp_s` (seconds, any monotonic clock: image stamps) against the
  // track and updates it. An accepted detection is returned unchanged; a rejected one has found =
  // false, outcome TrackOutcome::kOffTrack and the reason with the distance, the gate and the confirmation count.
  // Detections that are not found pass through (they only age the track). Stamps that go backwards
  // (a replayed bag restarted) reset the track.
  Detection apply(double stamp_s, const Detection& detection);

  void reset();
  bool tracking() const { return has_track_; }
  const Eigen::Vector3d& trackPosition() const { return position_m_; }

 private:
  double gateRadius(double dt_s, const Eigen::Matrix3d& covariance_m2) const;
  Eigen::Vector3d predict(double stamp_s) const;
  void startTrack(double stamp_s, const Eigen::Vector3d& position_m);

  TrackGateParams params_;
  bool has_track_ = false;
  double last_stamp_s_ = 0.0;        // last confirmed detection
  double last_seen_stamp_s_ = 0.0;   // last call, for stamps going backwards
  Eigen::Vector3d position_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps_ = Eigen::Vector3d::Zero();
  // A jump waiting for confirmation.
  int pending_frames_ = 0;
  double pending_stamp_s_ = 0.0;
  Eigen::Vector3d pending_position_m_ = Eigen::Vector3d::Zero();
};

}  // namespace disparity
}  // namespace docking_perception
