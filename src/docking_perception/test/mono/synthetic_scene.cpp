#include "synthetic_scene.h"

#include <Eigen/Geometry>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace mono {
namespace synthetic {

MarkerPoints defaultMarkers() {
  return {Eigen::Vector3d(0.0, 0.11, 0.09), Eigen::Vector3d(0.0, 0.0, 0.09), Eigen::Vector3d(0.0, -0.11, 0.09),
          Eigen::Vector3d(0.0, -0.11, 0.01), Eigen::Vector3d(0.0, -0.11, -0.07)};
}

CameraIntrinsics defaultCamera() {
  CameraIntrinsics camera;
  camera.fx = 550.0;
  camera.fy = 550.0;
  camera.cx = 319.5;
  camera.cy = 239.5;
  camera.width = 640;
  camera.height = 480;
  return camera;
}

cv::Mat makeTexture(uint64_t seed, int cols, int rows) {
  cv::RNG rng(seed);
  cv::Mat texture(rows, cols, CV_8UC1, cv::Scalar(150));
  // Busy, high-contrast clutter: filled rectangles, circles, lines and small text, as on a mockup.
  for (int i = 0; i < 260; ++i) {
    const cv::Point p(rng.uniform(0, cols), rng.uniform(0, rows));
    const int shade = rng.uniform(0, 256);
    switch (rng.uniform(0, 4)) {
      case 0:
        cv::rectangle(texture, p, p + cv::Point(rng.uniform(6, 60), rng.uniform(6, 60)), cv::Scalar(shade), cv::FILLED);
        break;
      case 1:
        cv::circle(texture, p, rng.uniform(3, 25), cv::Scalar(shade), cv::FILLED);
        break;
      case 2:
        cv::line(texture, p, p + cv::Point(rng.uniform(-80, 80), rng.uniform(-80, 80)), cv::Scalar(shade),
                 rng.uniform(1, 4));
        break;
      default: {
        const std::string letters = std::string(1, static_cast<char>('A' + rng.uniform(0, 26))) +
                                    static_cast<char>('A' + rng.uniform(0, 26));
        cv::putText(texture, letters, p, cv::FONT_HERSHEY_SIMPLEX, rng.uniform(0.6, 1.4), cv::Scalar(shade), 2);
      }
    }
  }
  const MarkerPoints markers = defaultMarkers();
  const double px_per_m = cols / 0.30;
  for (const Eigen::Vector3d& m : markers) {
    const cv::Point2d centre(cols / 2.0 - 0.5 + m.y() * px_per_m, rows / 2.0 - 0.5 - m.z() * px_per_m);
    // Fixed-point drawing (shift 4) keeps the dot centred to 1/16 px.
    const cv::Point centre_fixed(static_cast<int>(std::lround(centre.x * 16)), static_cast<int>(std::lround(centre.y * 16)));
    cv::circle(texture, centre_fixed, static_cast<int>(std::lround(0.018 * px_per_m * 16)), cv::Scalar(245),
               cv::FILLED, cv::LINE_AA, 4);
    cv::circle(texture, centre_fixed, static_cast<int>(std::lround(0.010 * px_per_m * 16)), cv::Scalar(15),
               cv::FILLED, cv::LINE_AA, 4);
  }
  return texture;
}

TargetModel makeModel(uint64_t seed) {
  return TargetModel::fromParts(0.30, 0.24, defaultMarkers(), 0.010, 0.005, makeTexture(seed));
}

Eigen::Matrix3d facingRotation(double yaw, double pitch, double roll) {
  Eigen::Matrix3d facing;
  // Columns: target x (face normal) towards the camera (-z), target y to the image right (+x),
  // target z up in the image (-y).
  facing << 0.0, 1.0, 0.0,  //
      0.0, 0.0, -1.0,        //
      -1.0, 0.0, 0.0;
  return facing * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
         Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()).toRotationMatrix() *
         Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()).toRotationMatrix();
}

void drawInnerPattern(cv::Mat* image, const TagSpec& tag, const CameraIntrinsics& camera,
                      const Eigen::Isometry3d& camera_T_target) {
  const cv::Mat cells = tagCells(tag);
  const int px_per_cell = 40;
  cv::Mat print;
  cv::resize(cells, print, cv::Size(), px_per_cell, px_per_cell, cv::INTER_NEAREST);
  print = 25 + print / 255 * 215;
  // Print pixel (u, v) (edges at -0.5 .. n*px - 0.5) -> point on the face -> image.
  const double n = cells.cols;
  const double cell_m = tag.size_m / (n - 2);
  const Eigen::Isometry3d camera_T_tag = camera_T_target * targetTTag(tag);
  std::vector<cv::Point2f> src, dst;
  for (const auto& uv : {cv::Point2f(0, 0), cv::Point2f(1, 0), cv::Point2f(1, 1), cv::Point2f(0, 1)}) {
    src.emplace_back(static_cast<float>(uv.x * n * px_per_cell - 0.5), static_cast<float>(uv.y * n * px_per_cell - 0.5));
    const Eigen::Vector3d p = camera_T_tag * Eigen::Vector3d((uv.x - 0.5) * n * cell_m, (uv.y - 0.5) * n * cell_m, 0.0);
    const Eigen::Vector2d q = camera.project(p);
    dst.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()));
  }
  cv::warpPerspective(print, *image, cv::getPerspectiveTransform(src, dst), image->size(), cv::INTER_LINEAR,
                      cv::BORDER_TRANSPARENT);
}

cv::Mat renderVisible(const TargetModel& model, const CameraIntrinsics& camera, const Eigen::Matrix3d& rotation,
                      const Eigen::Vector3d& translation, uint64_t seed, double noise_sigma, bool with_inner_pattern) {
  cv::RNG rng(seed);
  cv::Mat background(camera.height, camera.width, CV_8UC1);
  rng.fill(background, cv::RNG::UNIFORM, 40, 200);
  cv::GaussianBlur(background, background, cv::Size(0, 0), 6.0);

  Eigen::Matrix3d k;
  k << camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0;
  Eigen::Matrix3d plane;
  plane.col(0) = rotation.col(1);
  plane.col(1) = rotation.col(2);
  plane.col(2) = translation;
  // Pre-filter the texture (pyramid) so that the warp does not alias when the face is small.
  cv::Mat texture = model.textureGray();
  Eigen::Matrix3d level_to_base = Eigen::Matrix3d::Identity();
  const double face_px = camera.fx * model.faceWidth() / translation.z();
  while (texture.cols > 2.0 * face_px) {
    cv::Mat down;
    cv::pyrDown(texture, down);
    texture = down;
    Eigen::Matrix3d step;
    step << 2.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 1.0;  // pyrDown: level pixel i is centred on 2i
    level_to_base = level_to_base * step;
  }
  const Eigen::Matrix3d h = k * plane * model.textureToFace() * level_to_base;
  cv::Matx33d h_cv;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) h_cv(r, c) = h(r, c);
  cv::Mat image = background.clone();
  cv::warpPerspective(texture, image, h_cv, image.size(), cv::INTER_LINEAR, cv::BORDER_TRANSPARENT);
  if (with_inner_pattern && model.hasInnerPattern()) {
    Eigen::Isometry3d camera_T_target = Eigen::Isometry3d::Identity();
    camera_T_target.linear() = rotation;
    camera_T_target.translation() = translation;
    drawInnerPattern(&image, model.innerPattern(), camera, camera_T_target);
  }
  if (noise_sigma > 0.0) {
    cv::Mat noise(image.size(), CV_16SC1);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_sigma);
    cv::Mat image16;
    image.convertTo(image16, CV_16SC1);
    image16 += noise;
    image16.convertTo(image, CV_8UC1);
  }
  return image;
}

void drawSpot(cv::Mat* image, const Eigen::Vector2d& centre, double sigma_px, double peak) {
  const int reach = static_cast<int>(std::ceil(4.0 * sigma_px)) + 1;
  for (int y = static_cast<int>(centre.y()) - reach; y <= static_cast<int>(centre.y()) + reach; ++y) {
    for (int x = static_cast<int>(centre.x()) - reach; x <= static_cast<int>(centre.x()) + reach; ++x) {
      if (x < 0 || y < 0 || x >= image->cols || y >= image->rows) continue;
      const double d2 = (x - centre.x()) * (x - centre.x()) + (y - centre.y()) * (y - centre.y());
      const double value = image->at<uint8_t>(y, x) + peak * std::exp(-0.5 * d2 / (sigma_px * sigma_px));
      image->at<uint8_t>(y, x) = static_cast<uint8_t>(std::min(255.0, value));
    }
  }
}

cv::Mat renderLedSpots(const CameraIntrinsics& camera, const std::vector<Eigen::Vector3d>& points_camera,
                       double led_radius_m, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat image(camera.height, camera.width, CV_8UC1);
  rng.fill(image, cv::RNG::NORMAL, 20.0, 4.0);
  for (const Eigen::Vector3d& p : points_camera) {
    // A saturating spot slightly larger than the emitting disc (bloom), at least ~1.2 px sigma.
    const double sigma = std::max(1.2, 0.8 * camera.fx * led_radius_m / p.z());
    drawSpot(&image, camera.project(p), sigma, 400.0);
  }
  return image;
}

}  // namespace synthetic
}  // namespace mono
}  // namespace docking_perception
