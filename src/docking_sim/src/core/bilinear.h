// Internal to docking_sim_core (not installed): the fixed-point bilinear lookups behind the lens
// distortion. Each exists as a portable scalar loop and, on x86 with SSE2, as a SIMD loop; both give
// the same bytes (the test compares them), so arm64 and x86 render identical images.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>

namespace docking_sim {
namespace detail {

// Shared contract: `offsets` holds per output pixel the byte offset in `src` of the top-left source
// pixel; its 2x2 neighbourhood must lie inside `src`. Weights are 16-bit, meant to sum to 2^14;
// per channel the result is (sum of pixel * weight + 2^13) >> 14 clamped to 0..255 (what the SSE2
// saturating packs do). `dst` must already have its size and type.

// src CV_8UC4 (b, g, r, x), dst CV_8UC3. Weights per pixel: top-left, bottom-left, top-right, bottom-right.
void bilinearBgrxScalar(const cv::Mat& src, const int32_t* offsets, const int16_t* weights, cv::Mat& dst);
// src CV_8UC1, dst CV_8UC1 and continuous. Weights per group of four pixels (16 values): the
// (top-left, top-right) pair of each, then the (bottom-left, bottom-right) pair of each.
void bilinearGrayScalar(const cv::Mat& src, const int32_t* offsets, const int16_t* weights, cv::Mat& dst);

#if defined(__SSE2__)
void bilinearBgrxSse2(const cv::Mat& src, const int32_t* offsets, const int16_t* weights, cv::Mat& dst);
void bilinearGraySse2(const cv::Mat& src, const int32_t* offsets, const int16_t* weights, cv::Mat& dst);
#endif

// The variant this build uses: chosen at compile time (SSE2 is part of every x86-64 CPU; arm64
// builds take the scalar loops).
inline void bilinearBgrx(const cv::Mat& src, const int32_t* offsets, const int16_t* weights, cv::Mat& dst) {
#if defined(__SSE2__)
  bilinearBgrxSse2(src, offsets, weights, dst);
#else
  bilinearBgrxScalar(src, offsets, weights, dst);
#endif
}

inline void bilinearGray(const cv::Mat& src, const int32_t* offsets, const int16_t* weights, cv::Mat& dst) {
#if defined(__SSE2__)
  bilinearGraySse2(src, offsets, weights, dst);
#else
  bilinearGrayScalar(src, offsets, weights, dst);
#endif
}

}  // namespace detail
}  // namespace docking_sim
