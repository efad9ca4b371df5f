#include "docking_perception/disparity/footprint_fit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

namespace docking_perception {
namespace disparity {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kFineYawStepDeg = 1.0;
constexpr int kFaceSamples = 7;  // points along the face checked for support in the profile
// An ICP step that moves the port less than this has converged: the steps left would move it less
// still, a fraction of the ~cm the port is known to (measured: ports within 2 mm of running all steps,
// on 45 rendered far pairs; a looser stop or a thinned coarse pass moved some to another yaw).
constexpr double kConvergedStepM = 0.0005;

struct Segment {
  Eigen::Vector2d a, b;
};

// The face, two panels and one side wall at most: kept on the stack, built once per ICP step.
struct VisibleSegments {
  std::array<Segment, 4> items;
  int count = 0;
  void add(const Segment& segment) { items[static_cast<std::size_t>(count++)] = segment; }
  const Segment* begin() const { return items.data(); }
  const Segment* end() const { return items.data() + count; }
  const Segment& face() const { return items.front(); }
};

// The footprint's segments a camera at the origin can see with the face's normal at `normal`
// (unit, X-Z) and the port at `port`: the face, both panels, and the box wall on the camera's side
// (the back and the far wall are hidden behind the face).
VisibleSegments visibleSegments(const TargetShape& s, const Eigen::Vector2d& port, const Eigen::Vector2d& normal) {
  const Eigen::Vector2d along(-normal.y(), normal.x());  // along the face
  auto at = [&](double behind, double aside) { return Eigen::Vector2d(port - behind * normal + aside * along); };
  const double half = 0.5 * s.face_width_m;
  VisibleSegments segments;
  segments.add({at(0.0, -half), at(0.0, half)});  // the face first
  if (s.panel_span_m > 0.0) {
    const double p = s.panel_offset_behind_face_m;
    segments.add({at(p, half), at(p, half + s.panel_span_m)});
    segments.add({at(p, -half), at(p, -half - s.panel_span_m)});
  }
  const double side = along.dot(-port) > 0.0 ? 1.0 : -1.0;  // the wall whose outside faces the camera
  segments.add({at(0.0, side * half), at(s.body_depth_m, side * half)});
  return segments;
}

// The point of the footprint nearest to q.
Eigen::Vector2d nearestOnFootprint(const VisibleSegments& segments, const Eigen::Vector2d& q) {
  Eigen::Vector2d best = segments.face().a;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (const Segment& seg : segments) {
    const Eigen::Vector2d ab = seg.b - seg.a;
    const double length2 = ab.squaredNorm();
    const double u = length2 > 0.0 ? std::clamp((q - seg.a).dot(ab) / length2, 0.0, 1.0) : 0.0;
    const Eigen::Vector2d p = seg.a + u * ab;
    const double d2 = (q - p).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best = p;
    }
  }
  return best;
}

// The face is textured and faces the camera, so block matching sees it: a placement whose face lies
// where the profile has no points (the face put on a panel's data, both 0.3 m long) is penalised by the
// mean truncated distance from points along the face to the nearest profile point.
double unsupportedFace(const std::vector<Eigen::Vector2d>& profile, const Segment& face, double tau) {
  double sum = 0.0;
  for (int i = 0; i < kFaceSamples; ++i) {
    const double s = (i + 0.5) / kFaceSamples;
    const Eigen::Vector2d p = face.a + s * (face.b - face.a);
    double best = tau * tau;
    for (const Eigen::Vector2d& q : profile) best = std::min(best, (q - p).squaredNorm());
    sum += best;
  }
  return sum / kFaceSamples;
}

struct Placement {
  double cost = std::numeric_limits<double>::infinity();  // mean truncated squared distance
  double yaw_rad = 0.0;
  Eigen::Vector2d port{0.0, 0.0};
  int inliers = 0;
  double inlier_sum2 = 0.0;
};

// Translation-only ICP at one yaw, from `start`; inlier distance `tau`.
Placement placeAtYaw(const std::vector<Eigen::Vector2d>& profile, const TargetShape& shape, double yaw,
                     const Eigen::Vector2d& start, double tau, int iterations) {
  const Eigen::Vector2d to_camera = (-start).normalized();
  const double c = std::cos(yaw), s = std::sin(yaw);
  const Eigen::Vector2d normal(c * to_camera.x() - s * to_camera.y(), s * to_camera.x() + c * to_camera.y());
  Placement placement;
  placement.yaw_rad = yaw;
  placement.port = start;
  for (int iteration = 0; iteration <= iterations; ++iteration) {
    const auto segments = visibleSegments(shape, placement.port, normal);
    Eigen::Vector2d shift(0.0, 0.0);
    double cost = 0.0, inlier_sum2 = 0.0;
    int inliers = 0;
    for (const Eigen::Vector2d& q : profile) {
      const Eigen::Vector2d r = q - nearestOnFootprint(segments, q);
      const double d2 = r.squaredNorm();
      cost += std::min(d2, tau * tau);
      if (d2 <= tau * tau) {
        shift += r;
        inlier_sum2 += d2;
        ++inliers;
      }
    }
    placement.cost = cost / static_cast<double>(profile.size());
    placement.inliers = inliers;
    placement.inlier_sum2 = inlier_sum2;
    const Eigen::Vector2d step = inliers > 0 ? Eigen::Vector2d(shift / static_cast<double>(inliers))
                                             : Eigen::Vector2d::Zero();
    if (iteration == iterations || inliers == 0 || step.norm() < kConvergedStepM) {
      placement.cost += unsupportedFace(profile, segments.face(), tau);  // only the final placement's counts
      break;
    }
    placement.port += step;
  }
  return placement;
}

}  // namespace

std::vector<Eigen::Vector2d> columnProfile(const std::vector<int>& columns,
                                           const std::vector<float>& disparities_px,
                                           const StereoGeometry& g, int min_pixels) {
  std::map<int, std::vector<float>> by_column;
  const std::size_t n = std::min(columns.size(), disparities_px.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (disparities_px[i] > 0.0f) by_column[columns[i]].push_back(disparities_px[i]);
  }
  std::vector<Eigen::Vector2d> profile;
  profile.reserve(by_column.size());
  for (auto& [u, values] : by_column) {
    if (static_cast<int>(values.size()) < min_pixels) continue;
    auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    const double z = g.focal_px * g.baseline_m / static_cast<double>(*middle);
    profile.emplace_back((u - g.cx_px) * z / g.focal_px, z);
  }
  return profile;
}

FootprintFit fitFootprint(const std::vector<Eigen::Vector2d>& profile, const TargetShape& shape,
                          const StereoGeometry& geometry, const FootprintFitParams& params) {
  FootprintFit fit;
  fit.profile_points = static_cast<int>(profile.size());
  if (fit.profile_points < kMinProfilePoints || !(geometry.focal_px > 0.0 && geometry.baseline_m > 0.0)) {
    return fit;
  }
  Eigen::Vector2d centroid(0.0, 0.0);
  for (const auto& q : profile) centroid += q;
  centroid /= static_cast<double>(profile.size());
  if (!(centroid.y() > 0.0)) return fit;
  // A column's depth noise: dZ = Z^2 / (f B) * d_sigma.
  const double tau = params.inlier_distance_m + centroid.y() * centroid.y() /
                                                    (geometry.focal_px * geometry.baseline_m) *
                                                    params.depth_sigma_px;
  const double max_yaw = params.max_yaw_deg * kPi / 180.0;
  const double coarse = std::max(0.5, params.coarse_yaw_step_deg) * kPi / 180.0;
  Placement best;
  for (double yaw = -max_yaw; yaw <= max_yaw + 1e-9; yaw += coarse) {
    const Placement p = placeAtYaw(profile, shape, yaw, centroid, tau, params.iterations);
    if (p.cost < best.cost) best = p;
  }
  const double fine = kFineYawStepDeg * kPi / 180.0;
  const Placement coarse_best = best;
  for (double yaw = coarse_best.yaw_rad - coarse; yaw <= coarse_best.yaw_rad + coarse + 1e-9; yaw += fine) {
    if (std::abs(yaw) > max_yaw) continue;
    const Placement p = placeAtYaw(profile, shape, yaw, coarse_best.port, tau, params.iterations);
    if (p.cost < best.cost) best = p;
  }
  if (best.inliers == 0 || !std::isfinite(best.cost)) return fit;
  fit.valid = true;
  fit.port_xz = best.port;
  fit.yaw_rad = best.yaw_rad;
  fit.inlier_fraction = static_cast<double>(best.inliers) / static_cast<double>(profile.size());
  fit.rms_m = std::sqrt(best.inlier_sum2 / static_cast<double>(best.inliers));
  return fit;
}

}  // namespace disparity
}  // namespace docking_perception
