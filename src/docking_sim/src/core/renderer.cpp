#include "docking_sim/renderer.h"

#include "bilinear.h"

#include <docking_msgs/thread_cpu_time.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstring>
#include <cmath>

namespace docking_sim {
namespace {

using docking_msgs::threadCpuMs;

constexpr double kNearPlaneM = 0.02;

// The noise table holds round(kNoiseTableSigma * N(0, 1)); each frame scales it to the lighting's
// noise_sigma x gain in 8.8 fixed point (so gain changes need no new table).
constexpr double kNoiseTableSigma = 16.0;
// Depth of field: ideal_ is blurred at these sigmas (px) and each pixel blends the two that bracket its
// circle of confusion's sigma, by variance (the blend of two Gaussians has the wanted second moment).
constexpr double kDefocusSigmas[] = {0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0};
constexpr int kDefocusLevels = sizeof(kDefocusSigmas) / sizeof(kDefocusSigmas[0]);
constexpr int kDefocusLutPerPx = 64;   // sigma lookup resolution: 1/64 px
// When the frame's total blur (defocus with the residual, in quadrature) varies by less than this (px)
// between its nearest and farthest pixels, defocus is one uniform Gaussian folded into the residual
// blur (free) instead of the per-pixel blend (~3-5 ms): the C270 default at 0.4-8 m varies by 0.04 px.
constexpr double kUniformDefocusSpreadPx = 0.1;
// Auto-exposure: per frame, the brightness moves by (target / mean)^kAeStep (a real camera's loop
// settles over a few frames); the first frame iterates to within kAeTolerance, at most kAePrimingFrames.
constexpr double kAeStep = 0.7;
constexpr double kAeTolerance = 0.03;
constexpr int kAePrimingFrames = 10;
// Metering samples every kMeterStride-th pixel of every kMeterStride-th row.
constexpr int kMeterStride = 4;

// The visible band is rasterised as 32-bit b, g, r, 0 pixels (a CV_8UC4 image) read and written as
// uint32_t: that byte order holds on little-endian machines only.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the 32-bit texel layout assumes little-endian");

/// (channel * gain) >> 8 for the four bytes of a packed texel at once, exact for gain <= 256: each
/// 8-bit x 9-bit product fits its 16-bit lane, so two channels share one multiply without carries.
inline uint32_t shadePacked(uint32_t texel, uint32_t gain) {
  const uint32_t even = ((texel & 0x00ff00ffu) * gain >> 8) & 0x00ff00ffu;
  const uint32_t odd = (((texel >> 8) & 0x00ff00ffu) * gain) & 0xff00ff00u;
  return even | odd;
}

/// The same with saturation at 255, one channel at a time (gains above 1: rare, e.g. lamps, LEDs).
inline uint32_t shadePackedSaturating(uint32_t texel, uint32_t gain) {
  uint32_t out = 0;
  for (int shift = 0; shift < 24; shift += 8) {
    const uint32_t value = (((texel >> shift) & 0xffu) * gain) >> 8;
    out |= (value > 255u ? 255u : value) << shift;
  }
  return out;
}

/// A texel coordinate in 16.16 fixed point (bounded first: an almost edge-on span can send the
/// homography's quotient anywhere, and the conversion must stay defined). Truncation, not floor:
/// repeating textures are biased positive, and clamped ones map (-1, 0) to texel 0 either way.
inline int64_t toFixed(double texel) {
  // Comparisons, not std::fmin/fmax: those were library calls here (~5 % of the simulator's CPU in
  // make demo), and these give the same result, NaN included (-1e9).
  const double bounded = texel > -1e9 ? (texel < 1e9 ? texel : 1e9) : -1e9;
  return static_cast<int64_t>(bounded * 65536.0);
}

/// (a (256 - w) + b w) / 256 for the four bytes of two packed pixels or texels at once (w in 0..256),
/// rounded or truncated: each product stays inside its 16-bit lane (255 * 256 + 128 < 2^16).
inline uint32_t lerpPacked(uint32_t a, uint32_t b, uint32_t w, bool round) {
  const uint32_t half = round ? 0x00800080u : 0u;
  const uint32_t even = (((a & 0x00ff00ffu) * (256 - w) + (b & 0x00ff00ffu) * w + half) >> 8) & 0x00ff00ffu;
  const uint32_t odd = (((a >> 8) & 0x00ff00ffu) * (256 - w) + ((b >> 8) & 0x00ff00ffu) * w + half) & 0xff00ff00u;
  return even | odd;
}

}  // namespace

/// Per 1/64 px of defocus sigma: the lower bracketing level (kDefocusSigmas) and the upper one's weight
/// (of 256), and the entry a pixel's 1/z falls on.
struct CameraRenderer::DefocusLut {
  DefocusLut(int top, float inv_s, float lut_scale)
      : size(static_cast<int>(kDefocusSigmas[top] * kDefocusLutPerPx) + 1),
        level(static_cast<std::size_t>(size)),
        weight(static_cast<std::size_t>(size)),
        inv_s_f(inv_s),
        scale_f(lut_scale) {
    for (int i = 0; i < size; ++i) {
      const double sigma = static_cast<double>(i) / kDefocusLutPerPx;
      int k = 0;
      while (k + 1 < top && kDefocusSigmas[k + 1] <= sigma) ++k;
      const double lo = kDefocusSigmas[k], hi = kDefocusSigmas[k + 1];
      const double w = std::clamp((sigma * sigma - lo * lo) / (hi * hi - lo * lo), 0.0, 1.0);
      level[static_cast<std::size_t>(i)] = static_cast<uint16_t>(k);
      weight[static_cast<std::size_t>(i)] = static_cast<uint16_t>(std::lround(256.0 * w));
    }
  }
  std::size_t index(float inv_z) const {
    return static_cast<std::size_t>(std::min(size - 1, static_cast<int>(std::abs(inv_s_f - inv_z) * scale_f + 0.5f)));
  }
  int size;
  std::vector<uint16_t> level;
  std::vector<uint16_t> weight;
  float inv_s_f;  ///< 1 / focus distance
  float scale_f;  ///< LUT entries per unit of |1/s - 1/z|
};

namespace {

/// A texel index wrapped (repeating textures: sizes are powers of two) or clamped to the texture.
template <bool kRepeat>
inline int64_t texelIndex(int64_t i, int64_t mask) {
  if (kRepeat) return i & mask;
  return i < 0 ? 0 : (i > mask ? mask : i);
}

/// One segment of a textured span: depth test, texel fetch, shading, for `count` pixels from
/// depth/row on. A separate function per (repeat, saturate, bilinear) case keeps the loop free of
/// branches that never change within a span and lets the compiler keep everything in registers.
/// kBilinear: the four texels around the sample, weighted by its position among their centres (the
/// target's surfaces, Surface::bilinear); else the texel the sample falls in.
template <int kChannels, bool kRepeat, bool kSaturate, bool kBilinear>
double shadeSegmentImpl(int count, double nw, double dnw, int64_t u, int64_t du, int64_t v, int64_t dv, float* depth,
                        uchar* row, const BlockedLevel& img, uint32_t gain) {
  const uint32_t* u_offset = img.u_offset.data();
  const uint32_t* v_offset = img.v_offset.data();
  const uint32_t* texels4 = img.bgrx.data();
  const uchar* texels1 = img.gray.data();
  uint32_t* row4 = reinterpret_cast<uint32_t*>(row);  // CV_8UC4 rows are 4-byte aligned
  const int64_t mask_u = img.width - 1, mask_v = img.height - 1;
  for (int i = 0; i < count; ++i, nw += dnw, u += du, v += dv) {
    const float inv_z = static_cast<float>(nw);
    if (inv_z <= depth[i]) continue;
    depth[i] = inv_z;
    // Texel j covers [j, j + 1): its centre is j + 1/2, so the bilinear neighbours start half a texel lower.
    // (The bias keeps u and v positive for repeating textures.)
    constexpr int64_t kHalfTexel = kBilinear ? 0x8000 : 0;
    const int64_t us = u - kHalfTexel, vs = v - kHalfTexel;
    const int64_t iu = texelIndex<kRepeat>(us >> 16, mask_u), iv = texelIndex<kRepeat>(vs >> 16, mask_v);
    const uint32_t index = u_offset[iu] + v_offset[iv];
    uint32_t t;
    if (kBilinear) {
      const int64_t iu1 = texelIndex<kRepeat>((us >> 16) + 1, mask_u);
      const int64_t iv1 = texelIndex<kRepeat>((vs >> 16) + 1, mask_v);
      const uint32_t wu = static_cast<uint32_t>((us & 0xffff) >> 8), wv = static_cast<uint32_t>((vs & 0xffff) >> 8);
      const uint32_t right = u_offset[iu1] + v_offset[iv], below = u_offset[iu] + v_offset[iv1];
      const uint32_t diagonal = u_offset[iu1] + v_offset[iv1];
      if (kChannels == 4) {
        // Truncated (the grey path rounds): under 1 DN darker on average, as measured in make eval.
        t = lerpPacked(lerpPacked(texels4[index], texels4[right], wu, false),
                       lerpPacked(texels4[below], texels4[diagonal], wu, false), wv, false);
      } else {
        const uint32_t top = texels1[index] * (256 - wu) + texels1[right] * wu;
        const uint32_t bottom = texels1[below] * (256 - wu) + texels1[diagonal] * wu;
        t = (top * (256 - wv) + bottom * wv + 0x8000) >> 16;
      }
    } else {
      t = kChannels == 4 ? texels4[index] : texels1[index];
    }
    if (kChannels == 4) {
      row4[i] = kSaturate ? shadePackedSaturating(t, gain) : shadePacked(t, gain);
    } else {
      const uint32_t value = (t * gain) >> 8;
      row[i] = static_cast<uchar>(value > 255u ? 255u : value);
    }
  }
  return nw;
}

template <int kChannels, bool kBilinear>
double shadeSegmentFiltered(bool repeat, bool saturate, int count, double nw, double dnw, int64_t u, int64_t du,
                            int64_t v, int64_t dv, float* depth, uchar* row, const BlockedLevel& img, uint32_t gain) {
  if (repeat) {
    return saturate
               ? shadeSegmentImpl<kChannels, true, true, kBilinear>(count, nw, dnw, u, du, v, dv, depth, row, img, gain)
               : shadeSegmentImpl<kChannels, true, false, kBilinear>(count, nw, dnw, u, du, v, dv, depth, row, img, gain);
  }
  return saturate
             ? shadeSegmentImpl<kChannels, false, true, kBilinear>(count, nw, dnw, u, du, v, dv, depth, row, img, gain)
             : shadeSegmentImpl<kChannels, false, false, kBilinear>(count, nw, dnw, u, du, v, dv, depth, row, img, gain);
}

template <int kChannels>
double shadeSegment(bool bilinear, bool repeat, bool saturate, int count, double nw, double dnw, int64_t u, int64_t du,
                    int64_t v, int64_t dv, float* depth, uchar* row, const BlockedLevel& img, uint32_t gain) {
  return bilinear
             ? shadeSegmentFiltered<kChannels, true>(repeat, saturate, count, nw, dnw, u, du, v, dv, depth, row, img, gain)
             : shadeSegmentFiltered<kChannels, false>(repeat, saturate, count, nw, dnw, u, du, v, dv, depth, row, img,
                                                      gain);
}

}  // namespace

CameraRenderer::CameraRenderer(const CameraCalibration& calibration, Band band, const CameraEffects& effects,
                               const LightingScenario& lighting, uint64_t seed, const RenderOptions& options)
    : calibration_(calibration), band_(band), effects_(effects), lighting_(lighting), options_(options), rng_(seed) {
  const int w = calibration.width, h = calibration.height;
  const int type = band == Band::kVisible ? CV_8UC3 : CV_8UC1;
  noise_sigma_ = band == Band::kVisible ? lighting.visible.noise_sigma : lighting.ir.noise_sigma;

  cv::Mat map_x, map_y;  // where each output pixel samples ideal_ (kept for the lookup tables below)
  if (options.distortion) undistortPixelCentres(&map_x, &map_y);
  ideal_K_ = calibration.K;
  ideal_K_(0, 2) += pad_.x;
  ideal_K_(1, 2) += pad_.y;
  // Visible: 4 bytes per ideal pixel (b, g, r, 0) so that the rasteriser moves whole texels and the
  // distortion lookup interpolates all channels of a pixel in one SIMD register.
  ideal_.create(h + 2 * pad_.y, w + 2 * pad_.x, band == Band::kVisible ? CV_8UC4 : CV_8UC1);
  if (options.distortion) buildRemapTables(map_x, map_y);
  depth_.create(ideal_.size(), CV_32F);
  depth_.setTo(cv::Scalar(0.0f));  // read before the first frame (projectedMotionPx): "nothing there"
  output_.create(h, w, type);
  buildVignette();
  buildNoiseTable();
  initExposure();
  if (band == Band::kVisible && lighting.glare.enabled) buildGlare();
}

void CameraRenderer::undistortPixelCentres(cv::Mat* map_x, cv::Mat* map_y) {
  // Where each raw (distorted) pixel looks in the ideal pinhole image: undistort every pixel centre
  // once. Barrel distortion looks beyond the pinhole frame, so the ideal image gets a margin.
  const int w = calibration_.width, h = calibration_.height;
  std::vector<cv::Point2f> raw;
  raw.reserve(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) raw.emplace_back(static_cast<float>(x), static_cast<float>(y));
  }
  std::vector<cv::Point2f> ideal;
  cv::undistortPoints(raw, ideal, cv::Mat(calibration_.K), cv::Mat(calibration_.D), cv::noArray(),
                      cv::Mat(calibration_.K), cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-9));
  float min_x = 0, min_y = 0, max_x = static_cast<float>(w - 1), max_y = static_cast<float>(h - 1);
  for (const auto& p : ideal) {
    min_x = std::min(min_x, p.x);
    min_y = std::min(min_y, p.y);
    max_x = std::max(max_x, p.x);
    max_y = std::max(max_y, p.y);
  }
  pad_.x = static_cast<int>(std::ceil(std::max(-min_x, max_x - (w - 1)))) + 2;
  pad_.y = static_cast<int>(std::ceil(std::max(-min_y, max_y - (h - 1)))) + 2;
  map_x->create(h, w, CV_32F);
  map_y->create(h, w, CV_32F);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const cv::Point2f& p = ideal[static_cast<std::size_t>(y) * w + x];
      map_x->at<float>(y, x) = p.x + static_cast<float>(pad_.x);  // inside the margin by construction
      map_y->at<float>(y, x) = p.y + static_cast<float>(pad_.y);
    }
  }
}

void CameraRenderer::buildRemapTables(const cv::Mat& map_x, const cv::Mat& map_y) {
  // Per output pixel: byte offset of the top-left source pixel and the four bilinear weights
  // (7-bit per axis, products <= 2^14, summing to 2^14), in the order the SIMD loops consume them.
  const int w = calibration_.width, h = calibration_.height;
  const bool visible = band_ == Band::kVisible;
  remap_offset_.resize(static_cast<std::size_t>(w) * h);
  remap_weights_.assign(4 * ((remap_offset_.size() + 3) / 4 * 4), 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const double sx = map_x.at<float>(y, x), sy = map_y.at<float>(y, x);
      const int x0 = static_cast<int>(std::floor(sx)), y0 = static_cast<int>(std::floor(sy));
      const int wx = static_cast<int>(std::lround((sx - x0) * 128.0)), wy = static_cast<int>(std::lround((sy - y0) * 128.0));
      remap_offset_[i] = static_cast<int32_t>(y0 * ideal_.step + x0 * ideal_.elemSize());
      const auto tl = static_cast<int16_t>((128 - wx) * (128 - wy)), tr = static_cast<int16_t>(wx * (128 - wy));
      const auto bl = static_cast<int16_t>((128 - wx) * wy), br = static_cast<int16_t>(wx * wy);
      if (visible) {  // per pixel: TL, BL, TR, BR
        const int16_t wts[4] = {tl, bl, tr, br};
        std::copy(wts, wts + 4, remap_weights_.begin() + 4 * i);
      } else {  // per group of 4 pixels: (TL, TR) of each, then (BL, BR) of each
        const std::size_t group = 16 * (i / 4), k = 2 * (i % 4);
        remap_weights_[group + k] = tl;
        remap_weights_[group + k + 1] = tr;
        remap_weights_[group + 8 + k] = bl;
        remap_weights_[group + 8 + k + 1] = br;
      }
    }
  }
}

void CameraRenderer::buildVignette() {
  // Vignetting: cos^4-like fall-off, `vignetting` darker at the corners.
  const int w = calibration_.width, h = calibration_.height;
  vignette_.resize(static_cast<std::size_t>(w) * h * output_.channels());
  const double cx = calibration_.K(0, 2), cy = calibration_.K(1, 2);
  const double r_corner2 = cx * cx + cy * cy;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double r2 = ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / r_corner2;
      const auto factor = static_cast<uint16_t>(std::lround(256.0 * (1.0 - effects_.vignetting * r2)));
      for (int c = 0; c < output_.channels(); ++c) {
        vignette_[(static_cast<std::size_t>(y) * w + x) * output_.channels() + c] = factor;
      }
    }
  }
}

void CameraRenderer::buildNoiseTable() {
  // Noise: a table twice the frame size; each frame reads it from a random offset (no RNG per pixel).
  const std::size_t frame_bytes =
      static_cast<std::size_t>(calibration_.width) * calibration_.height * output_.channels();
  noise_table_.resize(2 * frame_bytes);
  std::normal_distribution<double> normal(0.0, kNoiseTableSigma);
  for (auto& n : noise_table_) n = static_cast<int8_t>(std::clamp(std::lround(normal(rng_)), -127L, 127L));
}

void CameraRenderer::initExposure() {
  exposure_time_s_ = effects_.exposure_time_s;
  if (effects_.ae_enabled) {
    // Start inside the camera's range, the lost brightness in gain (as updateExposure would).
    exposure_time_s_ = std::clamp(effects_.exposure_time_s, effects_.ae_min_exposure_s, effects_.ae_max_exposure_s);
    gain_ = std::clamp(effects_.exposure_time_s / exposure_time_s_, 1.0, effects_.ae_max_gain);
    brightness_ = exposure_time_s_ / effects_.exposure_time_s * gain_;
  }
}

void CameraRenderer::buildGlare() {
  // Glare: an additive bright spot with a faint horizontal streak (visible cameras only).
  const int w = calibration_.width, h = calibration_.height;
  const auto& glare_config = lighting_.glare;
  cv::Mat glare(h, w, CV_32F);
  const double gx = glare_config.center_u_frac * w, gy = glare_config.center_v_frac * h;
  const double radius = glare_config.radius_frac * w;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double dx = (x - gx) / radius, dy = (y - gy) / radius;
      const double spot = std::exp(-(dx * dx + dy * dy));
      const double streak = 0.25 * std::exp(-dy * dy * 60.0) * std::exp(-std::abs(dx) * 0.8);
      glare.at<float>(y, x) = static_cast<float>(glare_config.peak * (spot + streak));
    }
  }
  cv::Mat glare8;
  glare.convertTo(glare8, CV_8U);
  cv::cvtColor(glare8, glare_, cv::COLOR_GRAY2BGR);
  // Warm the spot slightly (a lamp, not a white card).
  cv::multiply(glare_, cv::Scalar(0.92, 0.98, 1.0), glare_);
}

const cv::Mat& CameraRenderer::render(const Scene& scene, const Eigen::Isometry3d& world_T_camera) {
  const int frames = effects_.ae_enabled && options_.effects && !exposure_primed_ ? kAePrimingFrames : 1;
  for (int i = 0; i < frames; ++i) {
    const double t0 = threadCpuMs();
    led_spots_.clear();
    rasterizeSubframe(scene, world_T_camera, 1.0);
    exposure_.subframes = 1;
    exposure_.motion_px = 0.0;
    finishFrame(t0, threadCpuMs());
    if (exposureSettled()) break;
  }
  exposure_primed_ = true;
  return output_;
}

const cv::Mat& CameraRenderer::render(Scene& scene, const ExposureMotion& motion) {
  const int frames = effects_.ae_enabled && options_.effects && !exposure_primed_ ? kAePrimingFrames : 1;
  for (int i = 0; i < frames; ++i) {
    const double t0 = threadCpuMs();
    scene.update(motion.world_T_target_robot(0.0));
    const double exposure_s = exposure_time_s_;
    double motion_px = 0.0;
    int subframes = 1;
    if (effects_.motion_blur_enabled && options_.effects) {
      motion_px = projectedMotionPx(scene, motion, exposure_s);
      subframes = static_cast<int>(std::clamp(std::ceil(motion_px / kMotionBlurStepPx), 1.0,
                                              effects_.motion_blur_max_subframes));
    }
    led_spots_.clear();
    if (subframes == 1) {
      rasterizeSubframe(scene, motion.world_T_camera(0.0), 1.0);
    } else {
      // Sub-frame k covers [k, k + 1) / n of the exposure and is rendered at its middle. The middle
      // sub-frame goes last, so depth_ ends as the exposure's middle (defocus and LED occlusion use it).
      accumulator_.create(ideal_.size(), CV_MAKETYPE(CV_16U, ideal_.channels()));
      accumulator_.setTo(cv::Scalar::all(0));
      const int middle = subframes / 2;
      for (int k = 0; k < subframes; ++k) {
        const int index = k == subframes - 1 ? middle : (k < middle ? k : k + 1);
        const double dt = ((index + 0.5) / subframes - 0.5) * exposure_s;
        scene.update(motion.world_T_target_robot(dt));
        rasterizeSubframe(scene, motion.world_T_camera(dt), 1.0 / subframes);
        cv::add(accumulator_, ideal_, accumulator_, cv::noArray(), accumulator_.type());
      }
      accumulator_.convertTo(ideal_, ideal_.type(), 1.0 / subframes);  // rounds to nearest
      scene.update(motion.world_T_target_robot(0.0));
    }
    exposure_.subframes = subframes;
    exposure_.motion_px = motion_px;
    finishFrame(t0, threadCpuMs());
    if (exposureSettled()) break;
  }
  exposure_primed_ = true;
  return output_;
}

void CameraRenderer::rasterizeSubframe(const Scene& scene, const Eigen::Isometry3d& world_T_camera,
                                       double led_weight) {
  const Eigen::Isometry3d camera_T_world = world_T_camera.inverse();
  ideal_.setTo(cv::Scalar::all(0));
  depth_.setTo(cv::Scalar(0.0f));
  if (band_ == Band::kVisible) {
    rasterize<4>(scene, camera_T_world);
  } else {
    rasterize<1>(scene, camera_T_world);
  }
  if (effects_.specular_strength > 0.0) {
    for (const Surface& surface : scene.surfaces()) {
      if (!surface.glossy) continue;
      if (band_ == Band::kVisible) {
        addSpecular<4>(scene, surface, camera_T_world);
      } else {
        addSpecular<1>(scene, surface, camera_T_world);
      }
    }
  }
  if (band_ == Band::kInfrared) projectLeds(scene, camera_T_world, led_weight);
}

const cv::Mat& CameraRenderer::finishFrame(double t0, double t_raster) {
  if (options_.effects) applyDefocus();
  const double t_defocus = threadCpuMs();
  if (options_.distortion) {
    applyDistortion();
  } else {
    const cv::Mat crop = ideal_(cv::Rect(pad_.x, pad_.y, output_.cols, output_.rows));
    if (crop.channels() == 4) {
      cv::cvtColor(crop, distorted_, cv::COLOR_BGRA2BGR);
    } else {
      crop.copyTo(distorted_);
    }
  }
  const double t_distort = threadCpuMs();
  if (options_.effects) {
    applyEffects();
  } else {
    distorted_.copyTo(output_);
    addLedSpots(output_, 0.0, nullptr);  // no lens blur, no vignetting: the disc as the pixels sample it
  }
  // Metering: the mean grey level of the frame (a sparse grid is plenty for a mean).
  double sum = 0.0;
  long count = 0;
  const int channels = output_.channels();
  for (int y = kMeterStride / 2; y < output_.rows; y += kMeterStride) {
    const uchar* row = output_.ptr<uchar>(y);
    for (int x = kMeterStride / 2; x < output_.cols; x += kMeterStride) {
      for (int c = 0; c < channels; ++c) sum += row[x * channels + c];
      count += channels;
    }
  }
  exposure_.measured_mean = count > 0 ? sum / count : 0.0;
  exposure_.exposure_time_s = exposure_time_s_;
  exposure_.gain = gain_;
  exposure_.brightness = brightness_;
  if (options_.effects) updateExposure(exposure_.measured_mean);
  const double t_end = threadCpuMs();
  timing_ = RenderTiming{t_raster - t0, t_defocus - t_raster, t_distort - t_defocus, t_end - t_distort};
  return output_;
}

bool CameraRenderer::exposureSettled() const {
  // The frame just rendered used (exposure_, gain) of its report; the next one (exposure_time_s_, gain_).
  return std::abs(exposure_.exposure_time_s - exposure_time_s_) <= kAeTolerance * exposure_time_s_ &&
         std::abs(exposure_.gain - gain_) <= kAeTolerance * gain_;
}

void CameraRenderer::updateExposure(double mean) {
  if (!effects_.ae_enabled) return;
  // `exposure` stays what it was without auto-exposure: a brightness multiplier (here: of the target).
  const double target = std::clamp(effects_.ae_target_mean * effects_.exposure, 1.0, 254.0);
  const double wanted = brightness_ * std::pow(target / std::max(mean, 0.5), kAeStep);
  // Longer exposure first (no noise cost), then analog gain (noise scales with it), as webcams do.
  const double nominal = effects_.exposure_time_s;
  exposure_time_s_ = std::clamp(wanted * nominal, effects_.ae_min_exposure_s, effects_.ae_max_exposure_s);
  gain_ = std::clamp(wanted * nominal / exposure_time_s_, 1.0, effects_.ae_max_gain);
  brightness_ = exposure_time_s_ / nominal * gain_;
}

double CameraRenderer::projectedMotionPx(const Scene& scene, const ExposureMotion& motion, double exposure_s) const {
  const double half = 0.5 * exposure_s;
  const Eigen::Isometry3d cam_a = motion.world_T_camera(-half).inverse();
  const Eigen::Isometry3d cam_b = motion.world_T_camera(half).inverse();
  const Eigen::Isometry3d target_now_inv = motion.world_T_target_robot(0.0).inverse();
  // Where a point on the target (world, now) is at the exposure's start and end.
  const Eigen::Isometry3d move_a = motion.world_T_target_robot(-half) * target_now_inv;
  const Eigen::Isometry3d move_b = motion.world_T_target_robot(half) * target_now_inv;
  const cv::Matx33d& K = calibration_.K;
  const double w = output_.cols, h = output_.rows;
  double worst = 0.0;
  auto measure = [&](const Eigen::Vector3d& pa, const Eigen::Vector3d& pb) {
    const Eigen::Vector3d ca = cam_a * pa, cb = cam_b * pb;
    if (ca.z() < kNearPlaneM || cb.z() < kNearPlaneM) return;
    const Eigen::Vector2d qa(K(0, 0) * ca.x() / ca.z() + K(0, 2), K(1, 1) * ca.y() / ca.z() + K(1, 2));
    const Eigen::Vector2d qb(K(0, 0) * cb.x() / cb.z() + K(0, 2), K(1, 1) * cb.y() / cb.z() + K(1, 2));
    auto inside = [&](const Eigen::Vector2d& q) { return q.x() >= 0 && q.y() >= 0 && q.x() < w && q.y() < h; };
    if (!inside(qa) && !inside(qb)) return;
    worst = std::max(worst, (qa - qb).norm());
  };
  for (const Surface& s : scene.surfaces()) {
    if (!s.moves_with_target) continue;
    for (const auto& st : s.outline) {
      const Eigen::Vector3d p = s.origin + st.x() * s.edge_u + st.y() * s.edge_v;
      measure(move_a * p, move_b * p);
    }
  }
  // The static scene through the last depth buffer (a coarse grid; the first frame: rays at 2 m).
  const Eigen::Isometry3d world_T_camera_now = motion.world_T_camera(0.0);
  const double fx = ideal_K_(0, 0), fy = ideal_K_(1, 1), cx = ideal_K_(0, 2), cy = ideal_K_(1, 2);
  constexpr int kGrid = 8;
  for (int gy = 0; gy <= kGrid; ++gy) {
    for (int gx = 0; gx <= kGrid; ++gx) {
      const int x = pad_.x + (output_.cols - 1) * gx / kGrid, y = pad_.y + (output_.rows - 1) * gy / kGrid;
      const float inv_z = depth_.empty() ? 0.0f : depth_.at<float>(y, x);
      const double z = inv_z > 0.0f ? 1.0 / inv_z : 2.0;
      const Eigen::Vector3d p = world_T_camera_now * Eigen::Vector3d((x - cx) / fx * z, (y - cy) / fy * z, z);
      measure(p, p);
    }
  }
  return worst;
}

void CameraRenderer::applyDefocus() {
  uniform_defocus_variance_ = 0.0;
  if (!(effects_.f_number > 0.0)) return;
  // sigma = d / 4 with d = A f s / (s - f) |1/s - 1/z| / pitch: affine in the z-buffer's 1/z.
  const double inv_s = 1.0 / effects_.focus_distance_m;
  // A point at infinity has |1/s - 1/z| = 1/s: the factor from the one thin-lens formula (configs.cpp).
  const double scale = defocusSigmaPx(effects_, 1e15) * effects_.focus_distance_m;
  double min_sigma, max_sigma;
  defocusSigmaRange(inv_s, scale, &min_sigma, &max_sigma);
  const double residual2 = effects_.blur_sigma_px * effects_.blur_sigma_px;
  if (std::sqrt(residual2 + max_sigma * max_sigma) - std::sqrt(residual2 + min_sigma * min_sigma) <
      kUniformDefocusSpreadPx) {
    uniform_defocus_variance_ = 0.5 * (min_sigma * min_sigma + max_sigma * max_sigma);
    return;
  }
  int top = 1;
  while (top < kDefocusLevels - 1 && kDefocusSigmas[top] < max_sigma) ++top;
  const DefocusLut lut(top, static_cast<float>(inv_s), static_cast<float>(scale * kDefocusLutPerPx));
  blurUsedDefocusLevels(lut, top);
  blendDefocusLevels(lut, top);
  std::swap(ideal_, defocus_out_);
}

void CameraRenderer::defocusSigmaRange(double inv_s, double scale, double* min_sigma, double* max_sigma) const {
  double min_inv_z, max_inv_z;
  cv::minMaxLoc(depth_, &min_inv_z, &max_inv_z);
  *max_sigma = std::min(kDefocusSigmas[kDefocusLevels - 1],
                        scale * std::max(std::abs(inv_s - min_inv_z), std::abs(inv_s - max_inv_z)));
  *min_sigma = scale * (inv_s >= min_inv_z && inv_s <= max_inv_z
                            ? 0.0
                            : std::min(std::abs(inv_s - min_inv_z), std::abs(inv_s - max_inv_z)));
}

void CameraRenderer::blurUsedDefocusLevels(const DefocusLut& lut, int top) {
  // Blur only the levels some pixel blends (a pass over the z-buffer, ~0.3 ms).
  bool used[kDefocusLevels] = {};
  for (int y = 0; y < depth_.rows; ++y) {
    const float* depth = depth_.ptr<float>(y);
    for (int x = 0; x < depth_.cols; ++x) {
      const int level = lut.level[lut.index(depth[x])];
      used[level] = true;
      used[level + 1] = true;
    }
  }
  defocus_levels_.resize(kDefocusLevels);
  for (int k = 1; k <= top; ++k) {
    if (!used[k]) {
      defocus_levels_[static_cast<std::size_t>(k)] = ideal_;  // no pixel blends it (only its row pointer is taken)
      continue;
    }
    const double sigma = kDefocusSigmas[k];
    const int half = std::max(1, static_cast<int>(std::ceil(3.0 * sigma)));
    cv::GaussianBlur(ideal_, defocus_levels_[static_cast<std::size_t>(k)], cv::Size(2 * half + 1, 2 * half + 1),
                     sigma, sigma, cv::BORDER_REPLICATE);
  }
}

void CameraRenderer::blendDefocusLevels(const DefocusLut& lut, int top) {
  defocus_out_.create(ideal_.size(), ideal_.type());
  const int channels = ideal_.channels();
  const uchar* level_rows[kDefocusLevels];
  for (int y = 0; y < ideal_.rows; ++y) {
    const float* depth = depth_.ptr<float>(y);
    level_rows[0] = ideal_.ptr<uchar>(y);
    for (int k = 1; k <= top; ++k) level_rows[k] = defocus_levels_[static_cast<std::size_t>(k)].ptr<uchar>(y);
    uchar* out = defocus_out_.ptr<uchar>(y);
    for (int x = 0; x < ideal_.cols; ++x) {
      const std::size_t i = lut.index(depth[x]);
      const int k = lut.level[i];
      const int w = lut.weight[i];
      const uchar* a = level_rows[k] + x * channels;
      const uchar* b = level_rows[k + 1] + x * channels;
      if (channels == 4) {
        // One pixel's four bytes at once.
        uint32_t pa, pb;
        std::memcpy(&pa, a, 4);
        std::memcpy(&pb, b, 4);
        const uint32_t merged = lerpPacked(pa, pb, static_cast<uint32_t>(w), true);
        std::memcpy(out + x * 4, &merged, 4);
      } else {
        out[x] = static_cast<uchar>((a[0] * (256 - w) + b[0] * w + 128) >> 8);
      }
    }
  }
}

void CameraRenderer::applyDistortion() {
  // The margin keeps every 2x2 neighbourhood inside ideal_: no bounds checks per pixel.
  distorted_.create(output_.size(), output_.type());
  if (ideal_.channels() == 4) {
    detail::bilinearBgrx(ideal_, remap_offset_.data(), remap_weights_.data(), distorted_);
  } else {
    detail::bilinearGray(ideal_, remap_offset_.data(), remap_weights_.data(), distorted_);
  }
}

void CameraRenderer::applyEffects() {
  cv::Mat* src = &distorted_;
  double lens_sigma_px = 0.0;
  // The residual blur, with a frame-wide uniform defocus folded in (applyDefocus).
  const double sigma = std::sqrt(effects_.blur_sigma_px * effects_.blur_sigma_px + uniform_defocus_variance_);
  if (sigma > 0.05) {
    // Kernel +-3 sigma, at least 3x3 (OpenCV's fixed-point path for small 8-bit kernels).
    const int half = std::max(1, static_cast<int>(std::ceil(3.0 * sigma)) - 1);
    cv::GaussianBlur(distorted_, blurred_, cv::Size(2 * half + 1, 2 * half + 1), sigma);
    src = &blurred_;
    lens_sigma_px = effects_.blur_sigma_px;  // the LED spots carry their own defocus (projectLeds)
  }
  if (!glare_.empty()) {
    cv::add(*src, glare_, blurred_);  // saturating
    src = &blurred_;
  }
  // Vignetting and noise in one branch-free pass over the bytes (the compiler vectorises it).
  const int row_bytes = output_.cols * output_.channels();
  const std::size_t frame_bytes = static_cast<std::size_t>(row_bytes) * output_.rows;
  std::uniform_int_distribution<std::size_t> offset_dist(0, noise_table_.size() - frame_bytes);
  const int8_t* noise = noise_table_.data() + offset_dist(rng_);
  const int noise_scale = static_cast<int>(std::lround(256.0 * noise_sigma_ * gain_ / kNoiseTableSigma));
  const uint16_t* vig = vignette_.data();
  for (int y = 0; y < output_.rows; ++y) {
    const uchar* in = src->ptr<uchar>(y);
    uchar* out = output_.ptr<uchar>(y);
    const std::size_t base = static_cast<std::size_t>(y) * row_bytes;
    for (int i = 0; i < row_bytes; ++i) {
      const int value = ((in[i] * vig[base + i]) >> 8) + ((noise[base + i] * noise_scale + 128) >> 8);
      out[i] = static_cast<uchar>(std::min(255, std::max(0, value)));
    }
  }
  // The LEDs last: their spots carry the lens blur, vignetting darkens them before the sensor clips
  // (it is optical), and noise is additive (the same before or after, except where they saturate:
  // a saturated pixel shows none, as on a real sensor).
  addLedSpots(output_, lens_sigma_px, vignette_.data());
}

namespace {

/// The plumb_bob model (D = k1 k2 p1 p2 k3): normalised pinhole coordinates -> distorted
/// normalised coordinates, as cv::projectPoints computes them.
Eigen::Vector2d distortNormalised(const std::vector<double>& D, const Eigen::Vector2d& p) {
  const double x = p.x(), y = p.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (D[0] + r2 * (D[1] + r2 * D[4]));
  return {x * radial + 2.0 * D[2] * x * y + D[3] * (r2 + 2.0 * x * x),
          y * radial + D[2] * (r2 + 2.0 * y * y) + 2.0 * D[3] * x * y};
}

}  // namespace

void CameraRenderer::projectLeds(const Scene& scene, const Eigen::Isometry3d& camera_T_world, double weight) {
  const double fx = ideal_K_(0, 0), fy = ideal_K_(1, 1), cx = ideal_K_(0, 2), cy = ideal_K_(1, 2);
  // The same depth tie as a decal's: the LED lies in the plane of the face under it.
  constexpr float kDepthBias = 1.0f + 1e-4f;
  for (const Led& led : scene.leds()) {
    if (led.radiance_ir <= 0.0) continue;
    const Eigen::Vector3d c = camera_T_world * led.centre;
    if (c.z() < kNearPlaneM) continue;
    const Eigen::Vector3d n = camera_T_world.linear() * led.normal;
    const double n_dot_c = n.dot(c);
    if (n_dot_c >= 0.0) continue;  // seen from behind or edge-on
    // Visible when its centre is: the depth of the LED's plane at the centre pixel of the ideal
    // image (exactly what the face under it wrote there) against the z-buffer.
    const double px = fx * c.x() / c.z() + cx, py = fy * c.y() / c.z() + cy;
    const long xi = std::lround(px), yi = std::lround(py);
    if (xi < 0 || yi < 0 || xi >= ideal_.cols || yi >= ideal_.rows) continue;
    const Eigen::Vector3d ray((static_cast<double>(xi) - cx) / fx, (static_cast<double>(yi) - cy) / fy, 1.0);
    const double inv_z = n.dot(ray) / n_dot_c > 0.0 ? n.dot(ray) / n_dot_c : 1.0 / c.z();
    if (static_cast<float>(inv_z) * kDepthBias <= depth_.at<float>(static_cast<int>(yi), static_cast<int>(xi))) {
      continue;  // behind something
    }
    // The disc's projected area: two in-plane unit vectors through d(x/z, y/z)/dP, then through the
    // distortion's Jacobian (finite differences; it changes little over a pixel) and the focal lengths.
    const Eigen::Vector3d e1 = n.cross(std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY())
                                   .normalized();
    const Eigen::Vector3d e2 = n.cross(e1);
    Eigen::Matrix<double, 2, 3> pinhole_jacobian;
    pinhole_jacobian << 1.0, 0.0, -c.x() / c.z(), 0.0, 1.0, -c.y() / c.z();
    pinhole_jacobian /= c.z();
    Eigen::Matrix2d in_plane;
    in_plane.col(0) = pinhole_jacobian * e1;
    in_plane.col(1) = pinhole_jacobian * e2;
    const Eigen::Vector2d normalised(c.x() / c.z(), c.y() / c.z());
    Eigen::Vector2d centre = normalised;
    Eigen::Matrix2d lens_jacobian = Eigen::Matrix2d::Identity();
    if (options_.distortion) {
      constexpr double kStep = 1e-5;
      centre = distortNormalised(calibration_.D, normalised);
      lens_jacobian.col(0) = (distortNormalised(calibration_.D, normalised + Eigen::Vector2d(kStep, 0)) - centre) / kStep;
      lens_jacobian.col(1) = (distortNormalised(calibration_.D, normalised + Eigen::Vector2d(0, kStep)) - centre) / kStep;
    }
    const cv::Matx33d& K = calibration_.K;
    const double area_px = M_PI * led.radius_m * led.radius_m * K(0, 0) * K(1, 1) *
                           std::abs((lens_jacobian * in_plane).determinant());
    LedSpot spot;
    spot.x = K(0, 0) * centre.x() + K(0, 1) * centre.y() + K(0, 2);
    spot.y = K(1, 1) * centre.y() + K(1, 2);
    // A uniform disc of radius r: r^2 / 4 per axis; defocus spreads it by its own circle of confusion.
    const double defocus = options_.effects ? defocusSigmaPx(effects_, c.z()) : 0.0;
    spot.disc_variance = area_px / (4.0 * M_PI) + defocus * defocus;
    spot.integral = 255.0 * led.radiance_ir * area_px * brightness_ * weight;
    led_spots_.push_back(spot);
  }
}

void CameraRenderer::addLedSpots(cv::Mat& image, double lens_sigma_px, const uint16_t* vignette) {
  // A pixel integrates over its square: variance 1/12 per axis (keeps a tiny spot from falling
  // between pixel centres).
  constexpr double kPixelVariance = 1.0 / 12.0;
  for (const LedSpot& spot : led_spots_) {
    const double variance = lens_sigma_px * lens_sigma_px + spot.disc_variance + kPixelVariance;
    const double peak = spot.integral / (2.0 * M_PI * variance);
    if (peak < 0.5) continue;
    // Out to where the spot adds less than half a grey level.
    const double reach = std::sqrt(2.0 * variance * std::log(2.0 * peak));
    const int x0 = std::max(0, static_cast<int>(std::ceil(spot.x - reach)));
    const int x1 = std::min(image.cols - 1, static_cast<int>(std::floor(spot.x + reach)));
    const int y0 = std::max(0, static_cast<int>(std::ceil(spot.y - reach)));
    const int y1 = std::min(image.rows - 1, static_cast<int>(std::floor(spot.y + reach)));
    if (x0 > x1 || y0 > y1) continue;
    // Separable: exp(-(dx^2 + dy^2) / 2v) = exp(-dx^2 / 2v) exp(-dy^2 / 2v), the peak folded into the rows.
    spot_row_.resize(static_cast<std::size_t>(x1 - x0 + 1));
    spot_col_.resize(static_cast<std::size_t>(y1 - y0 + 1));
    for (int x = x0; x <= x1; ++x) {
      const double dx = x - spot.x;
      spot_row_[static_cast<std::size_t>(x - x0)] = static_cast<float>(peak * std::exp(-dx * dx / (2.0 * variance)));
    }
    for (int y = y0; y <= y1; ++y) {
      const double dy = y - spot.y;
      spot_col_[static_cast<std::size_t>(y - y0)] = static_cast<float>(std::exp(-dy * dy / (2.0 * variance)));
    }
    for (int y = y0; y <= y1; ++y) {
      uchar* row = image.ptr<uchar>(y);
      const float weight = spot_col_[static_cast<std::size_t>(y - y0)];
      const uint16_t* vignette_row = vignette ? vignette + static_cast<std::size_t>(y) * image.cols : nullptr;
      for (int x = x0; x <= x1; ++x) {
        float added = weight * spot_row_[static_cast<std::size_t>(x - x0)];
        if (vignette_row) added *= static_cast<float>(vignette_row[x]) * (1.0f / 256.0f);
        row[x] = static_cast<uchar>(std::min(255.0f, row[x] + added + 0.5f));
      }
    }
  }
}

template <int kChannels>
void CameraRenderer::rasterize(const Scene& scene, const Eigen::Isometry3d& camera_T_world) {
  // Front to back (by centre distance): hidden pixels then fail the depth test before any texel is
  // fetched. The z-buffer still decides; the order only saves work.
  const auto& surfaces = scene.surfaces();
  const Eigen::Vector3d eye = camera_T_world.inverse().translation();
  order_.clear();
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    const Surface& s = surfaces[i];
    const Eigen::Vector3d centre = s.origin + 0.5 * (s.edge_u + s.edge_v);
    order_.emplace_back((centre - eye).squaredNorm(), i);
  }
  std::sort(order_.begin(), order_.end());
  const unsigned band_bit = band_ == Band::kVisible ? kVisibleBand : kInfraredBand;
  for (const auto& entry : order_) {
    const Surface& surface = surfaces[entry.second];
    if ((surface.bands & band_bit) && !surface.decal) drawSurface<kChannels>(surface, camera_T_world);
  }
  // Decals last, blended over the finished opaque image, in the scene's order (halo, then LED).
  for (const Surface& surface : surfaces) {
    if ((surface.bands & band_bit) && surface.decal) drawDecal<kChannels>(surface, camera_T_world);
  }
}

bool CameraRenderer::projectOutline(const Surface& surface, const Eigen::Isometry3d& camera_T_world,
                                    Eigen::Matrix3d* H) {
  const Eigen::Matrix3d R = camera_T_world.linear();
  const Eigen::Vector3d O = camera_T_world * surface.origin;
  const Eigen::Vector3d U = R * surface.edge_u;
  const Eigen::Vector3d V = R * surface.edge_v;

  // The outline in camera coordinates, clipped to z >= near (Sutherland-Hodgman against one plane).
  clip_a_.clear();
  for (const auto& st : surface.outline) clip_a_.push_back(O + st.x() * U + st.y() * V);
  clip_b_.clear();
  for (std::size_t i = 0; i < clip_a_.size(); ++i) {
    const Eigen::Vector3d& a = clip_a_[i];
    const Eigen::Vector3d& b = clip_a_[(i + 1) % clip_a_.size()];
    const bool a_in = a.z() >= kNearPlaneM, b_in = b.z() >= kNearPlaneM;
    if (a_in) clip_b_.push_back(a);
    if (a_in != b_in) {
      const double t = (kNearPlaneM - a.z()) / (b.z() - a.z());
      clip_b_.push_back(a + t * (b - a));
    }
  }
  if (clip_b_.size() < 3) return false;

  // Pixel centres at integer coordinates of ideal_ (OpenCV's convention, shifted by the margin).
  const double fx = ideal_K_(0, 0), fy = ideal_K_(1, 1), cx = ideal_K_(0, 2), cy = ideal_K_(1, 2);
  const int width = ideal_.cols, height = ideal_.rows;
  projected_.clear();
  double min_x = 1e300, max_x = -1e300, min_y = 1e300, max_y = -1e300;
  for (const auto& p : clip_b_) {
    const Eigen::Vector2d q(fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy);
    projected_.push_back(q);
    min_x = std::min(min_x, q.x());
    max_x = std::max(max_x, q.x());
    min_y = std::min(min_y, q.y());
    max_y = std::max(max_y, q.y());
  }
  // (One pixel of slack: an anti-aliased decal touches pixels up to half a pixel outside.)
  if (max_x < -1 || min_x > width || max_y < -1 || min_y > height) return false;

  // Pixel -> surface coordinates: (s, t, 1) ~ H (x, y, 1) with H = (K [U V O])^-1; the third row of
  // H gives 1/z directly, affine in the pixel (the z-buffer value).
  Eigen::Matrix3d K;
  K << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  Eigen::Matrix3d M;
  M.col(0) = U;
  M.col(1) = V;
  M.col(2) = O;
  const Eigen::Matrix3d G = K * M;
  if (std::abs(G.determinant()) < 1e-12) return false;  // seen exactly edge-on
  *H = G.inverse();
  return true;
}

template <int kChannels>
uint32_t CameraRenderer::flatColour(const Surface& surface, int gain_fixed) const {
  // One packed b, g, r, 0 pixel (visible) or one grey byte (IR).
  uint32_t flat = 0;
  if (kChannels == 4) {
    for (int c = 0; c < 3; ++c) {
      flat |= static_cast<uint32_t>(cv::saturate_cast<uchar>((surface.color[c] * gain_fixed) >> 8)) << (8 * c);
    }
  } else {
    const double luma = 0.114 * surface.color[0] + 0.587 * surface.color[1] + 0.299 * surface.color[2];
    flat = cv::saturate_cast<uchar>(luma * gain_fixed / 256.0);
  }
  return flat;
}

namespace {

/// Area of the convex polygon `poly` inside the unit pixel square centred at (x, y): the polygon
/// clipped against the square's four sides (Sutherland-Hodgman), then the shoelace formula.
double pixelCoverage(const std::vector<Eigen::Vector2d>& poly, double x, double y, std::vector<Eigen::Vector2d>& a,
                     std::vector<Eigen::Vector2d>& b) {
  a = poly;
  // The sides as (axis, sign, limit): a point p is inside when sign * (p[axis] - limit) <= 0.
  const int axes[4] = {0, 0, 1, 1};
  const double signs[4] = {-1, 1, -1, 1};
  const double limits[4] = {x - 0.5, x + 0.5, y - 0.5, y + 0.5};
  for (int side = 0; side < 4 && a.size() >= 3; ++side) {
    const int k = axes[side];
    const double sg = signs[side], lim = limits[side];
    b.clear();
    for (std::size_t i = 0; i < a.size(); ++i) {
      const Eigen::Vector2d& p = a[i];
      const Eigen::Vector2d& q = a[(i + 1) % a.size()];
      const double dp = sg * (p[k] - lim), dq = sg * (q[k] - lim);
      if (dp <= 0) b.push_back(p);
      if ((dp <= 0) != (dq <= 0)) b.push_back(p + (dp / (dp - dq)) * (q - p));
    }
    std::swap(a, b);
  }
  if (a.size() < 3) return 0.0;
  double twice_area = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Eigen::Vector2d& p = a[i];
    const Eigen::Vector2d& q = a[(i + 1) % a.size()];
    twice_area += p.x() * q.y() - q.x() * p.y();
  }
  return std::min(1.0, 0.5 * std::abs(twice_area));
}

}  // namespace

namespace {

/// pixel + cover * (colour - pixel), rounded to nearest, per colour channel (weight: cover of 256).
template <int kChannels>
inline void blendTowards(uchar* pixel, uint32_t colour, int weight) {
  for (int c = 0; c < (kChannels == 4 ? 3 : 1); ++c) {
    uchar& px = pixel[c];
    const int diff = static_cast<int>((colour >> (8 * c)) & 0xffu) - px;
    const int step = diff >= 0 ? (diff * weight + 128) >> 8 : -((-diff * weight + 128) >> 8);
    px = static_cast<uchar>(px + step);
  }
}

}  // namespace

template <int kChannels>
void CameraRenderer::drawDecal(const Surface& surface, const Eigen::Isometry3d& camera_T_world) {
  Eigen::Matrix3d H;
  if (!projectOutline(surface, camera_T_world, &H)) return;
  PixelRange pixels;
  if (!decalEdges(&pixels)) return;

  const double gain = (band_ == Band::kVisible ? surface.gain_visible : surface.gain_ir) * brightness_;
  const int gain_fixed = static_cast<int>(std::lround(std::max(0.0, gain) * 256.0));
  const uint32_t flat = flatColour<kChannels>(surface, gain_fixed);
  // A pixel square lies wholly inside an edge's half-plane when its centre is more than half the
  // diagonal inside, wholly outside when more than that outside.
  constexpr double kHalfDiagonal = 0.70710678118654752 + 1e-9;
  // The depth tie with the surface the decal lies on: 1e-4 relative (0.1 mm at 1 m) is far above
  // float rounding and far below any real gap between surfaces.
  constexpr float kDepthBias = 1.0f + 1e-4f;
  for (int y = pixels.y_begin; y <= pixels.y_end; ++y) {
    const float* depth = depth_.ptr<float>(y);
    uchar* row = ideal_.ptr<uchar>(y);
    for (int x = pixels.x_begin; x <= pixels.x_end; ++x) {
      double outside = -1e300;
      for (const auto& e : edges_) outside = std::max(outside, e.x() * x + e.y() * y - e.z());
      if (outside >= kHalfDiagonal) continue;
      const double inv_z = H(2, 0) * x + H(2, 1) * y + H(2, 2);
      if (static_cast<float>(inv_z) * kDepthBias <= depth[x]) continue;  // behind something
      const double cover = outside <= -kHalfDiagonal ? 1.0 : pixelCoverage(projected_, x, y, cover_a_, cover_b_);
      if (cover <= 0.0) continue;
      blendTowards<kChannels>(row + x * kChannels, flat, static_cast<int>(std::lround(cover * 256.0)));
    }
  }
}

bool CameraRenderer::decalEdges(PixelRange* pixels) {
  const std::size_t n = projected_.size();
  double twice_area = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& p = projected_[i];
    const Eigen::Vector2d& q = projected_[(i + 1) % n];
    twice_area += p.x() * q.y() - q.x() * p.y();
  }
  if (std::abs(twice_area) < 1e-12) return false;
  const double orientation = twice_area > 0 ? 1.0 : -1.0;
  // Per edge of the projected (convex) outline: outward unit normal and offset, (nx, ny, c); the
  // signed distance of a pixel centre p outside the edge's line is nx * p.x + ny * p.y - c.
  edges_.clear();
  double min_x = 1e300, max_x = -1e300, min_y = 1e300, max_y = -1e300;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& p = projected_[i];
    const Eigen::Vector2d d = projected_[(i + 1) % n] - p;
    min_x = std::min(min_x, p.x());
    max_x = std::max(max_x, p.x());
    min_y = std::min(min_y, p.y());
    max_y = std::max(max_y, p.y());
    const double len = d.norm();
    if (len < 1e-12) continue;
    const Eigen::Vector2d normal = orientation * Eigen::Vector2d(d.y(), -d.x()) / len;
    edges_.emplace_back(normal.x(), normal.y(), normal.dot(p));
  }
  // Every pixel whose square the outline touches.
  pixels->x_begin = std::max(0, static_cast<int>(std::floor(min_x + 0.5)));
  pixels->x_end = std::min(ideal_.cols - 1, static_cast<int>(std::ceil(max_x - 0.5)));
  pixels->y_begin = std::max(0, static_cast<int>(std::floor(min_y + 0.5)));
  pixels->y_end = std::min(ideal_.rows - 1, static_cast<int>(std::ceil(max_y - 0.5)));
  return true;
}

template <int kChannels>
void CameraRenderer::drawSurface(const Surface& surface, const Eigen::Isometry3d& camera_T_world) {
  Eigen::Matrix3d H;
  if (!projectOutline(surface, camera_T_world, &H)) return;
  double min_y = 1e300, max_y = -1e300;
  for (const auto& q : projected_) {
    min_y = std::min(min_y, q.y());
    max_y = std::max(max_y, q.y());
  }
  const double gain = (band_ == Band::kVisible ? surface.gain_visible : surface.gain_ir) * brightness_;
  const int gain_fixed = static_cast<int>(std::lround(std::max(0.0, gain) * 256.0));
  const uint32_t flat = flatColour<kChannels>(surface, gain_fixed);
  const int y_begin = std::max(0, static_cast<int>(std::ceil(min_y)));
  const int y_end = std::min(ideal_.rows - 1, static_cast<int>(std::floor(max_y)));
  for (int y = y_begin; y <= y_end; ++y) {
    int x0, x1;
    if (!projectedSpan(y, &x0, &x1)) continue;
    if (surface.texture) {
      shadeTexturedSpan<kChannels>(surface, H, y, x0, x1, static_cast<uint32_t>(gain_fixed));
    } else {
      fillFlatSpan<kChannels>(H, y, x0, x1, flat);
    }
  }
}

// Always inlined (renderer.h): a call per row and surface costs ~5 % of the rasterising.
__attribute__((always_inline)) inline bool CameraRenderer::projectedSpan(int y, int* x0, int* x1) const {
  // Span of a convex polygon on this row (pixel centres at integer coordinates).
  double xl = 1e300, xr = -1e300;
  const std::size_t n = projected_.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& a = projected_[i];
    const Eigen::Vector2d& b = projected_[(i + 1) % n];
    if ((a.y() <= y && b.y() > y) || (b.y() <= y && a.y() > y)) {
      const double x = a.x() + (y - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      xl = std::min(xl, x);
      xr = std::max(xr, x);
    }
  }
  if (xl > xr) return false;
  *x0 = std::max(0, static_cast<int>(std::ceil(xl)));
  *x1 = std::min(ideal_.cols - 1, static_cast<int>(std::ceil(xr)) - 1);
  return *x0 <= *x1;
}

template <int kChannels>
__attribute__((always_inline)) inline void CameraRenderer::fillFlatSpan(const Eigen::Matrix3d& H, int y, int x0,
                                                                         int x1, uint32_t flat) {
  double nw = H(2, 0) * x0 + H(2, 1) * y + H(2, 2);
  float* depth = depth_.ptr<float>(y);
  uchar* row = ideal_.ptr<uchar>(y);
  // CV_8UC4 rows are 4-byte aligned (cv::Mat allocates aligned; the step is a multiple of 4).
  uint32_t* row4 = reinterpret_cast<uint32_t*>(row);
  for (int x = x0; x <= x1; ++x, nw += H(2, 0)) {
    const float inv_z = static_cast<float>(nw);
    if (inv_z <= depth[x]) continue;
    depth[x] = inv_z;
    if (kChannels == 4) {
      row4[x] = flat;
    } else {
      row[x] = static_cast<uchar>(flat);
    }
  }
}

namespace {

/// The texture level for a span: the texel footprint of one pixel at (xm, y). Level whose texel best
/// matches the pixel footprint f (rounded: a little softer, far less aliasing): round(log2 f), i.e.
/// level L for f in [2^(L-1/2), 2^(L+1/2)), found on f^2 against 2^(2L+1) without a log or a square root.
const BlockedLevel& spanTextureLevel(const std::vector<BlockedLevel>& levels, const Eigen::Matrix3d& H, double su,
                                     double sv, double xm, int y) {
  const BlockedLevel& base = levels[0];
  auto uv_at = [&](double px, double py) {
    const double inv_w = 1.0 / (H(2, 0) * px + H(2, 1) * py + H(2, 2));  // one division, not two
    return Eigen::Vector2d((H(0, 0) * px + H(0, 1) * py + H(0, 2)) * inv_w * su * base.width,
                           (H(1, 0) * px + H(1, 1) * py + H(1, 2)) * inv_w * sv * base.height);
  };
  const Eigen::Vector2d c0 = uv_at(xm, y);
  const double footprint2 = std::max((uv_at(xm + 1, y) - c0).squaredNorm(), (uv_at(xm, y + 1) - c0).squaredNorm());
  const int max_level = static_cast<int>(levels.size()) - 1;
  int level = 0;
  for (double limit = 2.0; level < max_level && footprint2 >= limit; limit *= 4.0) ++level;
  return levels[static_cast<std::size_t>(level)];
}

}  // namespace

template <int kChannels>
__attribute__((always_inline)) inline void CameraRenderer::shadeTexturedSpan(const Surface& surface,
                                                                              const Eigen::Matrix3d& H, int y, int x0,
                                                                              int x1, uint32_t gain_u) {
  const Texture* tex = surface.texture.get();
  const double su = surface.repeat_u, sv = surface.repeat_v;
  const BlockedLevel& img = spanTextureLevel(tex->blocked, H, su, sv, 0.5 * (x0 + x1), y);
  const int tw = img.width, th = img.height;
  const double scale_u = su * tw, scale_v = sv * th;
  const double off_u = surface.offset_u * tw, off_v = surface.offset_v * th;

  // Perspective-correct coordinates exactly at the ends of 16-pixel segments, linear in between
  // (the error is far below a texel at these sizes and saves a division per pixel).
  const bool repeat = tex->repeat;
  const bool saturates = gain_u > 256;
  const double bias_u = repeat ? off_u + 4096.0 * tw : off_u;  // keeps the cast positive when wrapping
  const double bias_v = repeat ? off_v + 4096.0 * th : off_v;
  auto texel_at = [&](int px, double* u, double* v) {
    const double inv_w = 1.0 / (H(2, 0) * px + H(2, 1) * y + H(2, 2));
    *u = (H(0, 0) * px + H(0, 1) * y + H(0, 2)) * inv_w * scale_u + bias_u;
    *v = (H(1, 0) * px + H(1, 1) * y + H(1, 2)) * inv_w * scale_v + bias_v;
  };
  double nw = H(2, 0) * x0 + H(2, 1) * y + H(2, 2);
  float* depth = depth_.ptr<float>(y);
  uchar* row = ideal_.ptr<uchar>(y);
  constexpr int kSegment = 16;
  double u_start, v_start;
  texel_at(x0, &u_start, &v_start);
  for (int xs = x0; xs <= x1; xs += kSegment) {
    const int xe = std::min(xs + kSegment, x1 + 1);
    double u_end = u_start, v_end = v_start;
    if (xe - 1 > xs) texel_at(xe - 1, &u_end, &v_end);
    // Fixed point inside the segment: integer steps instead of a double add and two double->int
    // conversions per pixel (1/65536 texel is far below the texel size).
    // The steps come from the double difference (a 64-bit integer division costs more than the
    // whole segment's pixels).
    int64_t u = toFixed(u_start), v = toFixed(v_start);
    const double steps = xe - 1 > xs ? 1.0 / (xe - 1 - xs) : 0.0;
    const int64_t du = toFixed((u_end - u_start) * steps), dv = toFixed((v_end - v_start) * steps);
    nw = shadeSegment<kChannels>(surface.bilinear, repeat, saturates, xe - xs, nw, H(2, 0), u, du, v, dv, depth + xs,
                                 row + static_cast<std::size_t>(xs) * kChannels, img, gain_u);
    if (xe <= x1) texel_at(xe, &u_start, &v_start);
  }
}

template <int kChannels>
void CameraRenderer::addSpecular(const Scene& scene, const Surface& surface, const Eigen::Isometry3d& camera_T_world) {
  Eigen::Matrix3d H;
  if (!projectOutline(surface, camera_T_world, &H)) return;
  // Normal towards the camera (at the origin), and the direction towards the light, camera frame.
  Eigen::Vector3d normal = (camera_T_world.linear() * surface.edge_u.cross(surface.edge_v)).normalized();
  if (normal.dot(camera_T_world * surface.origin) > 0.0) normal = -normal;
  const Eigen::Vector3d to_light = -(camera_T_world.linear() * scene.lightDirection()).normalized();
  if (normal.dot(to_light) <= 0.0) return;  // the light is behind the surface
  const BandLighting& light = band_ == Band::kVisible ? lighting_.visible : lighting_.ir;
  const double peak = 255.0 * effects_.specular_strength * light.illumination * effects_.exposure * brightness_;
  if (peak < 0.5) return;
  // Below this n.h the lobe adds less than half a grey level.
  const double cos_min = std::pow(0.5 / peak, 1.0 / effects_.specular_shininess);
  double min_x = 1e300, max_x = -1e300, min_y = 1e300, max_y = -1e300;
  for (const auto& q : projected_) {
    min_x = std::min(min_x, q.x());
    max_x = std::max(max_x, q.x());
    min_y = std::min(min_y, q.y());
    max_y = std::max(max_y, q.y());
  }
  const int x0 = std::max(0, static_cast<int>(std::ceil(min_x))), x1 = std::min(ideal_.cols - 1, static_cast<int>(max_x));
  const int y0 = std::max(0, static_cast<int>(std::ceil(min_y))), y1 = std::min(ideal_.rows - 1, static_cast<int>(max_y));
  // Per pixel, with the ray r = ((x - cx) / fx, (y - cy) / fy, 1), |r| = s and to_camera v = -r / s:
  // n.h = (n.v + n.l) / |v + l| and |v + l|^2 = 2 + 2 v.l. A pixel is rejected on the squares
  // (n.v + n.l)^2 <= cos_min^2 (2 + 2 v.l) without a division or a root; float throughout (the lobe adds
  // at most `peak` grey levels: float's 1e-7 moves it far less than the rounding to an integer).
  // With 16 motion-blur sub-frames and the face filling the image this loop was half the simulator's CPU.
  const float inv_fx = static_cast<float>(1.0 / ideal_K_(0, 0)), inv_fy = static_cast<float>(1.0 / ideal_K_(1, 1));
  const float cx = static_cast<float>(ideal_K_(0, 2)), cy = static_cast<float>(ideal_K_(1, 2));
  const float nx = static_cast<float>(normal.x()), ny = static_cast<float>(normal.y()), nz = static_cast<float>(normal.z());
  const float lx = static_cast<float>(to_light.x()), ly = static_cast<float>(to_light.y()), lz = static_cast<float>(to_light.z());
  const float n_dot_l = static_cast<float>(normal.dot(to_light));
  const float cos_min2 = static_cast<float>(cos_min * cos_min);
  const float peak_f = static_cast<float>(peak), shininess = static_cast<float>(effects_.specular_shininess);
  const float h20 = static_cast<float>(H(2, 0)), h21 = static_cast<float>(H(2, 1)), h22 = static_cast<float>(H(2, 2));
  for (int y = y0; y <= y1; ++y) {
    const float* depth = depth_.ptr<float>(y);
    uchar* row = ideal_.ptr<uchar>(y);
    const float b = (static_cast<float>(y) - cy) * inv_fy;
    const float row_s2 = b * b + 1.0f, row_n = ny * b + nz, row_l = ly * b + lz;
    const float row_inv_z = h21 * static_cast<float>(y) + h22;
    for (int x = x0; x <= x1; ++x) {
      // Only where this surface is what the pixel shows (the z-buffer holds its own 1/z there).
      const float inv_z = h20 * static_cast<float>(x) + row_inv_z;
      if (std::abs(depth[x] - inv_z) > 1e-4f * inv_z) continue;
      const float a = (static_cast<float>(x) - cx) * inv_fx;
      const float inv_s = 1.0f / std::sqrt(a * a + row_s2);
      const float num = n_dot_l - (nx * a + row_n) * inv_s;   // n.v + n.l
      const float den2 = 2.0f - 2.0f * (lx * a + row_l) * inv_s;  // |v + l|^2
      if (num <= 0.0f || num * num <= cos_min2 * den2) continue;
      const float n_dot_h = num / std::sqrt(den2);
      const int add = static_cast<int>(peak_f * std::exp2(shininess * std::log2(n_dot_h)) + 0.5f);
      for (int c = 0; c < (kChannels == 4 ? 3 : 1); ++c) {
        uchar& px = row[x * kChannels + c];
        px = static_cast<uchar>(std::min(255, px + add));
      }
    }
  }
}

template void CameraRenderer::rasterize<1>(const Scene&, const Eigen::Isometry3d&);
template void CameraRenderer::rasterize<4>(const Scene&, const Eigen::Isometry3d&);

}  // namespace docking_sim
