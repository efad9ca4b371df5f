#include "docking_perception/mono/pose_consistency.h"

#include "docking_perception/mono/face_alignment.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <string>
#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace mono {
namespace {

constexpr double kAppearanceWorkWidthPx = 160.0;  // the face is compared at most this wide (cost)
constexpr int kAppearanceCells = 4;               // cells per side over the face's bounding box
constexpr double kSaturatedLevel = 250.0;         // image pixels at or above: a glint, left out
constexpr double kMinCellStdDev = 4.0;            // template cells flatter than this carry no evidence
const double kTemplateBlurs[] = {0.0, 1.0, 2.0, 3.5};  // px at the working scale

// The appearance score's cells: whole cells of cw x ch px from the top left of the working image.
struct CellGrid {
  int cw;
  int ch;
  int columns;
  int rows;
};

// Sums over the valid (mask != 0) pixels of one cell, in double as cv::meanStdDev keeps them.
struct CellSums {
  double n = 0.0;
  double sum = 0.0;
  double sum2 = 0.0;
};

std::vector<CellSums> imageCellSums(const cv::Mat& image, const cv::Mat& valid, const CellGrid& grid) {
  std::vector<CellSums> sums(static_cast<size_t>(grid.columns * grid.rows));
  for (int y = 0; y < grid.rows * grid.ch; ++y) {
    const uint8_t* im = image.ptr<uint8_t>(y);
    const uint8_t* m = valid.ptr<uint8_t>(y);
    CellSums* row = &sums[static_cast<size_t>((y / grid.ch) * grid.columns)];
    for (int x = 0; x < grid.columns * grid.cw; ++x) {
      if (!m[x]) continue;
      CellSums& c = row[x / grid.cw];
      const double v = im[x];
      c.n += 1.0;
      c.sum += v;
      c.sum2 += v * v;
    }
  }
  return sums;
}

// The normalised cross-correlation of template and image over the valid pixels of each cell (the cells
// at least half valid whose template is not flat); 0 for a flat image cell. One pass over the pixels
// instead of a dozen small OpenCV calls a cell (the appearance check ran on every pose).
std::vector<double> cellCorrelations(const cv::Mat& image, const cv::Mat& templ, const cv::Mat& valid,
                                     const CellGrid& grid, const std::vector<CellSums>& image_sums) {
  std::vector<CellSums> templ_sums(image_sums.size());
  std::vector<double> cross(image_sums.size(), 0.0);
  for (int y = 0; y < grid.rows * grid.ch; ++y) {
    const uint8_t* im = image.ptr<uint8_t>(y);
    const float* t = templ.ptr<float>(y);
    const uint8_t* m = valid.ptr<uint8_t>(y);
    const size_t first = static_cast<size_t>((y / grid.ch) * grid.columns);
    for (int x = 0; x < grid.columns * grid.cw; ++x) {
      if (!m[x]) continue;
      const size_t cell = first + static_cast<size_t>(x / grid.cw);
      const double tv = t[x];
      templ_sums[cell].sum += tv;
      templ_sums[cell].sum2 += tv * tv;
      cross[cell] += tv * im[x];
    }
  }
  std::vector<double> nccs;
  const double cell_area = static_cast<double>(grid.cw) * grid.ch;
  for (size_t cell = 0; cell < image_sums.size(); ++cell) {
    const double n = image_sums[cell].n;
    if (n < std::floor(cell_area / 2.0) || n <= 0.0) continue;
    const double t_mean = templ_sums[cell].sum / n;
    const double t_std = std::sqrt(std::max(0.0, templ_sums[cell].sum2 / n - t_mean * t_mean));
    if (t_std < kMinCellStdDev) continue;
    const double i_mean = image_sums[cell].sum / n;
    const double i_std = std::sqrt(std::max(0.0, image_sums[cell].sum2 / n - i_mean * i_mean));
    if (i_std <= 1e-6) {
      nccs.push_back(0.0);
      continue;
    }
    nccs.push_back((cross[cell] - n * t_mean * i_mean) / (n * t_std * i_std));
  }
  return nccs;
}

// The outer edges of a `size` image's pixels (OpenCV's centres at integers: -0.5 .. size - 0.5) mapped by
// `homography`, clockwise from the top left.
std::vector<cv::Point2f> mappedOutline(const cv::Size& size, const cv::Matx33d& homography) {
  const float w = static_cast<float>(size.width) - 0.5f;
  const float h = static_cast<float>(size.height) - 0.5f;
  std::vector<cv::Point2f> outline;
  cv::perspectiveTransform(std::vector<cv::Point2f>{{-0.5f, -0.5f}, {w, -0.5f}, {w, h}, {-0.5f, h}}, outline,
                           cv::Mat(homography));
  return outline;
}

// The box of `gray` reduced by `scale` (<= 1) by area averaging: first by the whole factor k = floor(1 /
// scale) on a box cropped to multiples of k (OpenCV's fast integer path), then the rest (<= 2x) on the
// small image. One area resize by an arbitrary factor of the whole image cost 4 M instructions a frame
// near contact, where the face fills the image. `box` returns the crop.
cv::Mat workingImage(const cv::Mat& gray, double scale, cv::Rect* box) {
  if (scale >= 1.0) return gray(*box);
  // At most the box's smaller side, so that the crop keeps at least one whole block.
  const int whole = std::clamp(static_cast<int>(std::floor(1.0 / scale)), 1, std::min(box->width, box->height));
  box->width -= box->width % whole;
  box->height -= box->height % whole;
  cv::Mat reduced;
  if (whole > 1) {
    cv::resize(gray(*box), reduced, cv::Size(box->width / whole, box->height / whole), 0, 0, cv::INTER_AREA);
  } else {
    reduced = gray(*box);
  }
  const cv::Size final_size(std::max(1, static_cast<int>(std::lround(box->width * scale))),
                            std::max(1, static_cast<int>(std::lround(box->height * scale))));
  if (final_size == reduced.size()) return reduced;
  cv::Mat image;
  cv::resize(reduced, image, final_size, 0, 0, cv::INTER_AREA);
  return image;
}

// 255 where `warp` maps a pixel of a `source`-sized image (its pixel edges included) into the working
// image, 0 elsewhere: the face's outline filled, as warping an all-white image would give, without the warp.
cv::Mat faceMask(const cv::Size& source, const cv::Matx33d& warp, const cv::Size& work) {
  const std::vector<cv::Point2f> outline = mappedOutline(source, warp);
  constexpr int kShift = 4;  // fixed point: 1/16 px
  std::vector<cv::Point> fixed;
  for (const cv::Point2f& p : outline) {
    fixed.emplace_back(static_cast<int>(std::lround(p.x * (1 << kShift))), static_cast<int>(std::lround(p.y * (1 << kShift))));
  }
  cv::Mat mask(work, CV_8U, cv::Scalar(0));
  cv::fillConvexPoly(mask, fixed, cv::Scalar(255), cv::LINE_8, kShift);
  return mask;
}

}  // namespace

double inlierSpread(const std::vector<cv::Point2f>& texture_points, const cv::Size& texture_size) {
  if (texture_points.size() < 3 || texture_size.area() <= 0) return 0.0;
  std::vector<cv::Point2f> hull;
  cv::convexHull(texture_points, hull);
  return cv::contourArea(hull) / static_cast<double>(texture_size.area());
}

FaceAppearance::FaceAppearance(const TargetModel& model) {
  if (!model.hasTexture()) return;
  pyramid_.push_back(model.textureGray());
  while (pyramid_.back().cols > 40) {
    cv::Mat next;
    cv::pyrDown(pyramid_.back(), next);
    pyramid_.push_back(next);
  }
  texture_to_face_ = model.textureToFace();
}

AppearanceScore FaceAppearance::score(const cv::Mat& gray, const CameraIntrinsics& camera,
                                      const PoseWithCovariance& pose) const {
  AppearanceScore out;
  if (pyramid_.empty() || gray.empty()) return out;
  const cv::Matx33d texture_to_image = faceHomography(texture_to_face_, camera, pose);
  const cv::Size ts = pyramid_.front().size();
  const std::vector<cv::Point2f> outline = mappedOutline(ts, texture_to_image);
  cv::Rect box = cv::boundingRect(outline) & cv::Rect(0, 0, gray.cols, gray.rows);
  if (box.width < 16 || box.height < 16) return out;
  const double face_width = 0.5 * (cv::norm(outline[1] - outline[0]) + cv::norm(outline[2] - outline[3]));
  const double scale = std::min(1.0, kAppearanceWorkWidthPx / std::max(1.0, face_width));
  const cv::Mat image = workingImage(gray, scale, &box);
  // The pyramid level at least as fine as the working face width, warped into the working image.
  size_t level = 0;
  while (level + 1 < pyramid_.size() && pyramid_[level + 1].cols >= face_width * scale) ++level;
  const double level_scale = static_cast<double>(pyramid_[level].cols) / ts.width;
  const cv::Matx33d level_to_texture(1.0 / level_scale, 0.0, 0.5 / level_scale - 0.5, 0.0, 1.0 / level_scale,
                                     0.5 / level_scale - 0.5, 0.0, 0.0, 1.0);
  const cv::Matx33d to_work(scale, 0.0, (0.5 - box.x) * scale - 0.5, 0.0, scale, (0.5 - box.y) * scale - 0.5, 0.0, 0.0,
                            1.0);
  const cv::Matx33d warp = to_work * texture_to_image * level_to_texture;
  cv::Mat rendered;
  cv::warpPerspective(pyramid_[level], rendered, warp, image.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::Mat valid = faceMask(pyramid_[level].size(), warp, image.size());
  cv::erode(valid, valid, cv::Mat(), cv::Point(-1, -1), 2);
  valid.setTo(0, image >= kSaturatedLevel);
  cv::Mat rendered_f;
  rendered.convertTo(rendered_f, CV_32F);
  const int cw = std::max(4, image.cols / kAppearanceCells);
  const int ch = std::max(4, image.rows / kAppearanceCells);
  const CellGrid grid{cw, ch, image.cols / cw, image.rows / ch};
  // The image's own cell sums do not depend on the template's blur: once.
  const std::vector<CellSums> image_sums = imageCellSums(image, valid, grid);
  double best = -2.0;
  for (const double blur : kTemplateBlurs) {
    cv::Mat templ;
    if (blur > 0.0) {
      cv::GaussianBlur(rendered_f, templ, cv::Size(0, 0), blur);
    } else {
      templ = rendered_f;
    }
    std::vector<double> nccs = cellCorrelations(image, templ, valid, grid, image_sums);
    if (nccs.empty()) continue;
    std::nth_element(nccs.begin(), nccs.begin() + static_cast<std::ptrdiff_t>(nccs.size() / 2), nccs.end());
    const double median = nccs[nccs.size() / 2];
    if (median > best) {
      best = median;
      out.median_ncc = median;
      out.blur_sigma_px = blur / scale;
      out.cells = static_cast<int>(nccs.size());
    }
  }
  return out;
}

Matrix6d honestCovariance(const CameraIntrinsics& camera, const PoseWithCovariance& pose,
                          const std::vector<Eigen::Vector3d>& model_points, double residual_rms_px,
                          double min_pixel_sigma, double blur_sigma_px, const ConsistencyParams& params) {
  const double dof = std::max(1.0, 2.0 * static_cast<double>(model_points.size()) - 6.0);
  // residual_rms_px is per point (2D): N rms^2 squared residuals over 2N - 6 degrees of freedom.
  const double residual_sigma = residual_rms_px * std::sqrt(static_cast<double>(model_points.size()) / dof);
  const double pixel_sigma = std::max(residual_sigma, min_pixel_sigma) * (1.0 + params.covariance_blur_gain * blur_sigma_px);
  Matrix6d covariance;
  leastSquaresPoseCovariance(camera, pose.rotation, pose.translation, model_points, pixel_sigma * pixel_sigma,
                             &covariance);
  addCovarianceFloor(pose.translation.norm(), &covariance);
  return covariance;
}

void addCovarianceFloor(double range_m, Matrix6d* covariance) {
  const double position_floor = kPositionFloorFraction * range_m;
  const double rotation_floor = kRotationFloorDeg * M_PI / 180.0;
  for (int i = 0; i < 3; ++i) {
    (*covariance)(i, i) += position_floor * position_floor;
    (*covariance)(3 + i, 3 + i) += rotation_floor * rotation_floor;
  }
}

namespace {
// The sigma along a 3x3 covariance block's worst direction (its largest eigenvalue): a correlated block is
// judged by that, not by its diagonal. Infinite for a non-finite block, which claims nothing.
double largestSigma(const Eigen::Matrix3d& block) {
  if (!block.allFinite()) return std::numeric_limits<double>::infinity();
  const double largest_variance = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(block).eigenvalues().maxCoeff();
  return std::sqrt(std::max(0.0, largest_variance));
}
}  // namespace

bool orientationClaimed(const PoseWithCovariance& pose, const ConsistencyParams& params, std::string* note) {
  const double sigma_deg = largestSigma(pose.covariance.bottomRightCorner<3, 3>()) * 180.0 / M_PI;
  if (sigma_deg <= params.max_rotation_sigma_deg) return true;
  *note = "orientation withheld: rotation sigma " + std::to_string(sigma_deg) + " deg > max_rotation_sigma_deg";
  return false;
}

bool positionClaimed(const PoseWithCovariance& pose, const ConsistencyParams& params, std::string* note) {
  if (params.max_position_sigma_fraction <= 0.0) return true;
  const double range_m = pose.translation.norm();
  const double band_m = params.position_sigma_check_max_range_m;
  if (band_m > 0.0 && range_m >= band_m) return true;  // beyond the band: not checked
  const double sigma_m = largestSigma(pose.covariance.topLeftCorner<3, 3>());
  if (sigma_m <= params.max_position_sigma_fraction * range_m) return true;
  *note = "position withheld: sigma " + std::to_string(sigma_m) + " m is " + std::to_string(100.0 * sigma_m / range_m) +
          " % of the range " + std::to_string(range_m) + " m (max_position_sigma_fraction)";
  return false;
}

void InnovationCovarianceScale::setWindow(double window_frames) {
  weight_ = window_frames > 0.0 ? 1.0 / std::max(1.0, window_frames) : 0.0;
  if (weight_ == 0.0) reset();
}

namespace {
// d^T S^-1 d / 3 for one 3-dof block, S the sum of both covariances' blocks; NaN when S is singular.
double normalizedChi2(const Eigen::Vector3d& d, const Eigen::Matrix3d& s) {
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(s);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return std::numeric_limits<double>::quiet_NaN();
  return d.dot(ldlt.solve(d)) / 3.0;
}
}  // namespace

double InnovationCovarianceScale::update(const PoseWithCovariance& measured, const PoseWithCovariance& predicted) {
  const Matrix6d s = measured.covariance + predicted.covariance;
  const double position = normalizedChi2(measured.translation - predicted.translation, s.topLeftCorner<3, 3>());
  const double rotation = normalizedChi2(rotationLog(measured.rotation * predicted.rotation.transpose()),
                                         s.bottomRightCorner<3, 3>());
  if (weight_ > 0.0 && std::isfinite(position)) position_mean_ += weight_ * (position - position_mean_);
  if (weight_ > 0.0 && std::isfinite(rotation)) rotation_mean_ += weight_ * (rotation - rotation_mean_);
  return 3.0 * rotation;
}

void InnovationCovarianceScale::apply(Matrix6d* covariance) const {
  const double p = std::sqrt(positionScale());
  const double r = std::sqrt(rotationScale());
  Vector6d scale;
  scale << p, p, p, r, r, r;
  *covariance = scale.asDiagonal() * (*covariance) * scale.asDiagonal();
}

void InnovationCovarianceScale::reset() {
  position_mean_ = 1.0;
  rotation_mean_ = 1.0;
}

double undecidedAlternativeDeg(const PlanarPnpSolution& pnp, const Eigen::Matrix3d* claimed_previous,
                               size_t point_count, double rms_px, double pixel_sigma_px,
                               const Eigen::Matrix3d& rotation, const ConsistencyParams& params,
                               double extra_evidence_chi2) {
  if (!pnp.has_alternative || !(pixel_sigma_px > 0.0)) return 0.0;
  if (claimed_previous != nullptr && rotationAngleBetween(rotation, *claimed_previous) <
                                         rotationAngleBetween(pnp.alternative_rotation, *claimed_previous)) {
    return 0.0;
  }
  const double extra_squared = pnp.alternative_rms_px * pnp.alternative_rms_px - rms_px * rms_px;
  const double excess = static_cast<double>(point_count) * extra_squared / (pixel_sigma_px * pixel_sigma_px);
  if (excess + extra_evidence_chi2 >= params.ambiguity_chi2) return 0.0;
  return rotationAngleBetween(pnp.alternative_rotation, rotation) * 180.0 / M_PI;
}

double trackedOrientationEvidence(const PoseWithCovariance& tracked, const Eigen::Matrix3d& measured_rotation_covariance,
                                  const Eigen::Matrix3d& chosen, const Eigen::Matrix3d& other) {
  const Eigen::Matrix3d s = tracked.covariance.bottomRightCorner<3, 3>() + measured_rotation_covariance;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(s);
  if (!s.allFinite() || ldlt.info() != Eigen::Success || !ldlt.isPositive()) return 0.0;
  const Eigen::Vector3d to_chosen = rotationLog(chosen * tracked.rotation.transpose());
  const Eigen::Vector3d to_other = rotationLog(other * tracked.rotation.transpose());
  const double evidence = to_other.dot(ldlt.solve(to_other)) - to_chosen.dot(ldlt.solve(to_chosen));
  return std::isfinite(evidence) ? evidence : 0.0;
}

double modelPnpCovariance(const CameraIntrinsics& camera, const PlanarPnpSolution& pnp, const OrientationHistory& history,
                          const std::vector<Eigen::Vector3d>& model_points, double rms_px, double pixel_sigma_px,
                          double min_pixel_sigma, double blur_sigma_px, const ConsistencyParams& params,
                          PoseWithCovariance* pose) {
  pose->covariance =
      honestCovariance(camera, *pose, model_points, pixel_sigma_px, min_pixel_sigma, blur_sigma_px, params);
  const double tracked_evidence =
      history.tracked != nullptr && pnp.has_alternative
          ? trackedOrientationEvidence(*history.tracked, pose->covariance.bottomRightCorner<3, 3>(), pose->rotation,
                                       pnp.alternative_rotation)
          : 0.0;
  const double ambiguity_deg =
      undecidedAlternativeDeg(pnp, history.claimed, model_points.size(), rms_px,
                              std::max(pixel_sigma_px, min_pixel_sigma), pose->rotation, params, tracked_evidence);
  if (ambiguity_deg > 0.0) {
    addAlternative(*pose, pnp.alternative_rotation, pnp.alternative_translation, &pose->covariance);
  }
  return ambiguity_deg;
}

namespace {

// The face's corners projected under a rotation and translation; false when one is behind the camera.
bool projectFace(const CameraIntrinsics& camera, const std::vector<Eigen::Vector3d>& face_corners,
                 const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation, std::vector<Eigen::Vector2d>* pixels) {
  pixels->clear();
  for (const Eigen::Vector3d& corner : face_corners) {
    const Eigen::Vector3d in_camera = rotation * corner + translation;
    if (!(in_camera.z() > 0.0)) return false;
    pixels->push_back(camera.project(in_camera));
  }
  return true;
}

}  // namespace

void addFaceScaleBias(const CameraIntrinsics& camera, const std::vector<Eigen::Vector3d>& face_corners,
                      double scale_bias_px, PoseWithCovariance* pose) {
  if (!(scale_bias_px > 0.0) || face_corners.size() < 3) return;
  std::vector<Eigen::Vector2d> pixels;
  // A face behind the camera has no apparent size.
  if (!projectFace(camera, face_corners, pose->rotation, pose->translation, &pixels)) return;
  std::vector<cv::Point2f> outline;
  for (const Eigen::Vector2d& pixel : pixels) outline.emplace_back(static_cast<float>(pixel.x()), static_cast<float>(pixel.y()));
  const double area_px = std::abs(cv::contourArea(outline));
  const double range = pose->translation.norm();
  if (!(area_px > 0.0) || !(range > 0.0)) return;
  const double sigma = scale_bias_px / std::sqrt(area_px) * range;
  const Eigen::Vector3d line_of_sight = pose->translation / range;
  pose->covariance.topLeftCorner<3, 3>() += sigma * sigma * line_of_sight * line_of_sight.transpose();
}

void addAlternative(const PoseWithCovariance& chosen, const Eigen::Matrix3d& other_rotation,
                    const Eigen::Vector3d& other_translation, Matrix6d* covariance) {
  Vector6d d;
  d.head<3>() = other_translation - chosen.translation;
  d.tail<3>() = rotationLog(other_rotation * chosen.rotation.transpose());
  *covariance += d * d.transpose();
}

}  // namespace mono
}  // namespace docking_perception
