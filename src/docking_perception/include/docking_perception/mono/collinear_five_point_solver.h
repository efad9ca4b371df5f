// The paper's closed-form pose from 5 markers forming two collinear triples (section III.B).
//
// For a triple (P1, P2, P3) with P2 = (P1 + P3) / 2 and rays d_i = K^-1 [u_i v_i 1]^T, P_i = s_i d_i:
//     s2 d2 = (s1 d1 + s3 d3) / 2
// is a homogeneous 3x3 linear system in (s1, s2, s3). Its null space (the right singular vector of the
// smallest singular value, so that noisy rays still give the least-squares answer) fixes the depths up
// to scale; the known length |P1 - P3| fixes the scale. Each triple thus gives its 3D points and one
// direction of the target.
//
// Rotation: the direction of triple A (marker 2 -> 0) and of triple B (marker 2 -> 4), in the model and
// in the camera, are each orthonormalised by Gram-Schmidt (A first: it is the longer arm, so the better
// measured one) and completed by their cross product; R = F_camera * F_model^T.
// Position: given R, the least-squares translation that carries the 5 model markers onto the 5
// recovered points (marker 2 is recovered twice, once per triple, and averaged), t = mean(P) - R mean(M).
// This uses every recovered point rather than trusting one, and stays closed form: no iteration.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>

#include "docking_perception/mono/pose_types.h"
#include "docking_perception/mono/target_model.h"

namespace docking_perception {
namespace mono {

using MarkerPixels = std::array<Eigen::Vector2d, kMarkerCount>;

struct FivePointSolution {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // camera <- target
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  MarkerPoints points_camera{};       // the recovered 3D markers, camera frame
  double shared_marker_gap_m = 0.0;   // distance between the two estimates of marker 2 (a consistency check)
  double reprojection_rms_px = 0.0;   // of the model markers under (rotation, translation)
};

class CollinearFivePointSolver {
 public:
  // markers: the model (TargetModel validates the midpoint relations).
  explicit CollinearFivePointSolver(const MarkerPoints& markers);

  // pixels[i] is the image of markers[i]. False (with the reason) for a degenerate configuration:
  // depths of mixed sign (a point behind the camera or a non-collinear triple), or parallel arms.
  bool solve(const CameraIntrinsics& camera, const MarkerPixels& pixels, FivePointSolution* solution,
             std::string* reason) const;

  // solve() plus its covariance: the solver's Jacobian d(pose)/d(pixels) (central differences of the
  // closed form over the 10 pixel coordinates) propagates an isotropic pixel variance:
  // C = pixel_variance * J J^T. This is the covariance of this closed form itself (not of an optimal
  // estimator), so it shows the paper's solver's real weakness (out-of-plane tilt).
  bool solveWithCovariance(const CameraIntrinsics& camera, const MarkerPixels& pixels, double pixel_variance,
                           FivePointSolution* solution, Matrix6d* covariance, std::string* reason) const;

  const MarkerPoints& markers() const { return markers_; }

 private:
  MarkerPoints markers_;
  double length_a_m_;  // |M0 - M2|
  double length_b_m_;  // |M2 - M4|
  Eigen::Matrix3d model_frame_;  // Gram-Schmidt frame of the model arms (columns)
};

}  // namespace mono
}  // namespace docking_perception
