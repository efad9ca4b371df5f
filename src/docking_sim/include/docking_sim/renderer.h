// Renders one camera: planar textured polygons with perspective-correct texturing and a z-buffer onto
// an ideal pinhole image, then lens distortion (plumb_bob, precomputed remap), blur, glare, vignetting,
// noise. ROS-free; deterministic for a seed; no heap work per frame after the first.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <cstdint>
#include <functional>
#include <utility>
#include <random>
#include <vector>

#include "docking_sim/configs.h"
#include "docking_sim/scene.h"

namespace docking_sim {

/// Motion blur: sub-frames at most this far apart (px of the largest projected displacement over the
/// exposure). The average of copies s px apart is a comb; the residual blur (sigma 0.6) leaves
/// exp(-2 pi^2 0.36 / s^2) of its ripple: 4 % at 1.5 px (17 % at 2 px), for 2/3 of the sub-frames
/// (the cost) of a 1 px step.
constexpr double kMotionBlurStepPx = 1.5;

/// CPU time of the stages of the last render, ms (thread CPU time; for the benchmark).
struct RenderTiming {
  double rasterize_ms{0};   ///< all sub-frames, with specular and their accumulation
  double defocus_ms{0};     ///< depth-of-field blend
  double distort_ms{0};
  double effects_ms{0};     ///< residual blur, glare, vignetting, noise, LED spots, exposure metering
};

/// What the last frame's camera did (for tools and tests): exposure, gain, blur it rendered with.
struct ExposureReport {
  double exposure_time_s{0};   ///< this frame's exposure (auto-exposure's choice, or the fixed one)
  double gain{1};              ///< analog gain (noise sigma = the lighting's noise_sigma x gain)
  double brightness{1};        ///< scene brightness factor: exposure_time_s / nominal x gain
  double measured_mean{0};     ///< mean grey level of the frame (what auto-exposure meters)
  int subframes{1};            ///< sub-frames averaged for motion blur
  double motion_px{0};         ///< largest projected displacement over the exposure (the sub-frame count's basis)
};

/// The poses of the camera and of the target robot at a time offset (s) from the frame's stamp (the
/// exposure's middle): motion blur renders sub-frames across the exposure from these.
struct ExposureMotion {
  std::function<Eigen::Isometry3d(double)> world_T_camera;
  std::function<Eigen::Isometry3d(double)> world_T_target_robot;
};

struct RenderOptions {
  bool distortion{true};
  bool effects{true};   ///< blur, glare, vignetting, noise (false: the clean distorted render)
};

class CameraRenderer {
 public:
  /// band decides the output: kVisible -> CV_8UC3 (bgr8), kInfrared -> CV_8UC1 (mono8).
  CameraRenderer(const CameraCalibration& calibration, Band band, const CameraEffects& effects,
                 const LightingScenario& lighting, uint64_t seed, const RenderOptions& options = {});

  /// Renders the scene seen from a camera at world_T_camera (optical frame: z forward, x right, y down),
  /// one instant (no motion blur; auto-exposure and defocus as configured).
  const cv::Mat& render(const Scene& scene, const Eigen::Isometry3d& world_T_camera);
  /// Renders one exposure: sub-frames across it when things move (motion blur), the scene's target
  /// placed by motion.world_T_target_robot at each (the scene is left at offset 0).
  const cv::Mat& render(Scene& scene, const ExposureMotion& motion);

  /// The largest displacement (px) of the target's outline and of the static scene (sampled through
  /// the last depth buffer) between the exposure's start and end, for an exposure of exposure_s.
  double projectedMotionPx(const Scene& scene, const ExposureMotion& motion, double exposure_s) const;
  const ExposureReport& lastExposure() const { return exposure_; }
  const CameraEffects& effects() const { return effects_; }
  /// The z-buffer of the last frame (CV_32F 1/z, ideal image with its margin; 0 = nothing).
  const cv::Mat& depthBuffer() const { return depth_; }

  /// The undistorted pinhole render of the last frame (with a margin; see idealPrincipalOffset()).
  /// Visible band: CV_8UC4 (b, g, r, 0); IR: CV_8UC1.
  const cv::Mat& idealImage() const { return ideal_; }
  /// Pixel (u, v) of the output's pinhole model sits at (u + dx, v + dy) in idealImage().
  cv::Point2i idealPrincipalOffset() const { return pad_; }
  Band band() const { return band_; }
  const RenderTiming& lastTiming() const { return timing_; }

 private:
  struct DefocusLut;
  /// The pixels a decal may touch (inclusive bounds in ideal_).
  struct PixelRange {
    int x_begin, x_end, y_begin, y_end;
  };
  // Construction steps (in this order: the noise table draws from rng_).
  /// With distortion: where each raw pixel centre looks in ideal_ (map_x, map_y), and the margin pad_.
  void undistortPixelCentres(cv::Mat* map_x, cv::Mat* map_y);
  /// The distortion lookup (remap_offset_, remap_weights_) from those maps.
  void buildRemapTables(const cv::Mat& map_x, const cv::Mat& map_y);
  void buildVignette();
  void buildNoiseTable();
  void initExposure();
  void buildGlare();

  template <int kChannels>
  void rasterize(const Scene& scene, const Eigen::Isometry3d& camera_T_world);
  /// Rasterises one sub-frame (surfaces, specular, LEDs with weight `led_weight`) into ideal_/depth_.
  void rasterizeSubframe(const Scene& scene, const Eigen::Isometry3d& world_T_camera, double led_weight);
  /// The exposure's shared tail: defocus, distortion, effects, metering. t0: CPU ms at the frame start.
  const cv::Mat& finishFrame(double t0, double t_raster);
  /// Blinn-Phong highlights of the glossy surfaces, added to ideal_ where the surface is what shows.
  template <int kChannels>
  void addSpecular(const Scene& scene, const Surface& surface, const Eigen::Isometry3d& camera_T_world);
  /// Depth of field: per-pixel Gaussian of the circle of confusion's sigma (from depth_), by blending
  /// ideal_ blurred at fixed sigma levels, weighted by variance between the two that bracket it.
  void applyDefocus();
  /// The smallest and largest defocus sigma (px) over the z-buffer (the largest capped at the top level).
  void defocusSigmaRange(double inv_s, double scale, double* min_sigma, double* max_sigma) const;
  /// defocus_levels_[1..top]: ideal_ blurred at each level some pixel blends (others: ideal_ itself).
  void blurUsedDefocusLevels(const DefocusLut& lut, int top);
  /// defocus_out_: per pixel, the blend of the two levels that bracket its sigma.
  void blendDefocusLevels(const DefocusLut& lut, int top);
  /// Auto-exposure: from the frame just rendered (mean `mean`), the next frame's exposure and gain.
  void updateExposure(double mean);
  /// Whether the next frame's exposure and gain equal the last one's (within kAeTolerance).
  bool exposureSettled() const;
  template <int kChannels>
  void drawSurface(const Surface& surface, const Eigen::Isometry3d& camera_T_world);
  /// The pixels [x0, x1] of row y inside projected_ (false: none).
  bool projectedSpan(int y, int* x0, int* x1) const;
  // The span steps are always inlined into drawSurface (renderer.cpp): as calls, rasterising cost
  // ~5 % more (sim_render --bench, eval_real_clutter_2m).
  /// An untextured span: depth test and the flat colour.
  template <int kChannels>
  void fillFlatSpan(const Eigen::Matrix3d& H, int y, int x0, int x1, uint32_t flat);
  /// A textured span: the texture level for its footprint, then 16-pixel segments of texel fetches.
  template <int kChannels>
  void shadeTexturedSpan(const Surface& surface, const Eigen::Matrix3d& H, int y, int x0, int x1, uint32_t gain_u);
  /// A decal (Surface::decal): area coverage of each pixel's square (exact polygon clipping on the
  /// outline's edge pixels), blended over the image; depth test against the z-buffer with a bias.
  template <int kChannels>
  void drawDecal(const Surface& surface, const Eigen::Isometry3d& camera_T_world);
  /// The decal's outward edges (edges_) and the pixels it may touch; false for a degenerate outline.
  bool decalEdges(PixelRange* pixels);
  /// Clips the outline to z >= near, projects it into projected_ (ideal_ pixels) and computes the
  /// pixel -> (s, t, 1/z) homography H. False when nothing of it can show.
  bool projectOutline(const Surface& surface, const Eigen::Isometry3d& camera_T_world, Eigen::Matrix3d* H);
  template <int kChannels>
  uint32_t flatColour(const Surface& surface, int gain_fixed) const;
  void applyEffects();
  /// IR: the scene's LEDs that show (facing the camera, their centre not hidden in the z-buffer),
  /// projected through the lens model into led_spots_ (output pixels).
  void projectLeds(const Scene& scene, const Eigen::Isometry3d& camera_T_world, double weight);
  /// Adds the spots of led_spots_ to `image` (the output's size, CV_8UC1), saturating: each a
  /// Gaussian with the disc's variance plus the lens's (lens_sigma_px) and the pixel's own, darkened
  /// by `vignette` (per pixel, 256 = 1; null: none).
  void addLedSpots(cv::Mat& image, double lens_sigma_px, const uint16_t* vignette);

  CameraCalibration calibration_;
  Band band_;
  CameraEffects effects_;
  LightingScenario lighting_;
  RenderOptions options_;
  double noise_sigma_{0.0};
  cv::Point2i pad_{0, 0};
  cv::Matx33d ideal_K_;
  cv::Mat ideal_;          ///< pinhole render with margin (visible: CV_8UC4 b, g, r, 0)
  cv::Mat depth_;          ///< CV_32F, 1/z (0 = nothing)
  /// Distortion: per output pixel the byte offset of the top-left source pixel in ideal_ and four
  /// bilinear weights (sum 2^14). Visible: per pixel top-left, bottom-left, top-right, bottom-right;
  /// IR: per group of four pixels the (top-left, top-right) pairs, then the (bottom-left,
  /// bottom-right) pairs.
  std::vector<int32_t> remap_offset_;
  std::vector<int16_t> remap_weights_;
  void applyDistortion();
  cv::Mat distorted_;
  cv::Mat blurred_;
  cv::Mat glare_;          ///< additive, same type as the output (empty: no glare)
  std::vector<uint16_t> vignette_;  ///< per pixel, 256 = no darkening
  std::vector<int8_t> noise_table_;
  std::mt19937_64 rng_;
  cv::Mat output_;
  RenderTiming timing_;
  // Scratch polygons (kept to avoid per-frame allocation).
  std::vector<Eigen::Vector3d> clip_a_, clip_b_;
  std::vector<Eigen::Vector2d> projected_;
  std::vector<Eigen::Vector2d> cover_a_, cover_b_;  ///< decal coverage: outline clipped to a pixel
  std::vector<Eigen::Vector3d> edges_;              ///< decal: outward unit normal (x, y) and offset
  std::vector<std::pair<double, std::size_t>> order_;  ///< draw order: (squared distance, surface)
  /// An LED as the sensor sees it this frame: centre (output pixels), the variance of its projected
  /// disc (px^2) and the light it brings (grey levels * px^2: radiance * 255 * projected area).
  struct LedSpot {
    double x, y, disc_variance, integral;
  };
  std::vector<LedSpot> led_spots_;
  std::vector<float> spot_row_, spot_col_;  ///< the separable Gaussian's factors along x and y
  // Exposure state: brightness_ scales every surface's gain and the LEDs (1 = the nominal exposure).
  double exposure_time_s_{0.02};
  double gain_{1.0};
  double brightness_{1.0};
  bool exposure_primed_{false};  ///< auto-exposure has settled once (the first frame iterates)
  ExposureReport exposure_;
  cv::Mat accumulator_;          ///< CV_16U sum of the sub-frames (ideal_'s size and channels)
  std::vector<cv::Mat> defocus_levels_;  ///< ideal_ blurred at kDefocusSigmas (index 0: unused)
  cv::Mat defocus_out_;
  double uniform_defocus_variance_{0.0};  ///< px^2 folded into the residual blur (applyDefocus)
};

}  // namespace docking_sim
