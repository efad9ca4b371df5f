// The known target as mono_pose sees it: the textured docking face (plane x = 0 of frame `target`),
// its texture image, and the 5 reference markers of the paper's solver. Read from config/target.yaml,
// the same file the simulator renders from.
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "docking_perception/mono/apriltag_pose.h"

namespace docking_perception {
namespace mono {

// Raised for a missing or invalid file or field; the message names the file and the field.
class TargetModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Marker roles of the 5-point pattern: triple A = (0, 1, 2) with 1 at the midpoint of 0 and 2; triple
// B = (2, 3, 4) with 3 at the midpoint of 2 and 4; marker 2 is the shared end of both.
constexpr int kMarkerCount = 5;
using MarkerPoints = std::array<Eigen::Vector3d, kMarkerCount>;

class TargetModel {
 public:
  // Reads the yaml file and the texture it names (path relative to the yaml's folder). Throws
  // TargetModelError naming the file and field on any problem.
  static TargetModel loadFromYaml(const std::string& yaml_path, bool load_texture = true);

  // Builds a model from parts (tests, other tools). The texture may be empty (IR-only use) or 8-bit
  // gray / BGR. Throws TargetModelError (source named "<parts>") when the parts are inconsistent.
  static TargetModel fromParts(double face_width_m, double face_height_m, const MarkerPoints& markers_m,
                               double marker_radius_m, double led_radius_m, const cv::Mat& texture);

  double faceWidth() const { return face_width_m_; }
  double faceHeight() const { return face_height_m_; }
  const MarkerPoints& markers() const { return markers_m_; }
  double markerRadius() const { return marker_radius_m_; }
  double ledRadius() const { return led_radius_m_; }
  const std::string& frameId() const { return frame_id_; }
  // 8-bit single channel texture (empty when not loaded).
  const cv::Mat& textureGray() const { return texture_gray_; }
  bool hasTexture() const { return !texture_gray_.empty(); }
  // The optional inner pattern (target.inner_pattern): a tag near the port for close range.
  bool hasInnerPattern() const { return has_inner_pattern_; }
  const TagSpec& innerPattern() const { return inner_pattern_; }
  void setInnerPattern(const TagSpec& tag) {
    inner_pattern_ = tag;
    has_inner_pattern_ = true;
  }

  // Texture pixel (OpenCV convention: pixel centres at integer coordinates) -> point on the face, m.
  Eigen::Vector3d texturePixelToPoint(const cv::Point2f& pixel) const;
  // Point on the face -> texture pixel (the inverse of the above; x is ignored).
  cv::Point2d pointToTexturePixel(const Eigen::Vector3d& point) const;
  // The 3x3 map of homogeneous texture pixels (u, v, 1) to face coordinates (y, z, 1).
  Eigen::Matrix3d textureToFace() const;
  // Face corners in frame `target`, in the order top-left, top-right, bottom-right, bottom-left as seen
  // by a viewer in front of the face (texture corners (0,0), (W,0), (W,H), (0,H)).
  std::vector<Eigen::Vector3d> faceCorners() const;

 private:
  static void validate(const std::string& source, double width, double height, const MarkerPoints& markers,
                       double marker_radius, double led_radius);

  std::string frame_id_ = "target";
  double face_width_m_ = 0.0;
  double face_height_m_ = 0.0;
  MarkerPoints markers_m_{};
  double marker_radius_m_ = 0.0;
  double led_radius_m_ = 0.0;
  cv::Mat texture_gray_;
  bool has_inner_pattern_ = false;
  TagSpec inner_pattern_;
};

}  // namespace mono
}  // namespace docking_perception
