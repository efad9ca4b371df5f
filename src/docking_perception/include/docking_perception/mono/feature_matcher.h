// Finds the textured target face in an image and gives precise 2D-3D correspondences.
//
// Model (once): the texture at a few widths (a pyramid covering the face's apparent size from 0.4 m to
// 2 m), corners and descriptors at each width.
// Per image: corners (FAST by default: ~50x cheaper than BRISK's own scale-space detector, and the
// model pyramid already provides the scale invariance; BRISK's detector is selectable), 512-bit
// descriptors (by default the upright ring descriptor, upright_descriptor.h, for the sharp model: the
// test bed's cameras do not roll; OpenCV's rotation-invariant BRISK for the blurred model and when
// selected), 2-nearest-neighbour Hamming matching (hardware popcount) with Lowe's ratio test, RANSAC
// homography from texture pixels to image pixels.
// Refinement: corner positions are good to ~1 px, too coarse for sub-degree orientation. The texture
// level nearest the face's apparent size is warped into the image with the homography, and around each
// inlier the image is correlated (normalised cross-correlation, 11x11 patch, +-3 px, parabolic peak)
// with that rendering: this gives the image position of the exact model point to ~0.1 px. The model
// corners of that level that were not matched are refined the same way (up to 220 in all),
// which multiplies the constraints on the pose at a distance, where few features match.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <string>
#include <vector>

#include "docking_perception/mono/mono_pose_settings.h"
#include "docking_perception/mono/upright_descriptor.h"

namespace docking_perception {
namespace mono {

// The model pyramids a search can match against: the sharp texture; the texture blurred round
// (blurred_model_sigma_px: defocus); that blurred one also smeared along the rows (search_row_smear_px:
// a robot's yaw or drive during the exposure).
enum class ModelSet { kSharp, kBlurred, kRowSmeared };

// FeatureMatcherParams is declared in settings/mono_pose.yaml (generated header). upright_descriptors: the
// UprightRingDescriptor for the sharp model and its searches (no orientation: ~7 k instructions a keypoint
// against BRISK's ~65 k); false: OpenCV's rotation-invariant BRISK descriptors. The blurred model keeps BRISK
// either way: with upright descriptors it found more faces under 9 px of motion blur, but some 10-35 deg off
// with a small covariance (stress seeds 100-139 and 400-439: 2 confident wrong in 120 frames, BRISK none).

struct FaceMatch {
  bool found = false;
  std::string status;               // why not found
  int keypoints = 0;                // image keypoints with descriptors
  int matches = 0;                  // after the ratio test
  int inliers = 0;                  // ratio-test matches that are inliers of the RANSAC homography
  int pyramid_level = 0;            // the image level the keypoints came from (0 full, 1 half resolution)
  ModelSet model_set = ModelSet::kSharp;  // the model pyramid matched against
  bool refined = false;             // the correspondences below are the refined ones
  bool refined_with_blurred_model = false;  // ... against the blurred model's patches (blur_matched_refinement)
  int refined_with_row_smear_px = 0;        // ... against the model smeared along the rows by this (0: not)
  bool refined_again = false;       // the last pass moved the face more than refine_again_move_px: one more
  bool from_prediction = false;     // matchAtPrediction: no features, the refinement started from a prediction
  int refine_candidates = 0;        // points the (first) refinement pass tried to correlate
  int first_pass_kept = 0;          // ... and kept: whether a prediction held (later passes may keep fewer)
  cv::Matx33d homography = cv::Matx33d::eye();  // texture pixel -> image pixel
  std::vector<cv::Point2f> matched_image_points;  // all ratio-test matches (for the debug image)
  // The correspondences for the pose: the homography inliers, or after refinement the refined points
  // (inliers and unmatched model corners), so there may be more of them than `inliers`.
  std::vector<cv::Point2f> inlier_texture_points;
  std::vector<cv::Point2f> inlier_image_points;
  std::vector<cv::Point2f> face_outline;           // texture corners mapped by the homography
};

class FeatureMatcher {
 public:
  explicit FeatureMatcher(const FeatureMatcherParams& params = FeatureMatcherParams());

  // Model features from the texture (8-bit gray). Returns false (with the reason) when the texture
  // yields too few keypoints to ever reach min_inliers.
  bool buildModel(const cv::Mat& texture_gray, std::string* reason);
  // Changing detector or model parameters rebuilds the model features from the stored texture.
  void setParams(const FeatureMatcherParams& params);
  const FeatureMatcherParams& params() const { return params_; }
  int modelKeypointCount() const { return static_cast<int>(model_points_.size()); }
  // The BRISK object in use: null until buildModel, then (when BRISK describes: upright_descriptors false,
  // or a blurred model) the one of the process, shared by every matcher (its pattern tables take 46 MB).
  const cv::BRISK* descriptorExtractor() const { return brisk_.get(); }

  // Matches in roi (empty: the whole image) of an 8-bit gray image. expected_face_width_px > 0 (from
  // a predicted pose) restricts matching to the model levels within a factor 1.6 of that width.
  // pyramid_level 1 detects and describes on the half-resolution image (blurred images keep only coarse
  // corners; FAST finds them at half resolution); the homography and the refinement are at full
  // resolution either way.
  // model_set: the pyramid matched against (one not built: the sharp one).
  FaceMatch match(const cv::Mat& gray, const cv::Rect& roi = cv::Rect(), double expected_face_width_px = 0.0,
                  int pyramid_level = 0, ModelSet model_set = ModelSet::kSharp) const;
  bool hasBlurredModel() const { return params_.blurred_model_sigma_px > 0.0; }
  bool hasRowSmearedModel() const { return hasBlurredModel() && params_.search_row_smear_px > 0; }
  bool hasModelSet(ModelSet set) const {
    return set == ModelSet::kSharp || (set == ModelSet::kBlurred ? hasBlurredModel() : hasRowSmearedModel());
  }

  // Tracking without features (issue 15): the face where a predicted homography (texture pixel -> image
  // pixel, from the tracked pose) puts it; the model corners of the level nearest its apparent size are
  // refined by NCC as after a feature match (up to the same 220 points). No FAST, BRISK or
  // Hamming matching: a third of a feature search's instructions. found when the predicted outline is a
  // plausible view and at least max(min_inliers, min_kept_fraction x the points tried) survive the
  // correlation and the refinement's RANSAC; a prediction off by more than the NCC search (+-3 px) keeps
  // few points and is not found (the caller then searches with features).
  FaceMatch matchAtPrediction(const cv::Mat& gray, const cv::Matx33d& predicted_homography,
                              double min_kept_fraction) const;

 private:
  struct ModelLevel {
    int width_px;
    ModelSet set = ModelSet::kSharp;
    int smear_px = 0;      // a level smeared along the rows (refinement only, no descriptors)
    double scale;      // level pixels per texture pixel
    cv::Mat image;
    int first_row;     // this level's rows in model_descriptors_
    int row_count;
  };
  // The rows of model_descriptors_ a search matches against.
  struct ModelRows {
    int first = 0;
    int count = 0;
  };
  // The region to search (roi, or the whole image when empty), clipped; *problem says why none.
  cv::Rect searchRegion(const cv::Mat& gray, const cv::Rect& roi, std::string* problem) const;
  // Keypoints and descriptors of the region (half: at half resolution), of the kind the model set has.
  void describeRegion(const cv::Mat& gray, const cv::Rect& roi, bool half, bool blurred_set,
                      std::vector<cv::KeyPoint>* keypoints, cv::Mat* descriptors) const;
  // The levels of one model set, those within a factor 1.6 of the expected width when it is known (> 0)
  // and there are any.
  ModelRows modelRows(ModelSet set, double expected_face_width_px) const;
  // The image keypoints whose nearest model descriptor passes the ratio test, as texture and image points
  // (full resolution, offset by the region's corner).
  void ratioTestMatches(const cv::Mat& descriptors, const std::vector<cv::KeyPoint>& keypoints, const ModelRows& rows,
                        bool half, cv::Point offset, std::vector<cv::Point2f>* texture_points,
                        std::vector<cv::Point2f>* image_points) const;
  // The RANSAC homography and its inliers into *result; false (with the status) when none or too few.
  bool fitHomography(const std::vector<cv::Point2f>& texture_points, const std::vector<cv::Point2f>& image_points,
                     bool half, FaceMatch* result) const;
  // One level of the model pyramid: the texture at `width`, blurred / smeared as its set is, its keypoints
  // and descriptors appended to the model's.
  void addModelLevel(const cv::Mat& texture_gray, ModelSet set, int width);
  // The sharp levels smeared along their rows (refinement_row_smears_px; refinement only).
  void addRowSmearedLevels();
  void detect(const cv::Mat& image, std::vector<cv::KeyPoint>* keypoints, int max_keypoints) const;
  // Descriptors of the keypoints (those too near the border for them are removed), of the kind the
  // model set (sharp or blurred_set) was described with.
  void describe(const cv::Mat& image, std::vector<cv::KeyPoint>* keypoints, cv::Mat* descriptors,
                bool blurred_set) const;
  void refine(const cv::Mat& gray, FaceMatch* match) const;
  // Empty when the outline (texture corners mapped by the homography) is a plausible view of the face,
  // else why not (not convex, mirrored, too small).
  std::string outlineProblem(const std::vector<cv::Point2f>& outline) const;
  std::vector<cv::Point2f> textureCorners() const;
  // One refinement pass over candidates (texture pixels) with match->homography; false (match
  // unchanged) when too few points survive.
  bool refinePass(const cv::Mat& gray, const std::vector<cv::Point2f>& candidates, FaceMatch* match) const;
  // A pass more on the points the last one kept, at its homography; false (match unchanged) when it fails
  // or its points span less than min_spread_fraction of the last pass's (inlierSpread).
  bool refineKeptAgain(const cv::Mat& gray, double min_spread_fraction, FaceMatch* match) const;
  // The largest distance (px) between the face's corners under two homographies.
  double largestCornerMove(const cv::Matx33d& from, const cv::Matx33d& to) const;
  struct RefinedPoints {
    std::vector<cv::Point2f> texture_points;
    std::vector<cv::Point2f> image_points;
    double mean_correlation = 0.0;  // of the kept points' NCC peaks
  };
  // The model level of one set nearest the face's apparent width.
  const ModelLevel& refinementLevel(double apparent_width, ModelSet set) const;
  // Refinement against the row-smeared levels (refinement_row_smears_px): the smear whose patches
  // correlate best, or none (empty points) when no smear beats `to_beat`.
  RefinedPoints refineAgainstRowSmears(const cv::Mat& gray, double apparent_width,
                                       const std::vector<cv::Point2f>& candidates, const cv::Matx33d& homography,
                                       const cv::Rect& face_box, const RefinedPoints& to_beat, int* smear_px) const;
  // The candidates refined against the sharp model, or against the blurred one (or its row smears) when
  // those patches correlate clearly better (blur_matched_refinement); match notes which.
  RefinedPoints refineAgainstBestModel(const cv::Mat& gray, double apparent_width,
                                       const std::vector<cv::Point2f>& candidates, const cv::Rect& face_box,
                                       FaceMatch* match) const;
  // Each candidate's patch, drawn from `level` with the homography, located in the image by NCC.
  RefinedPoints refineAgainst(const cv::Mat& gray, const ModelLevel& level, const std::vector<cv::Point2f>& candidates,
                              const cv::Matx33d& homography, const cv::Rect& face_box) const;

  FeatureMatcherParams params_;
  cv::Ptr<cv::BRISK> brisk_;
  UprightRingDescriptor upright_descriptor_;
  cv::Mat texture_;
  cv::Size texture_size_;
  std::vector<ModelLevel> levels_;         // widest first
  std::vector<ModelLevel> smeared_levels_;  // refinement_row_smears_px x the widths (refinement only)
  std::vector<cv::Point2f> model_points_;  // texture pixel of each model descriptor row
  cv::Mat model_descriptors_;
};

// Two nearest neighbours (Hamming distance) of each query descriptor among train rows
// [first_row, first_row + row_count). 8-bit descriptors, the same width in both. Exposed for tests.
struct HammingPair {
  int best_index = -1;
  int best_distance = 1 << 30;
  int second_distance = 1 << 30;
};
std::vector<HammingPair> hammingKnn2(const cv::Mat& query, const cv::Mat& train, int first_row, int row_count);

// Zero-mean normalised cross-correlation of a small square 8-bit template at every position inside a
// square 8-bit window: response is (window - template + 1) square, CV_32F, in [-1, 1]; 0 where the
// template or the window patch is flat. Cheaper than cv::matchTemplate at these sizes (11x11 over 7x7
// positions: the refinement runs it for every refined point). Exposed for tests.
void normalisedCrossCorrelation(const cv::Mat& window, const cv::Mat& templ, cv::Mat* response);

// The model drawn into one square patch of the image: each patch pixel (image pixel top_left + (x, y))
// mapped through `image_to_model` into the 8-bit `model` and sampled bilinearly, as cv::warpPerspective
// (INTER_LINEAR, border 0) would draw it; patch is size x size, CV_8U. False when the patch leaves the
// model (a corner outside [-0.5, cols - 0.5) x [-0.5, rows - 0.5), where warpPerspective's nearest-
// neighbour mask is 0): a template must lie on the face. The refinement draws only the patches it
// correlates, not the whole face (at 0.3 m the face fills the image: two full warps cost ~25 M
// instructions a frame). Exposed for tests.
bool renderModelPatch(const cv::Mat& model, const cv::Matx33d& image_to_model, cv::Point top_left, int size,
                      cv::Mat* patch);

}  // namespace mono
}  // namespace docking_perception
