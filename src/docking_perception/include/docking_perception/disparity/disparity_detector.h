// The far-range target detector on a stereo disparity image (the paper's section III.A, made robust).
//
// ROS-free: plain C++17, OpenCV and Eigen. The nodelet converts messages and calls detect().
//
// detect() runs the detector's stages (stages.h; the package README, section disparity_detector, draws them):
//  1. input: the image and geometry usable; the searched region: the matcher's valid window;
//  2. valid disparity: the region's valid disparities above the floor cut (level_floor), median
//     filtered: enough of them;
//  3. band search: the closest object (the disparity `closest_min_pixels` pixels reach, so a few noisy
//     pixels cannot win), a threshold just below it that holds the target's own depth, and the band's blobs,
//     largest first: too small or thin, not of the mockup's shape (TargetShape: width and height it can
//     show from some yaw), height or isolation (a part split out of a blob merged with its neighbours), or the
//     target (with a SearchHint: inside the tracked target's gate). A band without it is removed and the
//     search looks behind it, so a nearer wall, person or box cannot hide the target; a blob that may be the
//     degraded target stops it;
//  4. port: the mockup's footprint fitted to the blob's depth profile gives the port (else the centroid of
//     the blob's nearest layer), reprojected with the rectified model, its covariance from pixel and
//     disparity noise;
//  5. plausibility: the blob's size, border and disparity range.
// The node adds the appearance check (face_appearance.h) and the track gate (target_track_gate.h).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "docking_perception/disparity/disparity_detector_settings.h"
#include "docking_perception/disparity/stages.h"

namespace docking_perception {
namespace disparity {

// The rectified stereo model the disparity was computed with (all in pixels and metres).
struct StereoGeometry {
  double focal_px = 0.0;    // rectified focal length f
  double cx_px = 0.0;       // rectified principal point of the left (reference) camera
  double cy_px = 0.0;
  double baseline_m = 0.0;  // B > 0; Z = f B / d
};

// The mockup's physical size (config/target.yaml: face, box behind it, two solar panels), from which
// the shape check derives what a target blob can measure. Defaults: the shipped mockup.
struct TargetShape {
  double face_width_m = 0.30;     // along y (the box is as wide as the face)
  double face_height_m = 0.24;    // along z (the box is as tall as the face)
  double body_depth_m = 0.30;     // box, behind the face
  double panel_span_m = 0.30;     // each panel, beyond the box side
  double panel_height_m = 0.16;
  double panel_offset_behind_face_m = 0.15;  // panels' plane behind the face (solar_panels.offset_x_m)
};

// Reads target.face.{width_m,height_m}, target.body.depth_m and target.solar_panels.{span_m,height_m}
// of a target.yaml (the panels are optional: without them span 0). Throws std::runtime_error naming
// the file and the field.
TargetShape loadTargetShape(const std::string& target_yaml_path);

// What the mockup can measure from any yaw, seen level (the port at camera height): its width is the
// extent of the face, box and panels projected on the image's horizontal (box alone edge-on, up to
// face + both panels face-on); its height that of the box (the panels are lower).
struct ShapeBounds {
  double min_width_m = 0.0, max_width_m = 0.0;
  double min_height_m = 0.0, max_height_m = 0.0;
};
ShapeBounds shapeBounds(const TargetShape& shape);

// Where the rig puts the stereo pair and the target's port, and how the matcher matches: the detector's
// rig-dependent limits (RigLimits) are derived from these, not set.
struct RigGeometry {
  double camera_height_m = 0.0;  // the left stereo camera above the floor (robot.yaml chaser.cameras.stereo_left z)
  double port_height_m = 0.0;    // the target's port above its floor (target.yaml target.mount z)
  int matcher_window_px = 0;     // block matching's window (stereo_image_proc.yaml correlation_window_size)
};

// Reads the two heights from robot.yaml and target.yaml; the matcher's window is the caller's (the node's
// ~matcher/correlation_window_size, the file's for tools). Throws std::runtime_error naming the file and field.
RigGeometry loadRigGeometry(const std::string& robot_yaml_path, const std::string& target_yaml_path,
                            int matcher_window_px);

// The limits that follow from the rig and the mockup (rigLimits()).
struct RigLimits {
  // level_floor: points lower than this below the optical axis are the floor; a blob's centre is expected
  // port_y_m below the axis (optical frame, y down), within kMaxCentreOffsetM.
  double floor_cut_m = 0.0;
  double port_y_m = 0.0;
  // The band keeps this depth behind the closest point.
  double band_depth_m = 0.0;
  // The mockup's shape bounds are widened by this many px at the blob's range.
  double shape_margin_px = 0.0;
};

// Constants of the method:
// the floor cut lies this far below the face's lower edge, so the face's edge rows stay (0.15 m below the axis
// on the test bed, whose floor is 0.25 m below);
constexpr double kFloorCutMarginM = 0.03;
// a blob's centre may lie this far above or below the port's height: the mockup's half height (0.12 m) and
// the height error at 8 m; patches 0.7-0.9 m off were taken at 6-8 m (eval_real_clutter_far_*);
constexpr double kMaxCentreOffsetM = 0.3;
// the band reaches this far behind the mockup's own depth: about the depth noise at 6 m (sigma_Z 0.16 m);
constexpr double kBandDepthMarginM = 0.2;
// the mockup's shape bounds are widened by this fraction of themselves (blur, glare and partial matches).
constexpr double kShapeToleranceFraction = 0.25;

// floor_cut_m: the face's lower edge below the axis (camera height - port height + half the face) plus
// kFloorCutMarginM; port_y_m: camera height - port height; band_depth_m: the mockup's body depth plus
// kBandDepthMarginM; shape_margin_px: half the matcher's window, rounded up (block matching fattens or trims
// edges by up to that).
RigLimits rigLimits(const TargetShape& shape, const RigGeometry& rig);

// The face print is stored reduced to this width once (face_appearance.cpp works at a narrower width).
constexpr double kMaxAppearanceWorkingWidthPx = 48.0;

// DetectorParams (the core's settings, with FaceAppearanceParams) are declared in
// settings/disparity_detector.yaml (generated header disparity_detector_settings.h).

// Throws std::invalid_argument (docking_settings::ConfigError) naming the first setting its declaration does not
// allow, or the rule between settings it breaks (median_kernel_px 0, 1, 3 or 5; max_disparity_px above
// min_disparity_px; with level_floor, a floor cut above the floor), or the mockup's size or the rig that is
// unusable.
void validate(const DetectorParams& params, const TargetShape& shape, const RigGeometry& rig);
std::vector<std::string> validateGeometry(const StereoGeometry& geometry);

// The metric shape of a blob, measured at its median raw disparity.
struct BlobShape {
  double width_m = 0.0, height_m = 0.0;  // bounding box at the blob's range
  double depth_extent_m = 0.0;           // 10th to 90th percentile of the depth (reported only: the
                                         // band's depth already bounds it)
  double fill = 0.0;                     // blob pixels / bounding-box pixels
  double range_z_m = 0.0;                // Z at the median disparity
};

// Where the tracked target is expected (TargetTrackGate::hint): among target-shaped blobs, the first
// one within radius_m of position_m is taken; the others are looked behind.
struct SearchHint {
  bool valid = false;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  double radius_m = 0.0;
};

// Where the disparity image lies in the camera's full image, when it is a window of it (the far stage's
// tracking window, far_stereo_rectify: camera_info roi). Edges of the window that are not the full
// image's are not the target's edge: a blob crossing one is a neighbour of the tracked target (or the
// target merged with one), never reported as the target cut by the border. Default: not a window.
struct ImageWindow {
  cv::Point offset{0, 0};  // the window's top-left pixel in the full image
  cv::Size full_size;      // the full image; empty: the disparity image is the full image
  bool isWindow() const { return full_size.area() > 0; }
};

struct Detection {
  bool found = false;
  // The stage that decided (stages.h): the first that did not pass; when found, the last the core ran, passed
  // (the node's appearance check and track gate may still refuse it).
  StageOutcome outcome;
  std::string reason;  // empty when found; otherwise human-readable, with the numbers that decided

  // Search figures (filled as far as the pipeline got, also when rejected).
  int valid_pixels = 0;              // valid disparities in the region of interest
  double closest_disparity_px = 0;   // robust closest disparity of the whole image
  double threshold_disparity_px = 0; // mask = filtered disparity >= this
  int near_objects_skipped = 0;      // nearer depth bands looked behind (too small, thin, or no
                                     // target-shaped blob in them)
  double blob_thickness_px = 0;      // diameter of the largest disc inside the blob
  int not_target_shaped_skipped = 0; // blobs measured and found not target-shaped
  BlobShape shape;                   // of the chosen blob (when the shape check ran)
  bool outside_hint = false;         // chosen although outside the hint's gate (no blob inside it)
  int merged_blobs_split = 0;        // blobs larger than the mockup in which a target-shaped part was
                                     // found (split_depth_step_m)
  bool footprint_fitted = false;     // the estimate is the fitted footprint's port (footprint_fit_enabled)
  double footprint_yaw_rad = 0.0;    // its yaw (face normal from the line of sight)
  double footprint_inlier_fraction = 0.0;
  bool appearance_judged = false;    // the face print was looked for (face_appearance.h) and judged
  double appearance_score = 0.0;     // its best match then (normalised correlation)

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
  // `shape`: the mockup of config/target.yaml (loadTargetShape); `rig`: loadRigGeometry. Throws
  // std::invalid_argument (validate()).
  DisparityDetector(const DetectorParams& params, const TargetShape& shape, const RigGeometry& rig);

  // Throws std::invalid_argument (validate()); keeps the old settings then.
  void setParams(const DetectorParams& params);
  const DetectorParams& params() const { return params_; }
  const TargetShape& shape() const { return shape_; }
  const RigGeometry& rig() const { return rig_; }

  // `disparity`: CV_32FC1, pixels; values that are not finite, <= 0 or outside
  // [search_min_px, search_max_px] (the matcher's search range) are invalid.
  // `valid_region`: the part of the image where the matcher can produce disparities (the left band of
  // width ~ the search range is blind); empty: the whole image. The border test uses its edges.
  // Never throws on bad input: returns found = false with outcome kBadInput and the reason.
  // `hint` (optional): the tracked target's predicted position, see SearchHint.
  // `window` (optional): the disparity image is a window of the full image, see ImageWindow; `geometry`
  // is then the window's (principal point shifted by its offset).
  Detection detect(const cv::Mat& disparity, const StereoGeometry& geometry,
                   double search_min_px = 0.0, double search_max_px = 1e9,
                   cv::Rect valid_region = cv::Rect(), const SearchHint& hint = SearchHint(),
                   const ImageWindow& window = ImageWindow()) const;

 private:
  DetectorParams params_;
  TargetShape shape_;
  RigGeometry rig_;
  RigLimits limits_;
};

// The noise model of a detection (constants of the method): 1-sigma error of the
// robust disparity (block matching's sub-pixel fit on a textured face; sigma_Z = Z^2 sigma_d / (f B)) and of
// the port's image point.
constexpr double kDisparitySigmaPx = 0.25;
constexpr double kCentreSigmaPx = 1.0;

// Position and its covariance from an image point and a disparity with the rectified model:
// Z = f B / d, X = (u - cx) Z / f, Y = (v - cy) Z / f; first-order propagation of independent pixel
// noise (u, v) and disparity noise d, so the depth error lies along the line of sight and grows as Z^2.
// Requires disparity_px > 0 and a valid geometry.
void reproject(const StereoGeometry& geometry, const cv::Point2d& centre_px, double disparity_px,
               double point_sigma_px, double disparity_noise_px, Eigen::Vector3d* position_m,
               Eigen::Matrix3d* covariance_m2);

// A bgr8 picture of a detection for rviz: the disparity in grey (near = bright, invalid = black), the
// blob tinted green when found and red when rejected, its contour, the centre cross and a status line.
cv::Mat renderDebugImage(const cv::Mat& disparity, const Detection& detection,
                         double display_max_disparity_px);

}  // namespace disparity
}  // namespace docking_perception
