#include "synthetic_tag_view.h"

#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace compare {

cv::Mat renderFaceView(const cv::Mat& texture, double face_width_m, double face_height_m,
                       const mono::CameraIntrinsics& camera, const Eigen::Isometry3d& camera_T_target,
                       double noise_sigma, int background, unsigned seed) {
  constexpr int kSuper = 4;
  const double ppm_u = texture.cols / face_width_m, ppm_v = texture.rows / face_height_m;
  // Texture pixel centre (i, j) -> face point (y, z).
  Eigen::Matrix3d A;
  A << 1.0 / ppm_u, 0, 0.5 / ppm_u - face_width_m / 2.0, 0, -1.0 / ppm_v, face_height_m / 2.0 - 0.5 / ppm_v, 0, 0, 1;
  // Supersampled camera: pixel centres of the fine grid map to ((x + 0.5) / k - 0.5) of the output.
  Eigen::Matrix3d K;
  K << camera.fx * kSuper, 0, (camera.cx + 0.5) * kSuper - 0.5, 0, camera.fy * kSuper, (camera.cy + 0.5) * kSuper - 0.5,
      0, 0, 1;
  Eigen::Matrix3d M;
  M.col(0) = camera_T_target.linear().col(1);
  M.col(1) = camera_T_target.linear().col(2);
  M.col(2) = camera_T_target.translation();
  const Eigen::Matrix3d H = K * M * A;
  cv::Matx33d Hcv;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Hcv(r, c) = H(r, c);
  cv::Mat fine(camera.height * kSuper, camera.width * kSuper, CV_8UC1, cv::Scalar(background));
  cv::warpPerspective(texture, fine, Hcv, fine.size(), cv::INTER_LINEAR, cv::BORDER_TRANSPARENT);
  cv::Mat image;
  cv::resize(fine, image, cv::Size(camera.width, camera.height), 0, 0, cv::INTER_AREA);
  if (noise_sigma > 0) {
    cv::Mat noise(image.size(), CV_16SC1);
    cv::RNG rng(seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_sigma);
    cv::Mat sum;
    image.convertTo(sum, CV_16SC1);
    sum += noise;
    sum.convertTo(image, CV_8UC1);
  }
  return image;
}

}  // namespace compare
}  // namespace docking_perception
