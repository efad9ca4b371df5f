#include "docking_perception/mono/apriltag_pose.h"

#include <apriltag/apriltag.h>
#include <apriltag/apriltag_pose.h>
#include <apriltag/tag36h11.h>

#include <cmath>
#include <cstdlib>
#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace mono {
namespace {

// Debian's libapriltag.so exports only the detector, family, pose and apriltag_to_image functions, not
// the `common` helpers (matd_destroy): a matd_t is one calloc'ed block (flexible array member).
void freeMatrix(matd_t* m) { std::free(m); }
// ... and an image_u8_t a calloc'ed struct plus its buffer (image_u8_destroy is not exported either).
void freeImage(image_u8_t* im) {
  if (!im) return;
  std::free(im->buf);
  std::free(im);
}

// camera <- target from apriltag's own pose of one detection (the region's offset undone).
Eigen::Isometry3d tagPose(const TagSpec& spec, apriltag_detection_t* detection, const CameraIntrinsics& camera,
                          const cv::Rect& region, double* object_space_error) {
  // apriltag's pixel coordinates put a pixel's centre at (i + 0.5, j + 0.5) (its quad fit adds half a
  // pixel), OpenCV's and camera_info's at (i, j): shifting the principal point by half a pixel is the
  // same as shifting every detected corner back.
  apriltag_detection_info_t info{detection, spec.size_m, camera.fx, camera.fy, camera.cx + 0.5 - region.x,
                                 camera.cy + 0.5 - region.y};
  apriltag_pose_t pose{nullptr, nullptr};
  *object_space_error = estimate_tag_pose(&info, &pose);
  Eigen::Isometry3d camera_T_tag = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) camera_T_tag.linear()(r, c) = MATD_EL(pose.R, r, c);
    camera_T_tag.translation()(r) = MATD_EL(pose.t, r, 0);
  }
  freeMatrix(pose.R);
  freeMatrix(pose.t);
  return cameraTTargetFromTag(camera_T_tag, spec);
}

}  // namespace

Eigen::Isometry3d targetTTag(const TagSpec& spec) {
  Eigen::Matrix3d R;
  // Columns: the tag's x, y, z axes in frame `target`.
  R.col(0) = Eigen::Vector3d(0, 1, 0);
  R.col(1) = Eigen::Vector3d(0, 0, -1);
  R.col(2) = Eigen::Vector3d(-1, 0, 0);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = spec.center_m;
  return T;
}

Eigen::Isometry3d cameraTTargetFromTag(const Eigen::Isometry3d& camera_T_tag, const TagSpec& spec) {
  return camera_T_tag * targetTTag(spec).inverse();
}

cv::Mat tagCells(const TagSpec& spec) {
  if (spec.family != "tag36h11") throw TagError("only tag36h11 is supported, not " + spec.family);
  apriltag_family_t* family = tag36h11_create();
  image_u8_t* tag = apriltag_to_image(family, static_cast<uint32_t>(spec.id));
  cv::Mat cells(tag->height, tag->width, CV_8UC1);
  for (int r = 0; r < tag->height; ++r) {
    for (int c = 0; c < tag->width; ++c) cells.at<uchar>(r, c) = tag->buf[r * tag->stride + c] < 128 ? 0 : 255;
  }
  freeImage(tag);
  tag36h11_destroy(family);
  return cells;
}

std::array<Eigen::Vector3d, 4> tagCornersInTarget(const TagSpec& spec) {
  const Eigen::Isometry3d T = targetTTag(spec);
  const double h = spec.size_m / 2.0;
  return {T * Eigen::Vector3d(-h, h, 0), T * Eigen::Vector3d(h, h, 0), T * Eigen::Vector3d(h, -h, 0),
          T * Eigen::Vector3d(-h, -h, 0)};
}

TagDetector::TagDetector(const TagSpec& spec, int nthreads, double quad_decimate) : spec_(spec) {
  if (spec.family != "tag36h11") throw TagError("only tag36h11 is supported, not " + spec.family);
  family_ = tag36h11_create();
  detector_ = apriltag_detector_create();
  apriltag_detector_add_family(detector_, family_);
  detector_->nthreads = nthreads;
  detector_->quad_decimate = static_cast<float>(quad_decimate);
}

TagDetector::~TagDetector() {
  apriltag_detector_destroy(detector_);
  tag36h11_destroy(family_);
}

TagResult TagDetector::detect(const cv::Mat& gray, const CameraIntrinsics& camera, const cv::Rect& roi,
                              TagOutput output) {
  TagResult result;
  const double start = threadCpuTimeMs();
  cv::Mat image = gray;
  if (image.channels() == 3) cv::cvtColor(gray, image, cv::COLOR_BGR2GRAY);
  const cv::Rect whole(0, 0, image.cols, image.rows);
  const cv::Rect region = roi.area() > 0 ? (roi & whole) : whole;
  // The region as a strided view of the image: apriltag reads rows `stride` bytes apart.
  image_u8_t im{region.width, region.height, static_cast<int32_t>(image.step[0]),
                region.area() > 0 ? image.ptr<uint8_t>(region.y) + region.x : image.data};
  if (region.area() <= 0 || region.width < 16 || region.height < 16) {
    result.status = "search region outside the image";
    result.processing_time_ms = threadCpuTimeMs() - start;
    return result;
  }
  zarray_t* detections = apriltag_detector_detect(detector_, &im);
  result.detections = zarray_size(detections);
  apriltag_detection_t* best = nullptr;
  for (int i = 0; i < zarray_size(detections); ++i) {
    apriltag_detection_t* det = nullptr;
    zarray_get(detections, i, &det);
    if (det->id == spec_.id && (!best || det->decision_margin > best->decision_margin)) best = det;
  }
  if (best) {
    result.decision_margin = best->decision_margin;
    result.hamming = best->hamming;
    bool corners_finite = true;
    for (int k = 0; k < 4; ++k) {
      result.corners_px[k] = Eigen::Vector2d(best->p[k][0] - 0.5 + region.x, best->p[k][1] - 0.5 + region.y);
      corners_finite = corners_finite && result.corners_px[k].allFinite();
    }
    result.found = corners_finite;
    if (!result.found) result.status = "corners not finite";
    if (result.found && output == TagOutput::kCornersAndPose) {
      result.camera_T_target = tagPose(spec_, best, camera, region, &result.object_space_error);
      result.found = std::isfinite(result.camera_T_target.translation().norm());
      if (!result.found) result.status = "pose not finite";
    }
  } else {
    result.status = result.detections ? "tag " + std::to_string(spec_.id) + " not among the detections" : "no tag detected";
  }
  apriltag_detections_destroy(detections);
  result.processing_time_ms = threadCpuTimeMs() - start;
  return result;
}

}  // namespace mono
}  // namespace docking_perception
