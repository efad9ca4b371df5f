#include "docking_perception/mono/face_alignment.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace docking_perception {
namespace mono {
namespace {

// Below this apparent width (px), at the prior or as aligned, the face has too few pixels for a homography
// of 8 parameters: a face 24 px wide (3.4 m, turned 53 deg; seed 7699) aligned 6 % small in height with a
// correlation of 0.92. The monocular range's faces (<= 2 m, turned <= 60 deg) are >= 41 px wide.
constexpr double kMinFaceWidthPx = 32.0;
// The coarsest pyramid level keeps the template at least this wide (narrower ones align on nothing).
constexpr double kMinTemplateWidthPx = 24.0;
// Around the predicted face the search window adds this fraction of its size: the prior's error.
constexpr double kWindowMarginFraction = 0.25;
// Less than this fraction of the predicted face inside the image: nothing reliable to align.
constexpr double kMinVisibleFraction = 0.6;
// The aligned face's area may differ from the prior's by this factor at most (else ECC ran away).
constexpr double kMaxAreaChange = 3.0;
// ECC smooths both images with a 5x5 Gaussian (the OpenCV default): neighbouring residuals are
// correlated over about this many pixels, so the independent samples are N / this.
constexpr double kResidualCorrelationPixels = 4.0;
constexpr int kEccGaussianSize = 5;
constexpr double kEccEpsilon = 1e-4;
// The working scale: the image is shrunk until the face is at most this wide (the CPU a frame), and ECC
// runs coarse to fine over this many levels (each half the previous), this many iterations a level.
constexpr double kWorkingFaceWidthPx = 128.0;
constexpr int kPyramidLevels = 3;
constexpr int kMaxIterations = 25;
// The aligned face goes to PnP as this grid of points.
constexpr int kGridColumns = 8;
constexpr int kGridRows = 6;

cv::Point2d apply(const cv::Matx33d& h, const cv::Point2d& p) {
  const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1.0);
  return {q[0] / q[2], q[1] / q[2]};
}

// Pixel-centre-exact map of a resize by (scale_x, scale_y) new pixels per old pixel.
cv::Matx33d resizeMap(double scale_x, double scale_y) {
  return cv::Matx33d(scale_x, 0.0, 0.5 * scale_x - 0.5, 0.0, scale_y, 0.5 * scale_y - 0.5, 0.0, 0.0, 1.0);
}

std::vector<cv::Point2d> textureCorners(const cv::Size& size) {
  const double w = size.width, h = size.height;
  return {{0.0, 0.0}, {w, 0.0}, {w, h}, {0.0, h}};
}

// The quadrilateral of the face in the image, or empty when a corner is behind the camera.
std::vector<cv::Point2d> mapCorners(const cv::Matx33d& h, const cv::Size& texture_size) {
  std::vector<cv::Point2d> out;
  for (const cv::Point2d& c : textureCorners(texture_size)) {
    const cv::Vec3d q = h * cv::Vec3d(c.x, c.y, 1.0);
    if (!(q[2] > 0.0) || !std::isfinite(q[0]) || !std::isfinite(q[1])) return {};
    out.emplace_back(q[0] / q[2], q[1] / q[2]);
  }
  return out;
}

double quadArea(const std::vector<cv::Point2d>& q) {
  std::vector<cv::Point2f> f(q.begin(), q.end());
  return std::abs(cv::contourArea(f));
}

// The face's apparent width: the mean of its top and bottom edges (corners as mapCorners gives them).
double faceWidth(const std::vector<cv::Point2d>& q) { return 0.5 * (cv::norm(q[1] - q[0]) + cv::norm(q[2] - q[3])); }

bool convex(const std::vector<cv::Point2d>& q) {
  std::vector<cv::Point2f> f(q.begin(), q.end());
  return cv::isContourConvex(f);
}

// One-sigma position error of a grid point (template px) implied by the final fit: the residual after a
// gain/offset fit over the template's gradient energy, spread over the grid's points as the fit spreads
// its information over the independent pixels.
double fitPixelSigma(const cv::Mat& template_f, const cv::Mat& image_f, const cv::Matx33f& warp, int grid_points) {
  cv::Mat warped, valid;
  cv::warpPerspective(image_f, warped, warp, template_f.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP);
  cv::warpPerspective(cv::Mat(image_f.size(), CV_8U, cv::Scalar(255)), valid, warp, template_f.size(),
                      cv::INTER_NEAREST | cv::WARP_INVERSE_MAP);
  cv::erode(valid, valid, cv::Mat());
  cv::Mat gx, gy;
  cv::Sobel(template_f, gx, CV_32F, 1, 0, 3, 0.125);
  cv::Sobel(template_f, gy, CV_32F, 0, 1, 3, 0.125);
  double st = 0, si = 0, stt = 0, sti = 0, sii = 0, sg = 0;
  int n = 0;
  for (int y = 1; y + 1 < template_f.rows; ++y) {
    const float* t = template_f.ptr<float>(y);
    const float* i = warped.ptr<float>(y);
    const uchar* m = valid.ptr<uchar>(y);
    const float* dx = gx.ptr<float>(y);
    const float* dy = gy.ptr<float>(y);
    for (int x = 1; x + 1 < template_f.cols; ++x) {
      if (!m[x]) continue;
      st += t[x];
      si += i[x];
      stt += double(t[x]) * t[x];
      sti += double(t[x]) * i[x];
      sii += double(i[x]) * i[x];
      sg += double(dx[x]) * dx[x] + double(dy[x]) * dy[x];
      ++n;
    }
  }
  if (n < 16) return INFINITY;
  const double var_t = stt / n - (st / n) * (st / n);
  const double cov = sti / n - (st / n) * (si / n);
  const double var_i = sii / n - (si / n) * (si / n);
  if (!(var_t > 0.0)) return INFINITY;
  const double gain = cov / var_t;
  const double residual_var = std::max(var_i - gain * cov, 1e-12);
  const double gradient_energy = gain * gain * sg / n;  // the image's gradients: the template's times the gain
  if (!(gradient_energy > 0.0)) return INFINITY;
  const double independent = n / kResidualCorrelationPixels;
  return std::sqrt(residual_var / gradient_energy * grid_points / independent);
}

// The image window as a warp (template px -> image px) sees it, with a margin on every side: its pixel
// (x, y) is template pixel (x - margin.x, y - margin.y). `from_seen` receives that map.
cv::Mat seenThroughWarp(const cv::Mat& templ, const cv::Mat& image, const cv::Matx33d& warp, cv::Matx33d* from_seen) {
  const int margin_x = std::max(2, static_cast<int>(std::lround(kWindowMarginFraction * templ.cols)));
  const int margin_y = std::max(2, static_cast<int>(std::lround(kWindowMarginFraction * templ.rows)));
  *from_seen = cv::Matx33d(1.0, 0.0, -margin_x, 0.0, 1.0, -margin_y, 0.0, 0.0, 1.0);
  cv::Mat seen;
  cv::warpPerspective(image, seen, warp * *from_seen, cv::Size(templ.cols + 2 * margin_x, templ.rows + 2 * margin_y),
                      cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
  return seen;
}

// The warp moved by the whole-pixel shift (within the window's margin) at which the template best matches
// the image as the warp sees it, by normalised correlation. Why: ECC follows its correlation's local
// gradient, and on a smooth face under defocus and noise over clutter the coarsest level's basin can be
// narrower than a one-frame prediction's miss (3 of 6 perturbed priors lost in test_face_alignment);
// sliding the ~32 px template over the window is cheap and starts ECC inside the basin.
cv::Matx33d warpAtBestShift(const cv::Mat& templ, const cv::Mat& image, const cv::Matx33d& warp) {
  cv::Matx33d from_seen;
  const cv::Mat seen = seenThroughWarp(templ, image, warp, &from_seen);
  cv::Mat scores;
  cv::matchTemplate(seen, templ, scores, cv::TM_CCOEFF_NORMED);
  double best_score = 0.0;
  cv::Point best;
  cv::minMaxLoc(scores, nullptr, &best_score, nullptr, &best);
  if (!std::isfinite(best_score)) return warp;  // a flat window: nothing to slide on
  return warp * from_seen * cv::Matx33d(1.0, 0.0, best.x, 0.0, 1.0, best.y, 0.0, 0.0, 1.0);
}

// One level's ECC over a homography; when that gives up, an affine ECC on the image as the warp sees it,
// composed onto the warp (the prior's perspective kept). Why: on a small smooth template the homography's
// 8 x 8 Hessian is near singular and OpenCV stops at the first step ("the correlation is going to be
// minimized") even where the fit is good: a test prior whose affine fit reached 0.99 failed so at every
// level. Returns the correlation; throws cv::Exception when both give up.
double eccAtLevel(const cv::Mat& templ, const cv::Mat& image, const cv::TermCriteria& stop, cv::Matx33d* warp) {
  cv::Mat homography = cv::Mat(cv::Matx33f(*warp), true);
  try {
    const double rho = cv::findTransformECC(templ, image, homography, cv::MOTION_HOMOGRAPHY, stop, cv::noArray(),
                                            kEccGaussianSize);
    *warp = cv::Matx33d(cv::Matx33f(homography));
    return rho;
  } catch (const cv::Exception&) {
    // falls through to the affine model
  }
  cv::Matx33d from_seen;
  const cv::Mat seen = seenThroughWarp(templ, image, *warp, &from_seen);
  // Start at the prior: template pixel (x, y) is seen pixel (x + margin.x, y + margin.y).
  cv::Mat affine = (cv::Mat_<float>(2, 3) << 1.0f, 0.0f, static_cast<float>(-from_seen(0, 2)), 0.0f, 1.0f,
                    static_cast<float>(-from_seen(1, 2)));
  const double rho = cv::findTransformECC(templ, seen, affine, cv::MOTION_AFFINE, stop, cv::noArray(), kEccGaussianSize);
  const cv::Matx23f a(affine);
  *warp = *warp * from_seen * cv::Matx33d(a(0, 0), a(0, 1), a(0, 2), a(1, 0), a(1, 1), a(1, 2), 0.0, 0.0, 1.0);
  return rho;
}

}  // namespace

cv::Matx33d faceHomography(const Eigen::Matrix3d& texture_to_face, const CameraIntrinsics& camera,
                           const PoseWithCovariance& pose) {
  // A face point (0, y, z) lands at K (y r1 + z r2 + t); textureToFace gives (y, z, 1) from (u, v, 1).
  Eigen::Matrix3d k;
  k << camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0;
  Eigen::Matrix3d plane;
  plane.col(0) = pose.rotation.col(1);
  plane.col(1) = pose.rotation.col(2);
  plane.col(2) = pose.translation;
  const Eigen::Matrix3d h = k * plane * texture_to_face;
  cv::Matx33d out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out(r, c) = h(r, c);
  }
  return out;
}

DirectFaceAligner::DirectFaceAligner(const TargetModel& model, const DirectAlignmentParams& params)
    : params_(params), texture_(model.textureGray()), model_(model) {}

DirectAlignment DirectFaceAligner::align(const cv::Mat& gray, const CameraIntrinsics& camera,
                                         const PoseWithCovariance& initial) const {
  return align(gray, faceHomography(model_, camera, initial));
}

// The working frames of one alignment: the image window around the prior, shrunk until the face is at
// most kWorkingFaceWidthPx wide, and the texture resampled to the face's size there.
struct DirectFaceAligner::Frames {
  cv::Mat image;                 // CV_32F
  cv::Mat templ;                 // CV_32F
  cv::Matx33d image_to_work;     // full image px -> working image px
  cv::Matx33d texture_to_templ;  // texture px -> template px
  double scale = 1.0;            // image px per working px
};

bool DirectFaceAligner::makeFrames(const cv::Mat& gray, const cv::Matx33d& initial, double template_blur_px,
                                   Frames* frames, std::string* why) const {
  const std::vector<cv::Point2d> quad = mapCorners(initial, texture_.size());
  if (quad.empty()) {
    *why = "prior puts the face behind the camera";
    return false;
  }
  const double face_width = faceWidth(quad);
  if (!(face_width >= kMinFaceWidthPx)) {
    *why = "face too small at the prior";
    return false;
  }
  std::vector<cv::Point2f> quad_f(quad.begin(), quad.end());
  const cv::Rect face_box = cv::boundingRect(quad_f);
  const int margin = static_cast<int>(kWindowMarginFraction * std::max(face_box.width, face_box.height)) + 4;
  const cv::Rect window = cv::Rect(face_box.x - margin, face_box.y - margin, face_box.width + 2 * margin,
                                   face_box.height + 2 * margin) & cv::Rect(0, 0, gray.cols, gray.rows);
  if ((face_box & window).area() < kMinVisibleFraction * face_box.area()) {
    *why = "face mostly outside the image at the prior";
    return false;
  }
  frames->scale = std::max(1.0, face_width / kWorkingFaceWidthPx);
  const cv::Size work_size(std::max(1, static_cast<int>(std::lround(window.width / frames->scale))),
                           std::max(1, static_cast<int>(std::lround(window.height / frames->scale))));
  cv::Mat work;
  cv::resize(gray(window), work, work_size, 0.0, 0.0, cv::INTER_AREA);
  work.convertTo(frames->image, CV_32F);
  const cv::Matx33d shift(1.0, 0.0, -window.x, 0.0, 1.0, -window.y, 0.0, 0.0, 1.0);
  frames->image_to_work = resizeMap(double(work_size.width) / window.width, double(work_size.height) / window.height) * shift;
  // The template as wide as the face in the working image (never enlarged beyond the texture).
  const double templ_scale = std::min(1.0, face_width / frames->scale / texture_.cols);
  const cv::Size templ_size(std::max(8, static_cast<int>(std::lround(texture_.cols * templ_scale))),
                            std::max(8, static_cast<int>(std::lround(texture_.rows * templ_scale))));
  cv::Mat templ;
  cv::resize(texture_, templ, templ_size, 0.0, 0.0, cv::INTER_AREA);
  templ.convertTo(frames->templ, CV_32F);
  const double blur_work_px = template_blur_px / frames->scale;
  if (blur_work_px > 0.0) cv::GaussianBlur(frames->templ, frames->templ, cv::Size(0, 0), blur_work_px);
  frames->texture_to_templ = resizeMap(double(templ_size.width) / texture_.cols, double(templ_size.height) / texture_.rows);
  return true;
}

DirectAlignment DirectFaceAligner::align(const cv::Mat& gray, const cv::Matx33d& initial, bool coarse_only,
                                         double template_blur_px) const {
  DirectAlignment result;
  Frames frames;
  if (!makeFrames(gray, initial, template_blur_px, &frames, &result.status)) return result;
  result.image_scale = frames.scale;
  // Levels: as many as asked while the template stays wide enough to align on.
  int levels = kPyramidLevels;
  while (levels > 1 && frames.templ.cols / std::pow(2.0, levels - 1) < kMinTemplateWidthPx) --levels;
  const int finest = coarse_only && levels > 1 ? 1 : 0;
  std::vector<cv::Mat> templ_pyramid, image_pyramid;
  cv::buildPyramid(frames.templ, templ_pyramid, levels - 1);
  cv::buildPyramid(frames.image, image_pyramid, levels - 1);
  // pyrDown keeps pixel 2i as pixel i: a level's coordinates are exactly half the finer level's.
  const double coarsest = std::pow(2.0, levels - 1);
  const cv::Matx33d down(1.0 / coarsest, 0.0, 0.0, 0.0, 1.0 / coarsest, 0.0, 0.0, 0.0, 1.0);
  const cv::Matx33d up(coarsest, 0.0, 0.0, 0.0, coarsest, 0.0, 0.0, 0.0, 1.0);
  cv::Matx33d warp = down * frames.image_to_work * initial * frames.texture_to_templ.inv() * up;
  const cv::Matx33d finer(2.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 1.0);
  const cv::TermCriteria stop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, kMaxIterations, kEccEpsilon);
  warp = warpAtBestShift(templ_pyramid[levels - 1], image_pyramid[levels - 1], warp);
  for (int level = levels - 1; level >= finest; --level) {
    try {
      result.correlation = eccAtLevel(templ_pyramid[level], image_pyramid[level], stop, &warp);
    } catch (const cv::Exception&) {
      result.status = "direct alignment did not converge";
      return result;
    }
    if (level > finest) warp = finer * warp * finer.inv();
  }
  const double back = std::pow(2.0, finest);
  const cv::Matx33d to_level0(back, 0.0, 0.0, 0.0, back, 0.0, 0.0, 0.0, 1.0);
  result.homography = frames.image_to_work.inv() * to_level0 * warp * to_level0.inv() * frames.texture_to_templ;
  result.homography *= 1.0 / result.homography(2, 2);
  return finish(initial, frames, templ_pyramid[finest], image_pyramid[finest], cv::Matx33f(warp), result);
}

DirectAlignment DirectFaceAligner::finish(const cv::Matx33d& initial, const Frames& frames, const cv::Mat& templ,
                                          const cv::Mat& image, const cv::Matx33f& warp, DirectAlignment result) const {
  const std::vector<cv::Point2d> prior = mapCorners(initial, texture_.size());
  const std::vector<cv::Point2d> quad = mapCorners(result.homography, texture_.size());
  if (quad.empty() || !convex(quad)) {
    result.status = "direct alignment folded the face";
    return result;
  }
  const double area_change = quadArea(quad) / std::max(quadArea(prior), 1.0);
  if (!(area_change < kMaxAreaChange && area_change > 1.0 / kMaxAreaChange)) {
    result.status = "direct alignment changed the face's size by " + std::to_string(area_change);
    return result;
  }
  for (const cv::Point2d& c : quad) result.face_outline.emplace_back(c);
  const double aligned_width = faceWidth(quad);
  if (!(aligned_width >= kMinFaceWidthPx)) {
    result.status = "direct alignment: the aligned face is " + std::to_string(aligned_width) + " px wide, too small";
    return result;
  }
  if (result.correlation < params_.min_correlation) {
    result.status = "direct alignment correlation " + std::to_string(result.correlation) + " below direct_min_correlation";
    return result;
  }
  const int grid_points = kGridColumns * kGridRows;
  const double sigma_work = fitPixelSigma(templ, image, warp, grid_points);
  // Template pixels are working pixels at the face's scale; working pixels are `scale` image pixels.
  const double level_scale = double(frames.templ.cols) / templ.cols;
  result.pixel_sigma_px = sigma_work * level_scale * frames.scale;
  if (!std::isfinite(result.pixel_sigma_px)) {
    result.status = "direct alignment: no texture where the face is";
    return result;
  }
  for (int r = 0; r < kGridRows; ++r) {
    for (int c = 0; c < kGridColumns; ++c) {
      const cv::Point2d t((c + 0.5) * texture_.cols / kGridColumns - 0.5, (r + 0.5) * texture_.rows / kGridRows - 0.5);
      result.texture_points.emplace_back(t);
      result.image_points.emplace_back(apply(result.homography, t));
    }
  }
  result.found = true;
  return result;
}

}  // namespace mono
}  // namespace docking_perception
