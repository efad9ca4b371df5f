// A user's own target face (issue 11): compose a printable face from any image, and check before
// printing that a face has enough texture and contrast for mono_pose. ROS-free (OpenCV, Eigen and the
// mono core); the CLIs make_target_print and check_target_print are thin wrappers.
//
// Compose: the image is cropped to the face's aspect (centred) and scaled; each of the five reference
// markers of target.yaml becomes a dark dot on a white ring, so the dot finder of the 5-point solver
// (mono::DarkDotLocator: background = a high percentile of a disc 1.5 dot radii wide) sees white
// around every dot whatever the image is there.
//
// Check: the face is rendered as the camera sees it at the working ranges (0.4, 1, 1.4, 2 m; on axis
// and turned 35 deg), with the camera's blur and noise, and the same feature matching as mono_pose
// (mono::FeatureMatcher with the mono_pose_visible.yaml parameters) and the same dot finder run on it.
// Each case reports matches, homography inliers, how much of the face the inliers cover, whether the
// matched face is where it truly is, and the dots; the print passes when every case does, and the
// print's own contrast is high enough to survive real lighting.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "docking_perception/mono/dark_dot_locator.h"
#include "docking_perception/mono/feature_matcher.h"
#include "docking_perception/mono/target_model.h"

namespace docking_perception {
namespace target_print {

// ---------------------------------------------------------------- compose
struct ComposeOptions {
  int width_px = 1800;              // print width in pixels (0.30 m: 1800 px = 152 dpi)
  double ring_outer_factor = 2.4;   // white ring's outer radius / dot radius (the dot finder searches
                                    // 1.5 radii; the rest is room for blur and print misregistration)
  int dot_grey = 15;                // dot level (8-bit); the ring is 255
};

// `image`: 8-bit BGR or grey, any size (at least 16x16). Returns the BGR print, width_px wide, the
// face's aspect. Throws std::invalid_argument for an unusable image or options.
cv::Mat composePrint(const cv::Mat& image, const mono::TargetModel& model,
                     const ComposeOptions& options = ComposeOptions());

// ---------------------------------------------------------------- check
struct ViewCase {
  double range_m = 1.0;
  double yaw_deg = 0.0;  // the face turned about its vertical axis
};

struct CheckParams {
  std::vector<ViewCase> cases = {{0.4, 0.0}, {0.4, 35.0}, {1.0, 0.0},  {1.0, 35.0},
                                 {1.4, 0.0}, {1.4, 35.0}, {2.0, 0.0}, {2.0, 35.0}};
  // The camera (config/cameras/stereo_left.yaml, rectified): 640x480, f = 550 px.
  int image_width = 640, image_height = 480;
  double focal_px = 550.0;
  double blur_sigma_px = 1.0;     // defocus of the fixed-focus webcam (Gaussian sigma)
  double noise_sigma_dn = 3.0;    // sensor noise, 8-bit levels
  double background_grey = 110.0;
  int views_per_case = 3;         // views with small offsets and their own noise; a case needs
  int min_views_passed = 2;       // this many passing views
  unsigned seed = 1;
  // Search as mono_pose does once it tracks: in the face's predicted region with this margin, at
  // the predicted face width (the background's clutter is not the print's business).
  double search_margin_px = 40.0;
  // A view passes when the face is found with at least inlier_margin x min_inliers inliers (the
  // margin keeps the print working when real light and blur take some away), covering at least
  // min_coverage of the face, and the matched outline lies within max_outline_error_fraction of the
  // face's apparent width of the truth; and all five dots are found within max_dot_error_px.
  double inlier_margin = 1.5;
  double min_coverage = 0.25;
  double max_outline_error_fraction = 0.05;
  double max_dot_error_px = 1.0;
  // The print itself: RMS contrast (standard deviation of the grey levels) at least this, so that
  // matte paper under uneven light (which halves it) keeps the corners FAST needs.
  double min_print_contrast_dn = 30.0;
  double min_dot_contrast_dn = 80.0;  // ring level - dot level in the print, per dot
};

// Why a print fails; the CLI prints the advice for each.
enum class PrintProblem {
  kLowContrast = 0,   // the print's grey levels are too flat
  kLowTexture,        // too few features match at some range: too little fine detail
  kPoorCoverage,      // the matched features cluster in a part of the face
  kWrongMatch,        // the face was found in the wrong place (repetitive texture)
  kDotsNotFound,      // the dot finder failed (no white ring / busy surroundings)
  kDotsLowContrast,   // a dot is not dark enough against its surroundings in the print
};
const char* problemName(PrintProblem problem);  // "low_contrast", ...
const char* problemAdvice(PrintProblem problem);  // what to change

struct CaseResult {
  ViewCase view;
  int views = 0, views_passed = 0;
  // Medians over the views.
  int matches = 0, inliers = 0;
  double coverage = 0.0;             // fraction of the face inside the inliers' convex hull
  double outline_error_px = 0.0;     // matched face corners vs the truth (max corner), px
  int dots_found = 0;                // of 5, within max_dot_error_px of the truth
  double face_width_px = 0.0;        // apparent width of the face
  bool passed = false;
  std::vector<PrintProblem> problems;
};

struct PrintReport {
  bool passed = false;
  double print_contrast_dn = 0.0;    // standard deviation of the print's grey levels
  double min_dot_contrast_dn = 0.0;  // lowest ring - dot level difference in the print
  int model_keypoints = 0;           // FeatureMatcher model keypoints over its pyramid
  int required_inliers = 0;          // inlier_margin x min_inliers
  std::vector<CaseResult> cases;
  std::vector<PrintProblem> problems;  // each once, in the order of the enum
};

std::vector<std::string> validateCheckParams(const CheckParams& params);

// `model` must hold its texture (the print). Throws std::invalid_argument for bad params or a model
// without texture; otherwise never throws.
PrintReport checkPrint(const mono::TargetModel& model, const mono::FeatureMatcherParams& matcher_params,
                       const CheckParams& params = CheckParams());

// A table of the cases, the verdict and the advice, for a terminal.
std::string formatReport(const PrintReport& report, const CheckParams& params);

}  // namespace target_print
}  // namespace docking_perception
