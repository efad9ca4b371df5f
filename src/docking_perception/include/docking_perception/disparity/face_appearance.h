// Does the far blob look like the target? The face print of config/target.yaml matched in the left
// rectified image where the disparity detector puts the port (issue 11).
//
// Disparity alone cannot tell the mockup from a stack of boxes of its size and shape (campaign seed
// 7515: boxes 6 m away passed the shape, footprint and gate checks and were approached to 1.3 m). The
// print can: at 2-6 m it is 27-80 px wide, and its five white rings and the port ring survive blur.
//
// Method: the left image around the detected port (the detector's position error, 0.25 m either side)
// and the print are both reduced so that the face is at most 24 px wide;
// the print, squeezed horizontally for each of a few yaws (the face turned up to 60 deg), is slid over
// that region (normalised cross-correlation, so gain and exposure do not matter). The best score is
// the match. Where the face cannot be judged (too much of it saturated by glare, too dark, outside the
// image) the check says so and the detector keeps its own verdict: it can only reject what is visibly
// not the print.
//
// ROS-free: plain C++17, OpenCV and Eigen.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "docking_perception/disparity/disparity_detector.h"

namespace docking_perception {
namespace disparity {

enum class AppearanceVerdict {
  kNotChecked = 0,       // no detection to check, or no usable image or print
  kLooksLikeTarget,      // the print matched
  kNotTheTarget,         // the print did not match: a rejection
  kGlare,                // too much of the face saturated to judge
  kTooDark,              // too dark to judge
  kOutsideImage,         // the face (with the search margin) is not inside the image
};
// Short stable name ("not_checked", "looks_like_target", "not_the_target", "glare", "too_dark", "outside_image").
const char* appearanceVerdictName(AppearanceVerdict verdict);
// True for the verdicts that looked but could not confirm or refute (glare, too dark, outside the image).
bool isUnjudged(AppearanceVerdict verdict);

struct AppearanceResult {
  AppearanceVerdict verdict = AppearanceVerdict::kNotChecked;
  double score = 0.0;               // best normalised correlation (-1..1); 0 when not judged
  double squeeze = 1.0;             // the print's horizontal squeeze at the best score (cos of the yaw)
  cv::Point2d matched_centre_px{0.0, 0.0};  // the print's centre at the best score, full-image pixels
  cv::Size2d matched_size_px{0.0, 0.0};     // the print's size there (squeezed width, height)
  double saturated_fraction = 0.0;  // of the expected face rectangle
  double mean_dn = 0.0;             // of the searched region
  std::string reason;               // numbers that decided, for the detector's status
};

struct AppearanceSearchLayout;  // where the face and its search margin lie (face_appearance.cpp)

class FaceAppearanceCheck {
 public:
  FaceAppearanceCheck() = default;
  // `print_grey`: the face texture (8-bit grey, covering the whole face); face size in metres.
  // Throws std::invalid_argument on an empty print or a non-positive size.
  FaceAppearanceCheck(const cv::Mat& print_grey, double face_width_m, double face_height_m);

  bool ready() const { return !print_.empty(); }

  // `left_rect`: the rectified left image (CV_8UC1) that `geometry` describes (a window or a reduced
  // image, as the disparity was computed on); `port_m`: the detected port in its optical frame.
  // Never throws: bad input is reported as kNotChecked with the reason.
  AppearanceResult check(const cv::Mat& left_rect, const StereoGeometry& geometry, const Eigen::Vector3d& port_m,
                         const FaceAppearanceParams& params) const;

 private:
  // The best match of the print, squeezed for each of appearanceSqueezes(), in the searched region: the
  // verdict, score and place in `result`.
  void matchPrint(const cv::Mat& left_rect, const AppearanceSearchLayout& layout, const FaceAppearanceParams& params,
                  AppearanceResult* result) const;
  // The print reduced to `size`, zero mean, unit norm; made once per size (a face keeps its size from frame
  // to frame, and reducing costs as much as the search).
  cv::Mat printOfSize(cv::Size size) const;

  cv::Mat print_;  // reduced once (area average) to kMaxAppearanceWorkingWidthPx wide, CV_32F
  double face_width_m_ = 0.0, face_height_m_ = 0.0;
  mutable std::mutex reduced_prints_mutex_;
  mutable std::map<std::uint64_t, cv::Mat> reduced_prints_;  // by (width << 32 | height)
};

// Checks a found detection's face (port: detection->position_m) in `left_rect`: a print that does not
// match turns it into a rejection (AppearanceOutcome::kMismatch, found = false, the reason with the score);
// a face too dark to judge leaves it found, one too saturated (glare) is refused (AppearanceOutcome::kGlare,
// found = false: the glare that hides the print hides part of the mockup, and the blob left puts the port
// 0.2-0.4 m off, campaign seed 10939). Sets appearance_judged and appearance_score. A detection
// not found is left alone (and not checked). With params.refine_port, a matched print moves the port
// to the print's centre: across the line of sight, and in depth to the median of `disparity` (CV_32F, the
// image the detection came from; empty: depth kept) over the middle half of the matched print (when at
// least a quarter of it is valid, > 0) if that depth and the detection's differ by more than twice the
// detection's depth sigma. The footprint fit's depth of a turned target's port jumps by ~0.1 m between
// frames (campaign seed 7605 at 2.2 m); the face's own disparity does not, but it is the noisier far away.
AppearanceResult confirmByAppearance(const FaceAppearanceCheck& check, const cv::Mat& left_rect,
                                     const cv::Mat& disparity, const StereoGeometry& geometry,
                                     const FaceAppearanceParams& params, Detection* detection);

// The print's horizontal squeezes tried: cos of yaws 0, 30, 45 and 60 deg.
const std::vector<double>& appearanceSqueezes();

}  // namespace disparity
}  // namespace docking_perception
