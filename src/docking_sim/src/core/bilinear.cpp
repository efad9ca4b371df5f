#include "bilinear.h"

#if defined(__SSE2__)
#include <emmintrin.h>  // SSE2: part of every x86-64 CPU
#endif

#include <cstddef>
#include <cstring>

namespace docking_sim {
namespace detail {
namespace {

/// (sum + 2^13) >> 14 clamped to 0..255: what _mm_srai_epi32 and the two saturating packs of the
/// SSE2 loops give. A negative value is clamped before the shift (shifting a negative int right is
/// implementation-defined in C++17); for it the SIMD path's arithmetic shift gives <= -1, i.e. 0.
inline uchar roundAndClamp(int32_t sum) {
  const int32_t biased = sum + (1 << 13);
  if (biased < 0) return 0;
  const int32_t value = biased >> 14;
  return static_cast<uchar>(value > 255 ? 255 : value);
}

/// One grey output pixel: `group` points at the 16 weights of its group of four, k is its place (0..3).
inline uchar grayPixel(const uchar* p, std::size_t stride, const int16_t* group, std::size_t k) {
  return roundAndClamp(p[0] * group[2 * k] + p[1] * group[2 * k + 1] + p[stride] * group[8 + 2 * k] +
                       p[stride + 1] * group[8 + 2 * k + 1]);
}

}  // namespace

void bilinearBgrxScalar(const cv::Mat& src, const int32_t* offsets, const int16_t* weights, cv::Mat& dst) {
  const uchar* base = src.data;
  const std::size_t stride = src.step;
  const int32_t* off = offsets;
  const int16_t* w = weights;
  for (int y = 0; y < dst.rows; ++y) {
    uchar* out = dst.ptr<uchar>(y);
    for (int x = 0; x < dst.cols; ++x, ++off, w += 4, out += 3) {
      const uchar* p = base + *off;
      for (int c = 0; c < 3; ++c) {  // the 4th (x) channel is not part of the bgr8 output
        out[c] = roundAndClamp(p[c] * w[0] + p[stride + c] * w[1] + p[4 + c] * w[2] + p[stride + 4 + c] * w[3]);
      }
    }
  }
}

void bilinearGrayScalar(const cv::Mat& src, const int32_t* offsets, const int16_t* weights, cv::Mat& dst) {
  const uchar* base = src.data;
  const std::size_t stride = src.step;
  uchar* out = dst.data;  // continuous: one flat run of pixels
  const std::size_t n = dst.total();
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = grayPixel(base + offsets[i], stride, weights + 16 * (i / 4), i % 4);
  }
}

#if defined(__SSE2__)

/// One pixel per SSE2 step: two 8-byte loads fetch the 2x2 neighbourhood, two multiply-adds weigh
/// it, all four channels at once. OpenCV's remap has no vectorised 3-channel path, and its
/// 4-channel one still costs about 40 instructions per pixel here.
void bilinearBgrxSse2(const cv::Mat& src, const int32_t* offsets, const int16_t* weights, cv::Mat& dst) {
  const uchar* base = src.data;
  const std::size_t stride = src.step;
  const int32_t* off = offsets;
  const int16_t* wts = weights;
  const __m128i zero = _mm_setzero_si128();
  const __m128i round = _mm_set1_epi32(1 << 13);
  for (int y = 0; y < dst.rows; ++y) {
    uchar* out = dst.ptr<uchar>(y);
    for (int x = 0; x < dst.cols; ++x, ++off, wts += 4) {
      const uchar* p = base + *off;
      // 16-bit lanes: top = TL(b,g,r,0) TR(b,g,r,0), bottom = BL BR.
      const __m128i top = _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)), zero);
      const __m128i bottom = _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p + stride)), zero);
      // Pairs (top, bottom) per channel: left column, then right column.
      const __m128i left = _mm_unpacklo_epi16(top, bottom);
      const __m128i right = _mm_unpackhi_epi16(top, bottom);
      const __m128i w = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(wts));  // (TL, BL), (TR, BR)
      __m128i sum = _mm_add_epi32(_mm_madd_epi16(left, _mm_shuffle_epi32(w, 0x00)),
                                  _mm_madd_epi16(right, _mm_shuffle_epi32(w, 0x55)));
      sum = _mm_srai_epi32(_mm_add_epi32(sum, round), 14);
      const __m128i bytes = _mm_packus_epi16(_mm_packs_epi32(sum, zero), zero);
      const uint32_t bgrx = static_cast<uint32_t>(_mm_cvtsi128_si32(bytes));
      if (x + 1 < dst.cols) {
        std::memcpy(out, &bgrx, 4);  // the 4th byte is overwritten by the next pixel
      } else {
        std::memcpy(out, &bgrx, 3);  // the row's last pixel: nothing may be written past it
      }
      out += 3;
    }
  }
}

/// Four output pixels per SSE2 step: the 2-byte top and bottom pairs of four neighbourhoods are
/// gathered into two registers and weighed with two multiply-adds.
void bilinearGraySse2(const cv::Mat& src, const int32_t* offsets, const int16_t* weights, cv::Mat& dst) {
  const uchar* base = src.data;
  const std::size_t stride = src.step;
  const int32_t* off = offsets;
  const int16_t* wts = weights;
  uchar* out = dst.data;  // continuous: one flat run of pixels
  const std::size_t n = dst.total();
  const __m128i zero = _mm_setzero_si128();
  const __m128i round = _mm_set1_epi32(1 << 13);
  auto pair = [](const uchar* p) {
    uint16_t v;
    std::memcpy(&v, p, 2);
    return static_cast<uint32_t>(v);
  };
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4, off += 4, wts += 16) {
    const uchar* p0 = base + off[0];
    const uchar* p1 = base + off[1];
    const uchar* p2 = base + off[2];
    const uchar* p3 = base + off[3];
    const auto top01 = static_cast<int>(pair(p0) | pair(p1) << 16), top23 = static_cast<int>(pair(p2) | pair(p3) << 16);
    const auto bot01 = static_cast<int>(pair(p0 + stride) | pair(p1 + stride) << 16);
    const auto bot23 = static_cast<int>(pair(p2 + stride) | pair(p3 + stride) << 16);
    const __m128i top = _mm_unpacklo_epi8(_mm_set_epi32(0, 0, top23, top01), zero);
    const __m128i bottom = _mm_unpacklo_epi8(_mm_set_epi32(0, 0, bot23, bot01), zero);
    __m128i sum = _mm_add_epi32(_mm_madd_epi16(top, _mm_loadu_si128(reinterpret_cast<const __m128i*>(wts))),
                                _mm_madd_epi16(bottom, _mm_loadu_si128(reinterpret_cast<const __m128i*>(wts + 8))));
    sum = _mm_srai_epi32(_mm_add_epi32(sum, round), 14);
    const auto four = static_cast<uint32_t>(_mm_cvtsi128_si32(_mm_packus_epi16(_mm_packs_epi32(sum, zero), zero)));
    std::memcpy(out + i, &four, 4);
  }
  for (std::size_t k = 0; i < n; ++i, ++k) {  // the tail (when the pixel count is not a multiple of 4)
    out[i] = grayPixel(base + off[k], stride, wts, k);
  }
}

#endif  // __SSE2__

}  // namespace detail
}  // namespace docking_sim
