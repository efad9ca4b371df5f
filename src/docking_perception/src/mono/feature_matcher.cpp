#include "docking_perception/mono/feature_matcher.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace mono {
namespace {

double signedArea(const std::vector<cv::Point2f>& polygon) {
  double area = 0.0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const cv::Point2f& a = polygon[i];
    const cv::Point2f& b = polygon[(i + 1) % polygon.size()];
    area += static_cast<double>(a.x) * b.y - static_cast<double>(b.x) * a.y;
  }
  return 0.5 * area;
}

}  // namespace

FeatureMatcher::FeatureMatcher(const FeatureMatcherParams& params) : params_(params) {
  brisk_ = cv::BRISK::create(params_.brisk_threshold, params_.brisk_octaves);
}

void FeatureMatcher::setParams(const FeatureMatcherParams& params) {
  const bool rebuild = params.brisk_threshold != params_.brisk_threshold ||
                       params.brisk_octaves != params_.brisk_octaves ||
                       params.model_widths_px != params_.model_widths_px;
  params_ = params;
  if (rebuild) {
    brisk_ = cv::BRISK::create(params_.brisk_threshold, params_.brisk_octaves);
    if (!texture_.empty()) buildModel(texture_, nullptr);
  }
}

bool FeatureMatcher::buildModel(const cv::Mat& texture_gray, std::string* reason) {
  texture_ = texture_gray;
  texture_size_ = texture_gray.size();
  model_points_.clear();
  model_descriptors_ = cv::Mat();
  if (texture_gray.empty() || texture_gray.type() != CV_8UC1) {
    if (reason) *reason = "the model texture must be a non-empty 8-bit gray image";
    return false;
  }
  for (const int width : params_.model_widths_px) {
    if (width <= 16) continue;
    const double scale = static_cast<double>(width) / texture_gray.cols;
    cv::Mat scaled;
    if (std::abs(scale - 1.0) < 1e-3) {
      scaled = texture_gray;
    } else {
      cv::resize(texture_gray, scaled, cv::Size(), scale, scale, scale < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR);
    }
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    brisk_->detectAndCompute(scaled, cv::noArray(), keypoints, descriptors);
    for (const cv::KeyPoint& kp : keypoints) {
      // Back to full-texture pixels (pixel centres at integers in both).
      model_points_.emplace_back(static_cast<float>((kp.pt.x + 0.5) / scale - 0.5),
                                 static_cast<float>((kp.pt.y + 0.5) / scale - 0.5));
    }
    if (!descriptors.empty()) model_descriptors_.push_back(descriptors);
  }
  if (static_cast<int>(model_points_.size()) < params_.min_inliers) {
    if (reason) {
      *reason = "the model texture gives only " + std::to_string(model_points_.size()) +
                " BRISK keypoints (need at least min_inliers = " + std::to_string(params_.min_inliers) + ")";
    }
    return false;
  }
  return true;
}

FaceMatch FeatureMatcher::match(const cv::Mat& gray, const cv::Rect& roi_in) const {
  FaceMatch result;
  if (model_descriptors_.empty()) {
    result.status = "no model features";
    return result;
  }
  if (gray.empty() || gray.type() != CV_8UC1) {
    result.status = "image is not 8-bit gray";
    return result;
  }
  const cv::Rect full(0, 0, gray.cols, gray.rows);
  const cv::Rect roi = roi_in.area() > 0 ? (roi_in & full) : full;
  if (roi.width < 16 || roi.height < 16) {
    result.status = "search region too small";
    return result;
  }
  std::vector<cv::KeyPoint> keypoints;
  const cv::Mat view = gray(roi);
  brisk_->detect(view, keypoints);
  if (static_cast<int>(keypoints.size()) > params_.max_image_keypoints) {
    cv::KeyPointsFilter::retainBest(keypoints, params_.max_image_keypoints);
  }
  cv::Mat descriptors;
  brisk_->compute(view, keypoints, descriptors);
  result.keypoints = static_cast<int>(keypoints.size());
  if (keypoints.size() < 4) {
    result.status = "too few image keypoints (" + std::to_string(keypoints.size()) + ")";
    return result;
  }

  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(descriptors, model_descriptors_, knn, 2);
  std::vector<cv::Point2f> texture_points;
  std::vector<cv::Point2f> image_points;
  for (const auto& pair : knn) {
    if (pair.size() < 2) continue;
    if (pair[0].distance >= params_.ratio * pair[1].distance) continue;
    const cv::Point2f& p = keypoints[static_cast<size_t>(pair[0].queryIdx)].pt;
    texture_points.push_back(model_points_[static_cast<size_t>(pair[0].trainIdx)]);
    image_points.emplace_back(p.x + roi.x, p.y + roi.y);
  }
  result.matches = static_cast<int>(image_points.size());
  result.matched_image_points = image_points;
  if (result.matches < params_.min_inliers) {
    result.status = "too few matches (" + std::to_string(result.matches) + " < " +
                    std::to_string(params_.min_inliers) + ")";
    return result;
  }
  std::vector<unsigned char> inlier_mask;
  const cv::Mat homography =
      cv::findHomography(texture_points, image_points, cv::RANSAC, params_.ransac_threshold_px, inlier_mask, 2000, 0.995);
  if (homography.empty()) {
    result.status = "no homography";
    return result;
  }
  for (size_t i = 0; i < inlier_mask.size(); ++i) {
    if (!inlier_mask[i]) continue;
    result.inlier_texture_points.push_back(texture_points[i]);
    result.inlier_image_points.push_back(image_points[i]);
  }
  result.inliers = static_cast<int>(result.inlier_image_points.size());
  if (result.inliers < params_.min_inliers) {
    result.status = "too few inliers (" + std::to_string(result.inliers) + " < " +
                    std::to_string(params_.min_inliers) + ")";
    return result;
  }
  result.homography = cv::Matx33d(homography);
  const float w = static_cast<float>(texture_size_.width) - 0.5f;
  const float h = static_cast<float>(texture_size_.height) - 0.5f;
  const std::vector<cv::Point2f> corners = {{-0.5f, -0.5f}, {w, -0.5f}, {w, h}, {-0.5f, h}};
  cv::perspectiveTransform(corners, result.face_outline, homography);
  // A real view of the face: a convex outline of plausible size, not mirrored.
  const double area = signedArea(result.face_outline);
  if (!cv::isContourConvex(result.face_outline)) {
    result.status = "matched face outline is not convex";
    return result;
  }
  if (area * signedArea(corners) <= 0.0) {
    result.status = "matched face is mirrored";
    return result;
  }
  if (std::abs(area) < params_.min_face_area_px) {
    result.status = "matched face too small";
    return result;
  }
  result.found = true;
  return result;
}

}  // namespace mono
}  // namespace docking_perception
