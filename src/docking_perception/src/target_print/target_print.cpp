#include "docking_perception/target_print/target_print.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <random>
#include <sstream>
#include <stdexcept>

#include <Eigen/Core>
#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace target_print {
namespace {

constexpr double kDegToRad = M_PI / 180.0;
constexpr int kMinImageSide = 16;
// Horizontal offset of the face between the views of one case, px (a different pixel phase each).
constexpr double kViewOffsetPx = 17.3;
// The texture is pre-shrunk to this many times the face's apparent width before the perspective warp,
// so bilinear warping does not alias the print's fine detail into texture the camera would not see.
constexpr double kPrefilterOversampling = 2.0;

// Texture pixel of a point (y, z) of the face for a texture of `size` (TargetModel's convention:
// column u along +y, row v along -z, pixel centres at integers, outer edges at -0.5 and size - 0.5).
cv::Point2d facePointToPixel(double y, double z, double width_m, double height_m, cv::Size size) {
  return {(y + width_m / 2.0) / width_m * size.width - 0.5,
          (height_m / 2.0 - z) / height_m * size.height - 0.5};
}

cv::Point2d applyHomography(const Eigen::Matrix3d& h, const cv::Point2d& p) {
  const Eigen::Vector3d q = h * Eigen::Vector3d(p.x, p.y, 1.0);
  return {q.x() / q.z(), q.y() / q.z()};
}

template <typename T>
T medianOf(std::vector<T> values) {
  if (values.empty()) return T();
  std::nth_element(values.begin(), values.begin() + static_cast<long>(values.size() / 2), values.end());
  return values[values.size() / 2];
}

// Texture pixel -> image pixel for the face centred `offset_px` right of the image centre at
// `range_m`, turned by yaw about its vertical axis.
Eigen::Matrix3d viewHomography(const mono::TargetModel& model, const ViewCase& view,
                               const CheckParams& params, double offset_px) {
  const double cx = (params.image_width - 1) / 2.0, cy = (params.image_height - 1) / 2.0;
  const double yaw = view.yaw_deg * kDegToRad;
  const double tx = offset_px * view.range_m / params.focal_px;
  // Face (y, z, 1) -> camera (x right, y down, z forward): y along the camera's x turned by yaw,
  // z up = -y of the camera.
  Eigen::Matrix3d face_to_camera;
  face_to_camera << std::cos(yaw), 0.0, tx,  //
      0.0, -1.0, 0.0,                         //
      -std::sin(yaw), 0.0, view.range_m;
  Eigen::Matrix3d intrinsics;
  intrinsics << params.focal_px, 0.0, cx, 0.0, params.focal_px, cy, 0.0, 0.0, 1.0;
  return intrinsics * face_to_camera * model.textureToFace();
}

// The camera's picture of the face: pre-shrunk texture warped onto the background, blurred, noisy.
cv::Mat renderView(const cv::Mat& texture, const Eigen::Matrix3d& texture_to_image,
                   double face_width_px, const CheckParams& params, std::mt19937* rng) {
  const double shrink = std::min(1.0, kPrefilterOversampling * face_width_px / texture.cols);
  cv::Mat small = texture;
  if (shrink < 1.0) {
    cv::resize(texture, small, cv::Size(), shrink, shrink, cv::INTER_AREA);
  }
  // Small texture pixel -> original texture pixel (pixel centres at integers in both).
  const double sx = static_cast<double>(texture.cols) / small.cols;
  const double sy = static_cast<double>(texture.rows) / small.rows;
  Eigen::Matrix3d small_to_texture;
  small_to_texture << sx, 0.0, 0.5 * sx - 0.5, 0.0, sy, 0.5 * sy - 0.5, 0.0, 0.0, 1.0;
  const Eigen::Matrix3d h = texture_to_image * small_to_texture;
  cv::Mat h_cv(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) h_cv.at<double>(r, c) = h(r, c);
  }
  cv::Mat warped;
  cv::warpPerspective(small, warped, h_cv, cv::Size(params.image_width, params.image_height),
                      cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(params.background_grey));
  cv::Mat image;
  warped.convertTo(image, CV_32F);
  if (params.blur_sigma_px > 0.0) {
    cv::GaussianBlur(image, image, cv::Size(0, 0), params.blur_sigma_px);
  }
  if (params.noise_sigma_dn > 0.0) {
    cv::Mat noise(image.size(), CV_32F);
    std::normal_distribution<float> normal(0.0f, static_cast<float>(params.noise_sigma_dn));
    for (int r = 0; r < noise.rows; ++r) {
      float* row = noise.ptr<float>(r);
      for (int c = 0; c < noise.cols; ++c) row[c] = normal(*rng);
    }
    image += noise;
  }
  cv::Mat gray;
  image.convertTo(gray, CV_8U);
  return gray;
}

// Ring level - dot level of each marker in the print: the dot's median against the 80th percentile of
// the disc the dot finder searches (1.5 dot radii), i.e. what the finder calls background.
double minDotContrast(const mono::TargetModel& model, const cv::Mat& texture) {
  const double px_per_m = texture.cols / model.faceWidth();
  const double radius = model.markerRadius() * px_per_m;
  double lowest = 255.0;
  for (const auto& marker : model.markers()) {
    const cv::Point2d centre = facePointToPixel(marker.y(), marker.z(), model.faceWidth(),
                                                model.faceHeight(), texture.size());
    std::vector<int> dot, disc;
    const int reach = static_cast<int>(std::ceil(1.5 * radius)) + 1;
    for (int v = static_cast<int>(centre.y) - reach; v <= static_cast<int>(centre.y) + reach; ++v) {
      for (int u = static_cast<int>(centre.x) - reach; u <= static_cast<int>(centre.x) + reach; ++u) {
        if (u < 0 || v < 0 || u >= texture.cols || v >= texture.rows) continue;
        const double d = std::hypot(u - centre.x, v - centre.y);
        const int level = texture.at<std::uint8_t>(v, u);
        if (d <= 0.6 * radius) dot.push_back(level);
        if (d <= 1.5 * radius) disc.push_back(level);
      }
    }
    if (dot.empty() || disc.empty()) return 0.0;
    std::sort(disc.begin(), disc.end());
    const double background = disc[disc.size() * 4 / 5];
    lowest = std::min(lowest, background - medianOf(dot));
  }
  return lowest;
}

struct ViewResult {
  int matches = 0, inliers = 0, dots_found = 0;
  double coverage = 0.0, outline_error_px = 0.0;
  bool face_ok = false, passed = false;
  std::vector<PrintProblem> problems;
};

// The texture's outer corners (pixel edges) in texture pixels.
std::vector<cv::Point2d> textureCorners(const cv::Size& texture_size) {
  return {{-0.5, -0.5},
          {texture_size.width - 0.5, -0.5},
          {texture_size.width - 0.5, texture_size.height - 0.5},
          {-0.5, texture_size.height - 0.5}};
}

// Matching as mono_pose does while tracking: in the true outline's bounding box plus the search margin.
mono::FaceMatch matchInPredictedRegion(const cv::Mat& gray, const Eigen::Matrix3d& truth,
                                       const std::vector<cv::Point2d>& corners, double face_width_px,
                                       const mono::FeatureMatcher& matcher, const CheckParams& params) {
  std::vector<cv::Point> outline;
  for (const auto& corner : corners) outline.push_back(applyHomography(truth, corner));
  const int margin = static_cast<int>(params.search_margin_px);
  cv::Rect roi = cv::boundingRect(outline);
  roi = cv::Rect(roi.x - margin, roi.y - margin, roi.width + 2 * margin, roi.height + 2 * margin) &
        cv::Rect(0, 0, gray.cols, gray.rows);
  return matcher.match(gray, roi, face_width_px);
}

// The match's homography (truth when there is none); fills the outline error and the inliers' coverage.
Eigen::Matrix3d measureMatch(const mono::FaceMatch& match, const Eigen::Matrix3d& truth,
                             const std::vector<cv::Point2d>& corners, const cv::Size& texture_size,
                             ViewResult* result) {
  result->matches = match.matches;
  result->inliers = match.inliers;
  Eigen::Matrix3d found = truth;
  if (!match.found) return found;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) found(r, c) = match.homography(r, c);
  }
  for (const auto& corner : corners) {
    result->outline_error_px = std::max(
        result->outline_error_px, cv::norm(applyHomography(found, corner) - applyHomography(truth, corner)));
  }
  if (match.inlier_texture_points.size() >= 3) {
    std::vector<cv::Point2f> hull;
    cv::convexHull(match.inlier_texture_points, hull);
    result->coverage = cv::contourArea(hull) / texture_size.area();
  }
  return found;
}

// The face's verdict: too few inliers, the wrong place, or too little of the face covered.
void judgeFace(const mono::FaceMatch& match, int required_inliers, double face_width_px, const CheckParams& params,
               ViewResult* result) {
  const bool enough = match.found && match.inliers >= required_inliers;
  const bool placed = match.found && result->outline_error_px <= params.max_outline_error_fraction * face_width_px;
  if (!enough) {
    result->problems.push_back(PrintProblem::kLowTexture);
  } else if (!placed) {
    result->problems.push_back(PrintProblem::kWrongMatch);
  } else if (result->coverage < params.min_coverage) {
    result->problems.push_back(PrintProblem::kPoorCoverage);
  }
  result->face_ok = result->problems.empty();
}

// Dots, predicted as the estimator does (through the homography `found`), found within
// max_dot_error_px of where they truly are.
int countDots(const cv::Mat& gray, const mono::TargetModel& model, const Eigen::Matrix3d& found,
              const Eigen::Matrix3d& truth, const mono::DarkDotLocator& locator, const CheckParams& params) {
  int dots_found = 0;
  for (const auto& marker : model.markers()) {
    const cv::Point2d texture_pixel = model.pointToTexturePixel(marker);
    const cv::Point2d edge = model.pointToTexturePixel(marker + Eigen::Vector3d(0.0, model.markerRadius(), 0.0));
    const cv::Point2d edge_z = model.pointToTexturePixel(marker + Eigen::Vector3d(0.0, 0.0, model.markerRadius()));
    const cv::Point2d predicted = applyHomography(found, texture_pixel);
    const double radius_px = std::max(cv::norm(applyHomography(found, edge) - predicted),
                                      cv::norm(applyHomography(found, edge_z) - predicted));
    Eigen::Vector2d located;
    std::string reason;
    if (locator.locate(gray, {predicted.x, predicted.y}, radius_px, &located, &reason) &&
        cv::norm(cv::Point2d(located.x(), located.y()) - applyHomography(truth, texture_pixel)) <=
            params.max_dot_error_px) {
      ++dots_found;
    }
  }
  return dots_found;
}

// Matching as mono_pose does while tracking (predicted region and face width), then the dots as the
// 5-point solver finds them (predicted through the matched homography).
ViewResult examineView(const cv::Mat& gray, const mono::TargetModel& model,
                       const Eigen::Matrix3d& truth, double face_width_px,
                       const mono::FeatureMatcher& matcher, const mono::DarkDotLocator& locator,
                       int required_inliers, const CheckParams& params) {
  const cv::Size texture_size = model.textureGray().size();
  const std::vector<cv::Point2d> corners = textureCorners(texture_size);
  const mono::FaceMatch match = matchInPredictedRegion(gray, truth, corners, face_width_px, matcher, params);
  ViewResult result;
  const Eigen::Matrix3d found = measureMatch(match, truth, corners, texture_size, &result);
  judgeFace(match, required_inliers, face_width_px, params, &result);
  result.dots_found = countDots(gray, model, found, truth, locator, params);
  if (result.dots_found < mono::kMarkerCount) result.problems.push_back(PrintProblem::kDotsNotFound);
  result.passed = result.problems.empty();
  return result;
}

void addOnce(std::vector<PrintProblem>* problems, PrintProblem problem) {
  if (std::find(problems->begin(), problems->end(), problem) == problems->end()) {
    problems->push_back(problem);
  }
}

CaseResult examineCase(const ViewCase& view, const mono::TargetModel& model,
                       const mono::FeatureMatcher& matcher, const mono::DarkDotLocator& locator,
                       int required_inliers, const CheckParams& params, std::mt19937* rng) {
  CaseResult result;
  result.view = view;
  std::vector<int> matches, inliers, dots;
  std::vector<double> coverage, outline_error;
  std::vector<PrintProblem> failed_view_problems;
  for (int i = 0; i < params.views_per_case; ++i) {
    const double offset_px = (i - (params.views_per_case - 1) / 2.0) * kViewOffsetPx;
    const Eigen::Matrix3d truth = viewHomography(model, view, params, offset_px);
    // Apparent face width: the outline's horizontal extent.
    const cv::Size size = model.textureGray().size();
    const double left = std::min(applyHomography(truth, {-0.5, -0.5}).x,
                                 applyHomography(truth, {-0.5, size.height - 0.5}).x);
    const double right = std::max(applyHomography(truth, {size.width - 0.5, -0.5}).x,
                                  applyHomography(truth, {size.width - 0.5, size.height - 0.5}).x);
    result.face_width_px = right - left;
    const cv::Mat gray = renderView(model.textureGray(), truth, result.face_width_px, params, rng);
    const ViewResult v = examineView(gray, model, truth, result.face_width_px, matcher, locator,
                                     required_inliers, params);
    ++result.views;
    if (v.passed) ++result.views_passed;
    for (PrintProblem p : v.problems) addOnce(&failed_view_problems, p);
    matches.push_back(v.matches);
    inliers.push_back(v.inliers);
    dots.push_back(v.dots_found);
    coverage.push_back(v.coverage);
    outline_error.push_back(v.outline_error_px);
  }
  result.matches = medianOf(matches);
  result.inliers = medianOf(inliers);
  result.dots_found = medianOf(dots);
  result.coverage = medianOf(coverage);
  result.outline_error_px = medianOf(outline_error);
  result.passed = result.views_passed >= params.min_views_passed;
  if (!result.passed) result.problems = failed_view_problems;
  return result;
}

}  // namespace

// ---------------------------------------------------------------- compose
cv::Mat composePrint(const cv::Mat& image, const mono::TargetModel& model, const ComposeOptions& options) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3) ||
      image.cols < kMinImageSide || image.rows < kMinImageSide) {
    throw std::invalid_argument("the image must be 8-bit grey or BGR, at least 16x16 pixels");
  }
  if (options.width_px < 64 || options.ring_outer_factor < 1.6 || options.dot_grey < 0 ||
      options.dot_grey > 100) {
    throw std::invalid_argument(
        "compose options: width_px >= 64, ring_outer_factor >= 1.6 (the dot finder searches 1.5 dot "
        "radii), dot_grey in [0, 100]");
  }
  cv::Mat colour = image;
  if (image.channels() == 1) cv::cvtColor(image, colour, cv::COLOR_GRAY2BGR);
  // Centred crop to the face's aspect, then scale to the print width.
  const double aspect = model.faceWidth() / model.faceHeight();
  cv::Rect crop(0, 0, colour.cols, colour.rows);
  if (static_cast<double>(colour.cols) / colour.rows > aspect) {
    crop.width = static_cast<int>(std::lround(colour.rows * aspect));
    crop.x = (colour.cols - crop.width) / 2;
  } else {
    crop.height = static_cast<int>(std::lround(colour.cols / aspect));
    crop.y = (colour.rows - crop.height) / 2;
  }
  const cv::Size print_size(options.width_px,
                            static_cast<int>(std::lround(options.width_px / aspect)));
  cv::Mat print;
  cv::resize(colour(crop), print, print_size, 0, 0,
             crop.width > print_size.width ? cv::INTER_AREA : cv::INTER_CUBIC);
  // Dots on white rings, drawn with 1/16 px precision (shift 4) and antialiased edges.
  constexpr int kShift = 4;
  constexpr double kScale = 1 << kShift;
  const double px_per_m = print_size.width / model.faceWidth();
  const double radius = model.markerRadius() * px_per_m;
  for (const auto& marker : model.markers()) {
    const cv::Point2d centre =
        facePointToPixel(marker.y(), marker.z(), model.faceWidth(), model.faceHeight(), print_size);
    const cv::Point fixed(static_cast<int>(std::lround(centre.x * kScale)),
                          static_cast<int>(std::lround(centre.y * kScale)));
    cv::circle(print, fixed, static_cast<int>(std::lround(options.ring_outer_factor * radius * kScale)),
               cv::Scalar(255, 255, 255), cv::FILLED, cv::LINE_AA, kShift);
    cv::circle(print, fixed, static_cast<int>(std::lround(radius * kScale)),
               cv::Scalar(options.dot_grey, options.dot_grey, options.dot_grey), cv::FILLED,
               cv::LINE_AA, kShift);
  }
  return print;
}

// ---------------------------------------------------------------- check
const char* problemName(PrintProblem problem) {
  switch (problem) {
    case PrintProblem::kLowContrast: return "low_contrast";
    case PrintProblem::kLowTexture: return "low_texture";
    case PrintProblem::kPoorCoverage: return "poor_coverage";
    case PrintProblem::kWrongMatch: return "wrong_match";
    case PrintProblem::kDotsNotFound: return "dots_not_found";
    case PrintProblem::kDotsLowContrast: return "dots_low_contrast";
  }
  return "unknown";
}

const char* problemAdvice(PrintProblem problem) {
  switch (problem) {
    case PrintProblem::kLowContrast:
      return "the print is too flat: stretch its levels (darkest near black, brightest near white), "
             "avoid pale or foggy images";
    case PrintProblem::kLowTexture:
      return "too few features match at some range: use an image with more sharp, fine, "
             "non-repeating detail (edges, corners, text-like structure) across the whole face; "
             "smooth gradients, sky and plain areas give nothing";
    case PrintProblem::kPoorCoverage:
      return "the matched features cluster in part of the face: the detail must spread over the "
             "whole face, not one corner";
    case PrintProblem::kWrongMatch:
      return "the face was matched in the wrong place: avoid repetitive patterns (grids, tiles, "
             "stripes) that look the same shifted";
    case PrintProblem::kDotsNotFound:
      return "the dot finder fails: compose the print with make_target_print (dark dots on white "
             "rings at target.yaml's marker positions)";
    case PrintProblem::kDotsLowContrast:
      return "a dot is not dark enough against its surroundings: compose the print with "
             "make_target_print (dot level 15 on a white ring)";
  }
  return "";
}

std::vector<std::string> validateCheckParams(const CheckParams& p) {
  std::vector<std::string> errors;
  if (p.cases.empty()) errors.push_back("cases: at least one view case");
  for (const auto& c : p.cases) {
    if (!(c.range_m > 0.05 && c.range_m < 100.0) || !(std::abs(c.yaw_deg) < 80.0)) {
      errors.push_back("cases: range_m in (0.05, 100) and |yaw_deg| < 80");
      break;
    }
  }
  if (p.image_width < 64 || p.image_height < 64) errors.push_back("image size at least 64x64");
  if (!(p.focal_px > 0.0)) errors.push_back("focal_px must be > 0");
  if (!(p.blur_sigma_px >= 0.0 && p.blur_sigma_px <= 20.0)) errors.push_back("blur_sigma_px in [0, 20]");
  if (!(p.noise_sigma_dn >= 0.0 && p.noise_sigma_dn <= 50.0)) errors.push_back("noise_sigma_dn in [0, 50]");
  if (p.views_per_case < 1 || p.min_views_passed < 1 || p.min_views_passed > p.views_per_case) {
    errors.push_back("1 <= min_views_passed <= views_per_case");
  }
  if (!(p.inlier_margin >= 1.0)) errors.push_back("inlier_margin must be >= 1");
  if (!(p.min_coverage >= 0.0 && p.min_coverage <= 1.0)) errors.push_back("min_coverage in [0, 1]");
  if (!(p.max_outline_error_fraction > 0.0)) errors.push_back("max_outline_error_fraction must be > 0");
  if (!(p.max_dot_error_px > 0.0)) errors.push_back("max_dot_error_px must be > 0");
  return errors;
}

PrintReport checkPrint(const mono::TargetModel& model, const mono::FeatureMatcherParams& matcher_params,
                       const CheckParams& params) {
  const auto errors = validateCheckParams(params);
  if (!errors.empty()) {
    std::string joined;
    for (const auto& e : errors) joined += (joined.empty() ? "" : "; ") + e;
    throw std::invalid_argument("check parameters: " + joined);
  }
  if (!model.hasTexture()) throw std::invalid_argument("the target model has no texture (the print)");
  PrintReport report;
  cv::Scalar mean, stddev;
  cv::meanStdDev(model.textureGray(), mean, stddev);
  report.print_contrast_dn = stddev[0];
  report.min_dot_contrast_dn = minDotContrast(model, model.textureGray());
  report.required_inliers =
      static_cast<int>(std::ceil(params.inlier_margin * matcher_params.min_inliers));

  mono::FeatureMatcher matcher(matcher_params);
  std::string reason;
  const bool model_ok = matcher.buildModel(model.textureGray(), &reason);
  report.model_keypoints = matcher.modelKeypointCount();
  const mono::DarkDotLocator locator;
  std::mt19937 rng(params.seed);
  for (const auto& view : params.cases) {
    CaseResult result;
    if (model_ok) {
      result = examineCase(view, model, matcher, locator, report.required_inliers, params, &rng);
    } else {
      result.view = view;
      result.problems = {PrintProblem::kLowTexture};
    }
    for (PrintProblem p : result.problems) addOnce(&report.problems, p);
    report.cases.push_back(result);
  }
  if (report.print_contrast_dn < params.min_print_contrast_dn) {
    addOnce(&report.problems, PrintProblem::kLowContrast);
  }
  if (report.min_dot_contrast_dn < params.min_dot_contrast_dn) {
    addOnce(&report.problems, PrintProblem::kDotsLowContrast);
  }
  std::sort(report.problems.begin(), report.problems.end());
  report.passed = report.problems.empty();
  return report;
}

std::string formatReport(const PrintReport& report, const CheckParams& params) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(1);
  out << "print: RMS contrast " << report.print_contrast_dn << " DN (need >= "
      << params.min_print_contrast_dn << "), lowest dot contrast " << report.min_dot_contrast_dn
      << " DN (need >= " << params.min_dot_contrast_dn << "), " << report.model_keypoints
      << " model keypoints\n";
  out << "camera: blur sigma " << params.blur_sigma_px << " px, noise " << params.noise_sigma_dn
      << " DN; a view passes with >= " << report.required_inliers << " inliers, coverage >= "
      << std::setprecision(2) << params.min_coverage << ", all 5 dots\n";
  out << "  range   yaw  face px  matches  inliers  coverage  outline err  dots  views  result\n";
  for (const auto& c : report.cases) {
    out << std::setprecision(1) << std::setw(6) << c.view.range_m << " m" << std::setw(5)
        << c.view.yaw_deg << std::setw(9) << c.face_width_px << std::setw(9) << c.matches
        << std::setw(9) << c.inliers << std::setprecision(2) << std::setw(10) << c.coverage
        << std::setprecision(1) << std::setw(10) << c.outline_error_px << " px" << std::setw(4)
        << c.dots_found << "/5" << std::setw(4) << c.views_passed << "/" << c.views << "  "
        << (c.passed ? "pass" : "FAIL");
    for (PrintProblem p : c.problems) out << " " << problemName(p);
    out << "\n";
  }
  out << (report.passed ? "PASS" : "FAIL") << "\n";
  for (PrintProblem p : report.problems) {
    out << "  " << problemName(p) << ": " << problemAdvice(p) << "\n";
  }
  return out.str();
}

}  // namespace target_print
}  // namespace docking_perception
