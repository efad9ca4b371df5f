// The fixed-point bilinear lookups of the lens distortion: known values (rounding half up, clamping)
// for the variant this build uses and for the portable scalar one, and on x86 the SSE2 loops against
// the scalar loops over random images, offsets and weights, byte for byte (arm64 builds run the
// scalar loops, so this is what keeps their images identical to x86's).
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "bilinear.h"

namespace {

using docking_sim::detail::bilinearBgrx;
using docking_sim::detail::bilinearBgrxScalar;
using docking_sim::detail::bilinearGray;
using docking_sim::detail::bilinearGrayScalar;

using Lookup = void (*)(const cv::Mat&, const int32_t*, const int16_t*, cv::Mat&);

/// A 2x2 neighbourhood in a 2x3 b,g,r,x image (its 3rd column must not be read); one output pixel.
cv::Vec3b bgrxOnePixel(Lookup lookup, const cv::Vec4b& tl, const cv::Vec4b& tr, const cv::Vec4b& bl,
                       const cv::Vec4b& br, int16_t w_tl, int16_t w_bl, int16_t w_tr, int16_t w_br) {
  cv::Mat src(2, 3, CV_8UC4, cv::Scalar::all(77));
  src.at<cv::Vec4b>(0, 0) = tl;
  src.at<cv::Vec4b>(0, 1) = tr;
  src.at<cv::Vec4b>(1, 0) = bl;
  src.at<cv::Vec4b>(1, 1) = br;
  const int32_t offset = 0;
  const int16_t weights[4] = {w_tl, w_bl, w_tr, w_br};
  cv::Mat dst(1, 1, CV_8UC3, cv::Scalar::all(0));
  lookup(src, &offset, weights, dst);
  return dst.at<cv::Vec3b>(0, 0);
}

/// The same for grey: one output pixel (group slot 0) from a 2x2 neighbourhood.
int grayOnePixel(Lookup lookup, uchar tl, uchar tr, uchar bl, uchar br, int16_t w_tl, int16_t w_tr, int16_t w_bl,
                 int16_t w_br) {
  cv::Mat src = (cv::Mat_<uchar>(2, 3) << tl, tr, 77, bl, br, 77);
  const int32_t offset = 0;
  int16_t weights[16] = {};
  weights[0] = w_tl;
  weights[1] = w_tr;
  weights[8] = w_bl;
  weights[9] = w_br;
  cv::Mat dst(1, 1, CV_8UC1, cv::Scalar::all(0));
  lookup(src, &offset, weights, dst);
  return dst.at<uchar>(0, 0);
}

void expectKnownValues(Lookup bgrx, Lookup gray) {
  // Equal quarters: means 25.5 (rounds up), 25.25 (down), 255, and the x channel is ignored.
  const cv::Vec3b mean = bgrxOnePixel(bgrx, {10, 10, 255, 9}, {20, 20, 255, 9}, {30, 30, 255, 9},
                                      {42, 41, 255, 9}, 4096, 4096, 4096, 4096);
  EXPECT_EQ(mean, cv::Vec3b(26, 25, 255));
  // All weight on one corner picks that pixel exactly.
  EXPECT_EQ(bgrxOnePixel(bgrx, {1, 2, 3, 0}, {4, 5, 6, 0}, {7, 8, 9, 0}, {10, 11, 12, 0}, 0, 16384, 0, 0),
            cv::Vec3b(7, 8, 9));
  // Out-of-range sums saturate (weights far above 2^14 or negative).
  EXPECT_EQ(bgrxOnePixel(bgrx, {255, 0, 100, 0}, {255, 0, 100, 0}, {255, 0, 100, 0}, {255, 0, 100, 0}, 32767,
                         32767, 32767, 32767),
            cv::Vec3b(255, 0, 255));
  EXPECT_EQ(bgrxOnePixel(bgrx, {255, 1, 100, 0}, {255, 1, 100, 0}, {255, 1, 100, 0}, {255, 1, 100, 0}, -32768,
                         -32768, 0, 0),
            cv::Vec3b(0, 0, 0));
  EXPECT_EQ(grayOnePixel(gray, 10, 20, 30, 42, 4096, 4096, 4096, 4096), 26);
  EXPECT_EQ(grayOnePixel(gray, 10, 20, 30, 41, 4096, 4096, 4096, 4096), 25);
  EXPECT_EQ(grayOnePixel(gray, 1, 2, 3, 4, 0, 16384, 0, 0), 2);
  EXPECT_EQ(grayOnePixel(gray, 200, 200, 200, 200, 32767, 32767, 0, 0), 255);
  EXPECT_EQ(grayOnePixel(gray, 200, 200, 200, 200, -32768, 0, 0, 0), 0);
}

TEST(Bilinear, ScalarKnownValues) { expectKnownValues(bilinearBgrxScalar, bilinearGrayScalar); }

TEST(Bilinear, ThisBuildsVariantKnownValues) { expectKnownValues(bilinearBgrx, bilinearGray); }

#if defined(__SSE2__)

using docking_sim::detail::bilinearBgrxSse2;
using docking_sim::detail::bilinearGraySse2;

enum class WeightKind { kRenderer, kAnyInt16 };

/// Random lookup inputs for an output of rows x cols: source image (with room for every 2x2
/// neighbourhood), offsets, and weights laid out as the given variant reads them.
struct RandomCase {
  cv::Mat src;
  std::vector<int32_t> offsets;
  std::vector<int16_t> weights;
};

RandomCase randomCase(std::mt19937& rng, int rows, int cols, bool visible, WeightKind kind) {
  RandomCase c;
  std::uniform_int_distribution<int> size(2, 40);
  c.src.create(size(rng), size(rng), visible ? CV_8UC4 : CV_8UC1);
  cv::randu(c.src, cv::Scalar::all(0), cv::Scalar::all(256));
  // Saturated areas as well: clamping must agree where the sums run past 0..255.
  if (rng() % 2 == 0) c.src.row(0).setTo(cv::Scalar::all(255));
  const std::size_t n = static_cast<std::size_t>(rows) * cols;
  std::uniform_int_distribution<int> x0(0, c.src.cols - 2), y0(0, c.src.rows - 2);
  c.offsets.resize(n);
  for (auto& o : c.offsets) o = static_cast<int32_t>(y0(rng) * c.src.step + x0(rng) * c.src.elemSize());
  c.weights.assign(16 * ((n + 3) / 4), 0);
  std::uniform_int_distribution<int> frac(0, 128), any(-32768, 32767);
  for (std::size_t i = 0; i < n; ++i) {
    int16_t tl, tr, bl, br;
    if (kind == WeightKind::kRenderer) {  // what the renderer makes: 7 bits per axis, summing to 2^14
      const int wx = frac(rng), wy = frac(rng);
      tl = static_cast<int16_t>((128 - wx) * (128 - wy));
      tr = static_cast<int16_t>(wx * (128 - wy));
      bl = static_cast<int16_t>((128 - wx) * wy);
      br = static_cast<int16_t>(wx * wy);
    } else {
      tl = static_cast<int16_t>(any(rng));
      tr = static_cast<int16_t>(any(rng));
      bl = static_cast<int16_t>(any(rng));
      br = static_cast<int16_t>(any(rng));
    }
    if (visible) {
      const int16_t w[4] = {tl, bl, tr, br};
      std::copy(w, w + 4, c.weights.begin() + 4 * i);
    } else {
      const std::size_t group = 16 * (i / 4), k = 2 * (i % 4);
      c.weights[group + k] = tl;
      c.weights[group + k + 1] = tr;
      c.weights[group + 8 + k] = bl;
      c.weights[group + 8 + k + 1] = br;
    }
  }
  return c;
}

/// Runs both variants on many random cases; the outputs start from different fillings so that a
/// byte one of them leaves unwritten also shows as a difference.
void compareOnRandomCases(bool visible, Lookup simd, Lookup scalar) {
  std::mt19937 rng(visible ? 20240611u : 20240612u);
  std::uniform_int_distribution<int> size(1, 37);  // odd sizes too: gray tails, last pixel of a row
  int cases = 0;
  for (const WeightKind kind : {WeightKind::kRenderer, WeightKind::kAnyInt16}) {
    for (int trial = 0; trial < 300; ++trial, ++cases) {
      const int rows = size(rng), cols = size(rng);
      const RandomCase c = randomCase(rng, rows, cols, visible, kind);
      const int type = visible ? CV_8UC3 : CV_8UC1;
      cv::Mat a(rows, cols, type, cv::Scalar::all(0xAA)), b(rows, cols, type, cv::Scalar::all(0x55));
      simd(c.src, c.offsets.data(), c.weights.data(), a);
      scalar(c.src, c.offsets.data(), c.weights.data(), b);
      ASSERT_TRUE(a.isContinuous() && b.isContinuous());
      const std::size_t bytes = a.total() * a.elemSize();
      const auto* pa = a.ptr<uchar>();
      const auto* pb = b.ptr<uchar>();
      for (std::size_t i = 0; i < bytes; ++i) {
        ASSERT_EQ(pa[i], pb[i]) << "byte " << i << " of a " << rows << "x" << cols << " output, trial " << trial
                                << (kind == WeightKind::kRenderer ? " (renderer weights)" : " (any int16 weights)");
      }
    }
  }
  EXPECT_EQ(cases, 600);
}

TEST(Bilinear, Sse2MatchesScalarBgrx) { compareOnRandomCases(true, bilinearBgrxSse2, bilinearBgrxScalar); }

TEST(Bilinear, Sse2MatchesScalarGray) { compareOnRandomCases(false, bilinearGraySse2, bilinearGrayScalar); }

#endif  // __SSE2__

}  // namespace
