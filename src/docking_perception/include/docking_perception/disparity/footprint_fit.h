// Where the port is, from the mockup's top-down outline in the disparity (issue 11 / 15).
//
// The disparity detector's blob is the mockup's visible parts: the face, one side of the box and the
// solar panels. When the target is turned, the nearest of them is a panel tip or the face's near edge,
// so the centroid of the blob's nearest layer lies 0.1-0.4 m beside the port (the disparity source's
// confident wrong estimates). This fits the mockup's footprint, seen from above (config/target.yaml's
// face, box and panels), to the blob's depth profile: one point per image column (the median
// disparity of the blob's pixels in it, reprojected to X and Z), and reads the port off the fitted
// footprint.
//
// Method: for each yaw of the face towards the camera (a coarse grid, then 1 degree around the best),
// the footprint's visible segments (face, the camera-side box wall, both panels) are placed by a
// translation-only ICP from the profile's centroid, with each point's distance truncated at the inlier
// distance (which grows with range as the depth noise does). The yaw with the smallest truncated cost
// wins. The mockup is symmetric front to back (panels at mid-depth), so a face turned away is
// indistinguishable from one turned towards the camera; the fit assumes the face is turned towards
// the camera, as it is whenever the chaser can dock.
//
// ROS-free: plain C++17 and Eigen.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "docking_perception/disparity/disparity_detector.h"

namespace docking_perception {
namespace disparity {

struct FootprintFitParams {
  double inlier_distance_m = 0.05;   // at zero range; grows by the depth noise of depth_sigma_px
  double depth_sigma_px = 0.1;       // disparity noise of one column's median (px), for the growth
  double coarse_yaw_step_deg = 4.0;  // first pass over (-max_yaw, max_yaw)
  double max_yaw_deg = 86.0;         // the face turned at most this far from the line of sight
  int iterations = 8;                // ICP steps per yaw
};

struct FootprintFit {
  bool valid = false;            // false: fewer than kMinProfilePoints columns, or no yaw converged
  Eigen::Vector2d port_xz{0.0, 0.0};  // the port in the left rectified optical frame's X-Z plane (m)
  double yaw_rad = 0.0;          // face normal's angle from the line of sight to the camera
                                 // (positive: normal turned towards +X)
  double inlier_fraction = 0.0;  // of the profile points, within the inlier distance of the footprint
  double rms_m = 0.0;            // of the inliers' distances
  int profile_points = 0;
};

// Fewer profile points than this: no fit (too little of the target to place a footprint).
constexpr int kMinProfilePoints = 6;

// The blob's depth profile: for each image column with at least `min_pixels` of the given points,
// the median disparity reprojected to (X, Z) with the rectified model.
std::vector<Eigen::Vector2d> columnProfile(const std::vector<int>& columns,
                                           const std::vector<float>& disparities_px,
                                           const StereoGeometry& geometry, int min_pixels = 3);

// Fits the footprint of `shape` to `profile` (X, Z points). Never throws; invalid on too few points.
FootprintFit fitFootprint(const std::vector<Eigen::Vector2d>& profile, const TargetShape& shape,
                          const StereoGeometry& geometry, const FootprintFitParams& params);

}  // namespace disparity
}  // namespace docking_perception
