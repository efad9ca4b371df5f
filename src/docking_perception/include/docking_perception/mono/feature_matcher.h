// Finds the textured target face in an image: BRISK keypoints of the model texture computed once (at a
// few texture widths, so that the face's apparent size from 0.4 m to 2 m is covered), BRISK on the
// image (or a region of it), 2-nearest-neighbour Hamming matching with Lowe's ratio test, and a RANSAC
// homography from texture pixels to image pixels.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <string>
#include <vector>

namespace docking_perception {
namespace mono {

struct FeatureMatcherParams {
  int brisk_threshold = 30;        // AGAST score threshold of BRISK
  int brisk_octaves = 3;
  int max_image_keypoints = 800;   // strongest kept before descriptors are computed (bounds the time)
  std::vector<int> model_widths_px = {480, 240, 120};  // texture widths at which model features are taken
  double ratio = 0.8;              // Lowe's ratio test
  double ransac_threshold_px = 3.0;
  int min_inliers = 12;
  double min_face_area_px = 600.0; // the matched face outline must be at least this big
};

struct FaceMatch {
  bool found = false;
  std::string status;               // why not found
  int keypoints = 0;                // image keypoints with descriptors
  int matches = 0;                  // after the ratio test
  int inliers = 0;                  // of the homography
  cv::Matx33d homography = cv::Matx33d::eye();  // texture pixel -> image pixel
  std::vector<cv::Point2f> matched_image_points;  // all ratio-test matches (for the debug image)
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
  // Changing BRISK or model parameters rebuilds the model features from the stored texture.
  void setParams(const FeatureMatcherParams& params);
  const FeatureMatcherParams& params() const { return params_; }
  int modelKeypointCount() const { return static_cast<int>(model_points_.size()); }

  // Matches in roi (empty: the whole image) of an 8-bit gray image.
  FaceMatch match(const cv::Mat& gray, const cv::Rect& roi = cv::Rect()) const;

 private:
  FeatureMatcherParams params_;
  cv::Ptr<cv::BRISK> brisk_;
  cv::Mat texture_;
  cv::Size texture_size_;
  std::vector<cv::Point2f> model_points_;  // texture pixel of each model descriptor row
  cv::Mat model_descriptors_;
};

}  // namespace mono
}  // namespace docking_perception
