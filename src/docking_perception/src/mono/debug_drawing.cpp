#include "docking_perception/mono/debug_drawing.h"

#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "docking_perception/debug_caption.h"

namespace docking_perception {
namespace mono {
namespace {

cv::Point2f toPoint(const Eigen::Vector2d& p) { return {static_cast<float>(p.x()), static_cast<float>(p.y())}; }

}  // namespace

cv::Mat drawDebugImage(const cv::Mat& image, const MonoPoseResult& result, const CameraIntrinsics& camera,
                       const TargetModel& model) {
  cv::Mat canvas;
  if (image.empty()) {
    canvas = cv::Mat(std::max(camera.height, 1), std::max(camera.width, 1), CV_8UC3, cv::Scalar(0, 0, 0));
  } else if (image.channels() == 1) {
    cv::cvtColor(image, canvas, cv::COLOR_GRAY2BGR);
  } else {
    canvas = image.clone();
  }
  if (result.search_region.area() > 0) cv::rectangle(canvas, result.search_region, cv::Scalar(90, 90, 90), 1);
  for (const cv::Point2f& p : result.matched_points) cv::circle(canvas, p, 2, cv::Scalar(160, 160, 160), 1);
  for (const cv::Point2f& p : result.inlier_points) cv::circle(canvas, p, 2, cv::Scalar(0, 220, 0), cv::FILLED);
  if (result.face_outline.size() == 4) {
    std::vector<cv::Point> outline;
    for (const cv::Point2f& p : result.face_outline) outline.emplace_back(cvRound(p.x), cvRound(p.y));
    cv::polylines(canvas, outline, true, cv::Scalar(0, 220, 220), 1, cv::LINE_AA);
  }
  for (const Eigen::Vector2d& p : result.blob_pixels) cv::circle(canvas, toPoint(p), 6, cv::Scalar(0, 140, 255), 1);
  for (const Eigen::Vector2d& p : result.marker_pixels) cv::circle(canvas, toPoint(p), 4, cv::Scalar(0, 0, 255), 2);

  if (result.valid) {
    auto project = [&](const Eigen::Vector3d& point) {
      return toPoint(camera.project(result.pose.rotation * point + result.pose.translation));
    };
    const std::vector<Eigen::Vector3d> corners = model.faceCorners();
    for (size_t i = 0; i < corners.size(); ++i) {
      cv::line(canvas, project(corners[i]), project(corners[(i + 1) % corners.size()]), cv::Scalar(255, 255, 0), 2,
               cv::LINE_AA);
    }
    const double axis = 0.5 * std::min(model.faceWidth(), model.faceHeight());
    const cv::Point2f origin = project(Eigen::Vector3d::Zero());
    cv::line(canvas, origin, project(Eigen::Vector3d(axis, 0.0, 0.0)), cv::Scalar(0, 0, 255), 2, cv::LINE_AA);
    cv::line(canvas, origin, project(Eigen::Vector3d(0.0, axis, 0.0)), cv::Scalar(0, 255, 0), 2, cv::LINE_AA);
    cv::line(canvas, origin, project(Eigen::Vector3d(0.0, 0.0, axis)), cv::Scalar(255, 0, 0), 2, cv::LINE_AA);
  }
  char text[256];
  if (result.valid) {
    std::snprintf(text, sizeof(text), "%.3f m  %d inliers  %.2f px", result.range_m, result.feature_inliers,
                  result.reprojection_error_px);
  } else {
    std::snprintf(text, sizeof(text), "no pose: %s", result.status.c_str());
  }
  drawCaption(canvas, text, result.valid ? cv::Scalar(0, 255, 0) : cv::Scalar(0, 0, 255));
  return canvas;
}

}  // namespace mono
}  // namespace docking_perception
