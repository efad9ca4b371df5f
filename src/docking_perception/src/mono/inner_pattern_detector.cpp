#include "docking_perception/mono/inner_pattern_detector.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>
#include <opencv2/imgproc.hpp>
#include <vector>


namespace docking_perception {
namespace mono {
namespace {

// A tag pose is trusted only from a clear detection of a tag big enough to give a pose: apriltag's decision
// margin at least 30, the shortest edge at least 24 px, at least 10 grid corners refined, their RMS
// residual within 2 px.
constexpr double kMinDecisionMargin = 30.0;
constexpr double kMinTagEdgePx = 24.0;
constexpr int kMinGridPoints = 10;
constexpr double kMaxReprojectionPx = 2.0;
// apriltag's quad_decimate: where the tag is looked for (inner_pattern_use_range_m) it is >= 50 px wide,
// which half resolution finds.
constexpr double kQuadDecimate = 2.0;

std::string fmt(const char* format, double a, double b) {
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer), format, a, b);
  return buffer;
}

}  // namespace

InnerPatternDetector::InnerPatternDetector(const TagSpec& tag) : tag_(tag) {
  if (!(tag.size_m > 0.0)) throw TagError("inner pattern: size_m must be positive");
  // Grid points between cells, inside the white ring: (gx, gy) = 1..n-1 in cell units from the print's
  // top-left. A point is a corner when its 4 cells are neither one colour nor split by a straight edge.
  const cv::Mat cells = tagCells(tag);
  const int n = cells.cols;
  const double cell_m = tag.size_m / (n - 2);
  const Eigen::Isometry3d target_T_tag = targetTTag(tag);
  for (int gy = 1; gy < n; ++gy) {
    for (int gx = 1; gx < n; ++gx) {
      const bool tl = cells.at<uchar>(gy - 1, gx - 1) != 0, tr = cells.at<uchar>(gy - 1, gx) != 0;
      const bool bl = cells.at<uchar>(gy, gx - 1) != 0, br = cells.at<uchar>(gy, gx) != 0;
      const bool uniform = tl == tr && bl == br && tl == bl;
      const bool straight = (tl == tr && bl == br) || (tl == bl && tr == br);
      if (uniform || straight) continue;
      const Eigen::Vector2d xy((gx - 0.5 * n) * cell_m, (gy - 0.5 * n) * cell_m);
      grid_tag_m_.push_back(xy);
      grid_target_m_.push_back(target_T_tag * Eigen::Vector3d(xy.x(), xy.y(), 0.0));
    }
  }
  detector_ = std::make_unique<TagDetector>(tag_, 1, kQuadDecimate);
  PlanarPnpParams pnp;
  // 30-40 grid corners: let the residuals choose between IPPE's two poses unless they really are
  // alike; the previous pose (itself from a coarse tag pose at 0.2-0.3 m) decided wrongly by degrees
  // when both fitted within the face's 0.5 px floor.
  pnp.ambiguity_floor_px = 0.05;
  pnp_.setParams(pnp, kMinPixelSigmaPx);
}

void InnerPatternDetector::refineGrid(const cv::Mat& gray, const std::array<Eigen::Vector2d, 4>& corners,
                                      std::vector<Eigen::Vector3d>* model, std::vector<Eigen::Vector2d>* image) const {
  // Homography tag frame (m) -> image from the black square's corners (tagCornersInTarget's order).
  const double h = tag_.size_m / 2.0;
  const std::vector<cv::Point2f> tag_xy = {{float(-h), float(h)}, {float(h), float(h)}, {float(h), float(-h)},
                                           {float(-h), float(-h)}};
  std::vector<cv::Point2f> pixels;
  for (const auto& c : corners) pixels.emplace_back(float(c.x()), float(c.y()));
  const cv::Matx33d H = cv::getPerspectiveTransform(tag_xy, pixels);
  double shortest_edge = INFINITY;
  for (int k = 0; k < 4; ++k) shortest_edge = std::min(shortest_edge, (corners[(k + 1) % 4] - corners[k]).norm());
  const double cell_px = shortest_edge / 8.0;
  // The search window must stay inside the cells around the corner; wider helps under blur.
  const int half_window = std::max(2, std::min(12, static_cast<int>(0.4 * cell_px)));
  std::vector<cv::Point2f> predicted;
  std::vector<int> index;
  for (std::size_t i = 0; i < grid_tag_m_.size(); ++i) {
    const cv::Vec3d q = H * cv::Vec3d(grid_tag_m_[i].x(), grid_tag_m_[i].y(), 1.0);
    const cv::Point2f p(float(q[0] / q[2]), float(q[1] / q[2]));
    if (p.x < half_window + 1 || p.y < half_window + 1 || p.x > gray.cols - half_window - 2 ||
        p.y > gray.rows - half_window - 2) {
      continue;
    }
    predicted.push_back(p);
    index.push_back(static_cast<int>(i));
  }
  if (predicted.empty()) return;
  std::vector<cv::Point2f> refined = predicted;
  cv::cornerSubPix(gray, refined, cv::Size(half_window, half_window), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.01));
  // A corner that wandered off (blur, a neighbour's pull) is dropped, not trusted.
  const double max_shift = std::max(1.0, 0.3 * cell_px);
  for (std::size_t k = 0; k < refined.size(); ++k) {
    const cv::Point2f d = refined[k] - predicted[k];
    if (!std::isfinite(d.x) || !std::isfinite(d.y) || std::hypot(d.x, d.y) > max_shift) continue;
    model->push_back(grid_target_m_[static_cast<std::size_t>(index[k])]);
    image->emplace_back(refined[k].x, refined[k].y);
  }
}

InnerPatternResult InnerPatternDetector::detect(const cv::Mat& gray, const CameraIntrinsics& camera,
                                                const Eigen::Matrix3d* previous_rotation, const cv::Rect& roi) {
  InnerPatternResult result;
  const double start = threadCpuTimeMs();
  const TagResult tag = detector_->detect(gray, camera, roi, TagOutput::kCornersOnly);  // the grid fit gives the pose
  if (!tag.found) {
    result.status = "inner pattern: " + tag.status;
  } else {
    result.corners_px = tag.corners_px;
    result.decision_margin = tag.decision_margin;
    result.hamming = tag.hamming;
    double shortest_edge = INFINITY;
    for (int k = 0; k < 4; ++k) {
      shortest_edge = std::min(shortest_edge, (tag.corners_px[(k + 1) % 4] - tag.corners_px[k]).norm());
    }
    if (tag.decision_margin < kMinDecisionMargin) {
      result.status = fmt("inner pattern: decision margin %.1f below %.1f", tag.decision_margin, kMinDecisionMargin);
    } else if (shortest_edge < kMinTagEdgePx) {
      result.status = fmt("inner pattern: tag edge %.1f px below %.1f px", shortest_edge, kMinTagEdgePx);
    } else {
      std::vector<Eigen::Vector3d> model;
      std::vector<Eigen::Vector2d> image;
      cv::Mat gray8 = gray;
      if (gray.channels() == 3) cv::cvtColor(gray, gray8, cv::COLOR_BGR2GRAY);
      refineGrid(gray8, tag.corners_px, &model, &image);
      result.candidate_points = static_cast<int>(grid_target_m_.size());
      result.pose_points = static_cast<int>(model.size());
      PlanarPnpSolution solution;
      std::string reason;
      if (static_cast<int>(model.size()) < kMinGridPoints) {
        result.status = fmt("inner pattern: %.0f grid corners refined, fewer than %.0f", double(model.size()),
                            double(kMinGridPoints));
      } else if (!pnp_.solve(camera, model, image, previous_rotation, &solution, &reason)) {
        result.status = "inner pattern: " + reason;
      } else if (solution.reprojection_rms_px > kMaxReprojectionPx) {
        result.status = fmt("inner pattern: reprojection %.2f px above %.2f px", solution.reprojection_rms_px,
                            kMaxReprojectionPx);
      } else if (solution.pose.rotation.col(0).dot(solution.pose.translation) >= 0.0) {
        result.status = "inner pattern: pose shows the back of the face";
      } else {
        result.valid = true;
        result.pose = solution.pose;
        result.reprojection_rms_px = solution.reprojection_rms_px;
        result.model_points = std::move(model);
        result.pnp = solution;
      }
    }
  }
  result.processing_time_ms = threadCpuTimeMs() - start;
  return result;
}

}  // namespace mono
}  // namespace docking_perception
