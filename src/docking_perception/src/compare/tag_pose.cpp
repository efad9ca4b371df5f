#include "tag_pose.h"

#include <apriltag/apriltag.h>
#include <apriltag/apriltag_pose.h>
#include <apriltag/tag36h11.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdlib>
#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace compare {
namespace {

[[noreturn]] void fail(const std::string& file, const std::string& field, const std::string& what) {
  throw TagError(file + ": " + field + ": " + what);
}

// Debian's libapriltag.so exports only the detector, family, pose and apriltag_to_image functions, not
// the `common` helpers (matd_destroy, image_u8_destroy). What they free was calloc'ed by the library:
// a matd_t is one block (flexible array member), an image_u8_t a struct plus its buffer.
void freeMatrix(matd_t* m) { std::free(m); }
void freeImage(image_u8_t* im) {
  if (!im) return;
  std::free(im->buf);
  std::free(im);
}

}  // namespace

TagSpec loadTagSpec(const std::string& target_yaml) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(target_yaml);
  } catch (const YAML::Exception& e) {
    throw TagError(target_yaml + ": cannot read: " + e.what());
  }
  const YAML::Node tag = root["target"]["apriltag"];
  if (!tag || !tag.IsMap()) fail(target_yaml, "target.apriltag", "missing (not a tagged target?)");
  TagSpec spec;
  try {
    spec.family = tag["family"] ? tag["family"].as<std::string>() : spec.family;
    if (!tag["id"]) fail(target_yaml, "target.apriltag.id", "missing");
    spec.id = tag["id"].as<int>();
    if (!tag["size_m"]) fail(target_yaml, "target.apriltag.size_m", "missing");
    spec.size_m = tag["size_m"].as<double>();
    const YAML::Node c = tag["center_m"];
    if (c) {
      if (!c.IsSequence() || c.size() != 3) fail(target_yaml, "target.apriltag.center_m", "must be [x, y, z]");
      for (std::size_t i = 0; i < 3; ++i) spec.center_m(static_cast<int>(i)) = c[i].as<double>();
    }
  } catch (const YAML::Exception& e) {
    throw TagError(target_yaml + ": target.apriltag: " + e.what());
  }
  if (spec.family != "tag36h11") fail(target_yaml, "target.apriltag.family", "only tag36h11 is supported");
  if (spec.id < 0 || spec.id >= 587) fail(target_yaml, "target.apriltag.id", "must be in [0, 586] for tag36h11");
  if (!(spec.size_m > 0.0) || !std::isfinite(spec.size_m)) fail(target_yaml, "target.apriltag.size_m", "must be > 0");
  if (std::abs(spec.center_m.x()) > 1e-9) fail(target_yaml, "target.apriltag.center_m", "must lie on the face, x = 0");
  return spec;
}

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

cv::Mat makeTagTexture(const TagSpec& spec, double face_width_m, double face_height_m, double px_per_m, int black,
                       int paper) {
  apriltag_family_t* family = tag36h11_create();
  image_u8_t* tag = apriltag_to_image(family, spec.id);  // total_width cells: the white ring included
  const int cells_black = static_cast<int>(family->width_at_border);
  const double cell_m = spec.size_m / cells_black;
  const int W = static_cast<int>(std::lround(face_width_m * px_per_m));
  const int H = static_cast<int>(std::lround(face_height_m * px_per_m));
  cv::Mat texture(H, W, CV_8UC1, cv::Scalar(paper));
  // Tag centre in texture pixels (u along +y, v along -z, pixel edges at integer coordinates here).
  const double cu = (spec.center_m.y() + face_width_m / 2.0) * px_per_m;
  const double cv_ = (face_height_m / 2.0 - spec.center_m.z()) * px_per_m;
  const int n = tag->width;
  const double half = 0.5 * n * cell_m * px_per_m;
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const uint8_t value = tag->buf[r * tag->stride + c];
      const int u0 = static_cast<int>(std::lround(cu - half + c * cell_m * px_per_m));
      const int u1 = static_cast<int>(std::lround(cu - half + (c + 1) * cell_m * px_per_m));
      const int v0 = static_cast<int>(std::lround(cv_ - half + r * cell_m * px_per_m));
      const int v1 = static_cast<int>(std::lround(cv_ - half + (r + 1) * cell_m * px_per_m));
      const cv::Rect cell = cv::Rect(u0, v0, u1 - u0, v1 - v0) & cv::Rect(0, 0, W, H);
      if (cell.area() > 0) texture(cell).setTo(value < 128 ? black : paper);
    }
  }
  freeImage(tag);
  tag36h11_destroy(family);
  return texture;
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

TagResult TagDetector::detect(const cv::Mat& gray, const mono::CameraIntrinsics& camera) {
  TagResult result;
  const double start = mono::threadCpuTimeMs();
  cv::Mat image = gray;
  if (image.channels() == 3) cv::cvtColor(gray, image, cv::COLOR_BGR2GRAY);
  if (!image.isContinuous()) image = image.clone();
  image_u8_t im{image.cols, image.rows, static_cast<int32_t>(image.step[0]), image.data};
  zarray_t* detections = apriltag_detector_detect(detector_, &im);
  result.detections = zarray_size(detections);
  apriltag_detection_t* best = nullptr;
  for (int i = 0; i < zarray_size(detections); ++i) {
    apriltag_detection_t* det = nullptr;
    zarray_get(detections, i, &det);
    if (det->id == spec_.id && (!best || det->decision_margin > best->decision_margin)) best = det;
  }
  if (best) {
    // apriltag's pixel coordinates put a pixel's centre at (i + 0.5, j + 0.5) (its quad fit adds half a
    // pixel), OpenCV's and camera_info's at (i, j): shifting the principal point by half a pixel is the
    // same as shifting every detected corner back.
    apriltag_detection_info_t info{best, spec_.size_m, camera.fx, camera.fy, camera.cx + 0.5, camera.cy + 0.5};
    apriltag_pose_t pose{nullptr, nullptr};
    result.object_space_error = estimate_tag_pose(&info, &pose);
    Eigen::Isometry3d camera_T_tag = Eigen::Isometry3d::Identity();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) camera_T_tag.linear()(r, c) = MATD_EL(pose.R, r, c);
      camera_T_tag.translation()(r) = MATD_EL(pose.t, r, 0);
    }
    freeMatrix(pose.R);
    freeMatrix(pose.t);
    result.camera_T_target = cameraTTargetFromTag(camera_T_tag, spec_);
    result.decision_margin = best->decision_margin;
    result.hamming = best->hamming;
    result.found = std::isfinite(result.camera_T_target.translation().norm());
    if (!result.found) result.status = "pose not finite";
  } else {
    result.status = result.detections ? "tag " + std::to_string(spec_.id) + " not among the detections" : "no tag detected";
  }
  apriltag_detections_destroy(detections);
  result.processing_time_ms = mono::threadCpuTimeMs() - start;
  return result;
}

}  // namespace compare
}  // namespace docking_perception
