// Error statistics of the comparison: percentiles and the pose / velocity errors against the truth.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace docking_perception {
namespace compare {

// Linear interpolation between the closest ranks (q in [0, 1]); NaN for an empty set.
double percentile(std::vector<double> values, double q);

// Angle of R_a R_b^T, degrees.
double rotationErrorDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);

}  // namespace compare
}  // namespace docking_perception
