// The far-range target detector on a stereo disparity image (the paper's section III.A, made robust).
//
// ROS-free: plain C++17, OpenCV and Eigen. The nodelet converts messages and calls detect().
//
// Pipeline (see the package README, section disparity_detector):
//  1. keep valid disparities inside the region of interest, drop floor points (optional height cut);
//  2. median (and optionally Gaussian) filter;
//  3. closest object: a high order statistic of the valid disparities (the value that at least
//     `closest_min_pixels` pixels reach), so a few noisy pixels cannot win;
//  4. threshold just below it (a depth band that holds the target's own depth), keep the largest
//     blob (outer contour); if it is smaller than min_blob_area_px or thinner than
//     min_blob_thickness_px (mismatches at occlusion edges, speckles), remove everything at that
//     depth and search again behind it (at most 5 times);
//  5. reject implausible blobs with a reason (too small, too large, on the border, out of range);
//  6. the target's visible face: the blob's nearest depth layer; its centroid is the centre, the median
//     of its disparities the robust disparity;
//  7. reproject with the rectified model and propagate pixel and disparity noise to a 3x3 covariance.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace docking_perception {
namespace disparity {

// The rectified stereo model the disparity was computed with (all in pixels and metres).
struct StereoGeometry {
  double focal_px = 0.0;    // rectified focal length f
  double cx_px = 0.0;       // rectified principal point of the left (reference) camera
  double cy_px = 0.0;
  double baseline_m = 0.0;  // B > 0; Z = f B / d
};

// Tuning of the detector. Defaults are only for tests; the node takes every value from
// config/disparity_detector.yaml.
struct DetectorParams {
  // Filtering of the disparity image before the search.
  int median_kernel_px = 3;        // 0 or 1: off; 3 or 5 (OpenCV's float median supports only these)
  double gaussian_sigma_px = 0.0;  // 0: off (the paper's Gaussian filter; blurs edges, off by default)

  // Closest object and threshold.
  int closest_min_pixels = 150;       // closest disparity = the value that this many valid pixels reach
  double target_depth_m = 0.5;        // depth of the target kept below the closest disparity
  double threshold_margin_px = 1.0;   // at least this much below the closest disparity (noise)

  // The visible face: the blob's nearest layer.
  double face_percentile = 0.9;       // reference disparity of the face: this percentile of the blob
  double face_depth_band_m = 0.10;    // face layer: within this depth of the reference
  double face_min_band_px = 0.25;     // ...but never thinner than this (sub-pixel noise at far range)

  // Plausibility of the blob.
  int min_blob_area_px = 400;             // fewer pixels: "blob too small" (looked behind)
  double min_blob_thickness_px = 16.0;    // thinner (largest inscribed disc): "blob too thin",
                                          // looked behind (mismatch strips at occlusion edges)
  double max_blob_area_fraction = 0.5;    // more than this fraction of the region: "blob too large"
  int border_margin_px = 2;               // within this of the valid region's edge: "touches border"
  double min_disparity_px = 4.0;          // robust disparity below this: "too far"
  double max_disparity_px = 92.0;         // above this: "too close" (0.6 m for our pair)

  // Where to look. Rows outside [roi_top_fraction, roi_bottom_fraction) of the image are ignored.
  double roi_top_fraction = 0.0;
  double roi_bottom_fraction = 1.0;
  // Floor removal on the test bed: points lower than `floor_cut_y_m` below the optical axis
  // (optical y points down) are ignored. The cameras are level on the robot, so the floor sits at the
  // camera height below the axis.
  bool floor_cut_enabled = true;
  double floor_cut_y_m = 0.15;
  // With the floor cut: points higher than this above the axis (the lab's ceiling and lights) are
  // ignored too; 0: off.
  double ceiling_cut_y_m = 0.0;

  // Noise model of the covariance.
  double disparity_sigma_px = 0.25;  // 1-sigma error of the robust disparity
  double centre_sigma_px = 1.0;      // 1-sigma error of the face centre in the image
};

// Every invalid field, each message naming it ("median_kernel_px must be 0, 1, 3 or 5 (got 4)").
// Empty: the parameters are usable.
std::vector<std::string> validateParams(const DetectorParams& params);
std::vector<std::string> validateGeometry(const StereoGeometry& geometry);

enum class Outcome {
  kFound = 0,
  kBadInput,             // empty image, wrong type, invalid geometry or parameters
  kNoValidDisparity,     // too few valid pixels to call anything the closest object
  kNoBlob,               // thresholding left nothing big enough to be a connected blob
  kBlobTooSmall,
  kBlobTooLarge,
  kBlobTouchesBorder,
  kDisparityOutOfRange,
};

// Short stable name of an outcome ("found", "blob_too_small", ...), for diagnostics keys and counters.
const char* outcomeName(Outcome outcome);

struct Detection {
  bool found = false;
  Outcome outcome = Outcome::kBadInput;
  std::string reason;  // empty when found; otherwise human-readable, with the numbers that decided

  // Search figures (filled as far as the pipeline got, also when rejected).
  int valid_pixels = 0;              // valid disparities in the region of interest
  double closest_disparity_px = 0;   // robust closest disparity of the whole image
  double threshold_disparity_px = 0; // mask = filtered disparity >= this
  int near_objects_skipped = 0;      // nearer objects too small or thin that were looked behind
  double blob_thickness_px = 0;      // diameter of the largest disc inside the blob

  // The chosen blob (filled whenever a blob was chosen, also when it was then rejected).
  std::vector<cv::Point> contour;  // outer contour of the blob, image pixels
  cv::Mat mask;                    // CV_8U, 255 on the blob's pixels, image size (empty if no blob)
  cv::Rect bounding_box;
  int blob_pixels = 0;             // pixels of the blob with a valid disparity
  int face_pixels = 0;             // of which in the face layer

  // The estimate (meaningful only when found, but also filled for a rejected blob when possible).
  cv::Point2d centre_px{0.0, 0.0};  // centroid of the face layer, rectified left image
  double disparity_px = 0.0;        // median disparity of the face layer
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();      // left rectified optical frame
  Eigen::Matrix3d covariance_m2 = Eigen::Matrix3d::Zero();   // of position_m
  double range_m = 0.0;                                       // |position_m|
};

class DisparityDetector {
 public:
  DisparityDetector() = default;
  // Throws std::invalid_argument naming the invalid fields.
  explicit DisparityDetector(const DetectorParams& params);

  // Throws std::invalid_argument naming the invalid fields; keeps the old parameters then.
  void setParams(const DetectorParams& params);
  const DetectorParams& params() const { return params_; }

  // `disparity`: CV_32FC1, pixels; values that are not finite, <= 0 or outside
  // [search_min_px, search_max_px] (the matcher's search range) are invalid.
  // `valid_region`: the part of the image where the matcher can produce disparities (the left band of
  // width ~ the search range is blind); empty: the whole image. The border test uses its edges.
  // Never throws on bad input: returns found = false with outcome kBadInput and the reason.
  Detection detect(const cv::Mat& disparity, const StereoGeometry& geometry,
                   double search_min_px = 0.0, double search_max_px = 1e9,
                   cv::Rect valid_region = cv::Rect()) const;

 private:
  DetectorParams params_;
};

// Position and its covariance from an image point and a disparity with the rectified model:
// Z = f B / d, X = (u - cx) Z / f, Y = (v - cy) Z / f; first-order propagation of independent pixel
// noise (u, v) and disparity noise d, so the depth error lies along the line of sight and grows as Z^2.
// Requires disparity_px > 0 and a valid geometry.
void reproject(const StereoGeometry& geometry, const cv::Point2d& centre_px, double disparity_px,
               double centre_sigma_px, double disparity_sigma_px, Eigen::Vector3d* position_m,
               Eigen::Matrix3d* covariance_m2);

// A bgr8 picture of a detection for rviz: the disparity in grey (near = bright, invalid = black), the
// blob tinted green when found and red when rejected, its contour, the centre cross and a status line.
cv::Mat renderDebugImage(const cv::Mat& disparity, const Detection& detection,
                         double display_max_disparity_px);

}  // namespace disparity
}  // namespace docking_perception
