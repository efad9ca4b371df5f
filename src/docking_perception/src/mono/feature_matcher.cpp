#include "docking_perception/mono/feature_matcher.h"

#include "docking_perception/mono/motion_kernel.h"
#include "docking_perception/mono/pose_consistency.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <utility>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#if defined(__SSE2__)
#include <emmintrin.h>
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif
#endif

namespace docking_perception {
namespace mono {
namespace {

// Constants of the method (not settings: nothing about a new rig changes them):
// Lowe's ratio test at his 0.8 (SIFT paper: rejects ~90 % of false matches, ~5 % of correct ones).
constexpr double kLoweRatio = 0.8;
// RANSAC homography inliers within 3 px at full resolution (6 px at half): only the match's inliers are
// refined by NCC to ~0.1 px afterwards.
constexpr double kRansacThresholdPx = 3.0;
// Image keypoints kept (the strongest) before descriptors: bounds the CPU time (full-frame
// search ~10 ms CPU).
constexpr int kMaxImageKeypoints = 300;
// Model keypoints per pyramid level: bounds the matching time (7 levels x up to 3 pyramids;
// full-frame search ~10 ms CPU).
constexpr int kMaxModelKeypointsPerLevel = 400;
// Inliers + unmatched model corners refined by NCC (150 -> 220: 0.79 -> 0.55 deg at 1 m on axis).
constexpr int kMaxRefinedPoints = 220;

// One BRISK object per (threshold, octaves) in the process: each one precomputes its sampling
// pattern for 64 scales x 1024 rotations, 46 MB (measured), and the visible and IR mono_pose nodelets
// in one perception process would otherwise hold one each. Sharing is safe: OpenCV's BRISK detect and
// compute are const and keep their buffers on the stack. Held weakly: the last matcher frees it.
cv::Ptr<cv::BRISK> sharedBrisk() {
  // Only BRISK's descriptors are used (FAST detects): its detector's threshold and octaves, OpenCV's
  // defaults, play no part.
  constexpr int kAgastThreshold = 30;
  constexpr int kOctaves = 3;
  static std::mutex mutex;
  static std::weak_ptr<cv::BRISK> instance;
  const std::lock_guard<std::mutex> lock(mutex);
  std::shared_ptr<cv::BRISK> brisk = instance.lock();
  if (!brisk) {
    brisk = cv::BRISK::create(kAgastThreshold, kOctaves);
    instance = brisk;
  }
  return cv::Ptr<cv::BRISK>(brisk);
}

double signedArea(const std::vector<cv::Point2f>& polygon) {
  double area = 0.0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const cv::Point2f& a = polygon[i];
    const cv::Point2f& b = polygon[(i + 1) % polygon.size()];
    area += static_cast<double>(a.x) * b.y - static_cast<double>(b.x) * a.y;
  }
  return 0.5 * area;
}

// The two nearest train rows so far: ties keep the earlier row, as a scan in row order does.
inline void keepTwoNearest(int distance, int index, HammingPair* pair) {
  if (distance < pair->best_distance) {
    pair->second_distance = pair->best_distance;
    pair->best_distance = distance;
    pair->best_index = index;
  } else if (distance < pair->second_distance) {
    pair->second_distance = distance;
  }
}

// The matching loop. kWords > 0: descriptors of exactly kWords 64-bit words (BRISK's 64 bytes), a
// loop of fixed length the compiler unrolls with the query's words held in registers; 0: any width.
// Instantiated twice more so that the popcount builtin compiles to the POPCNT instruction where the CPU
// has it, and to portable code elsewhere.
template <int kWords>
inline void knnLoop(const cv::Mat& query, const cv::Mat& train, int first_row, int row_count,
                    std::vector<HammingPair>* pairs) {
  const int words = kWords > 0 ? kWords : query.cols / 8;
  const int tail = kWords > 0 ? 0 : query.cols % 8;
  for (int q = 0; q < query.rows; ++q) {
    const uint8_t* a = query.ptr<uint8_t>(q);
    HammingPair& pair = (*pairs)[static_cast<size_t>(q)];
    for (int t = first_row; t < first_row + row_count; ++t) {
      const uint8_t* b = train.ptr<uint8_t>(t);
      int distance = 0;
      for (int w = 0; w < words; ++w) {
        uint64_t x;
        uint64_t y;
        std::memcpy(&x, a + 8 * w, 8);
        std::memcpy(&y, b + 8 * w, 8);
        distance += __builtin_popcountll(x ^ y);
      }
      for (int k = 0; k < tail; ++k) distance += __builtin_popcount(static_cast<unsigned>(a[8 * words + k] ^ b[8 * words + k]));
      keepTwoNearest(distance, t, &pair);
    }
  }
}

constexpr int kBriskWords = 8;  // 64-byte descriptors

inline void knnLoopAnyWidth(const cv::Mat& query, const cv::Mat& train, int first_row, int row_count,
                            std::vector<HammingPair>* pairs) {
  if (query.cols == 8 * kBriskWords) {
    knnLoop<kBriskWords>(query, train, first_row, row_count, pairs);
  } else {
    knnLoop<0>(query, train, first_row, row_count, pairs);
  }
}

#if defined(__x86_64__) && defined(__GNUC__)
__attribute__((target("popcnt"))) void knnLoopPopcnt(const cv::Mat& query, const cv::Mat& train, int first_row,
                                                     int row_count, std::vector<HammingPair>* pairs) {
  knnLoopAnyWidth(query, train, first_row, row_count, pairs);
}

// BRISK's 64-byte descriptors, four train rows a step: the query is held in two registers, each pair's
// bit counts summed per 64-bit lane (psadbw, <= 128 each), the four pairs' lanes packed as 16-bit fields
// of one register and summed once, so the horizontal sum is paid once per four pairs.
__attribute__((target("avx2,popcnt"))) void knnLoopAvx2(const cv::Mat& query, const cv::Mat& train, int first_row,
                                                        int row_count, std::vector<HammingPair>* pairs) {
  const int end = first_row + row_count;
  const int end_of_fours = first_row + row_count / 4 * 4;
  const __m256i zero = _mm256_setzero_si256();
  const __m256i nibble_bits = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4, 0, 1, 1, 2, 1, 2, 2, 3,
                                               1, 2, 2, 3, 2, 3, 3, 4);
  const __m256i low_nibble = _mm256_set1_epi8(0x0f);
  for (int q = 0; q < query.rows; ++q) {
    const uint8_t* a = query.ptr<uint8_t>(q);
    const __m256i a_low = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(a));
    const __m256i a_high = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(a + 32));
    HammingPair& pair = (*pairs)[static_cast<size_t>(q)];
    for (int t = first_row; t < end_of_fours; t += 4) {
      __m256i lane_sums[4];
      for (int k = 0; k < 4; ++k) {
        const uint8_t* b = train.ptr<uint8_t>(t + k);
        const __m256i x_low = _mm256_xor_si256(a_low, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(b)));
        const __m256i x_high = _mm256_xor_si256(a_high, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(b + 32)));
        // Bits set in each byte: a 16-entry table looked up per nibble (AVX2 has no vector popcount).
        const __m256i bits = _mm256_add_epi8(
            _mm256_add_epi8(_mm256_shuffle_epi8(nibble_bits, _mm256_and_si256(x_low, low_nibble)),
                            _mm256_shuffle_epi8(nibble_bits, _mm256_and_si256(_mm256_srli_epi16(x_low, 4), low_nibble))),
            _mm256_add_epi8(_mm256_shuffle_epi8(nibble_bits, _mm256_and_si256(x_high, low_nibble)),
                            _mm256_shuffle_epi8(nibble_bits, _mm256_and_si256(_mm256_srli_epi16(x_high, 4), low_nibble))));
        lane_sums[k] = _mm256_sad_epu8(bits, zero);
      }
      const __m256i packed =
          _mm256_or_si256(_mm256_or_si256(lane_sums[0], _mm256_slli_epi64(lane_sums[1], 16)),
                          _mm256_or_si256(_mm256_slli_epi64(lane_sums[2], 32), _mm256_slli_epi64(lane_sums[3], 48)));
      __m128i sum = _mm_add_epi16(_mm256_castsi256_si128(packed), _mm256_extracti128_si256(packed, 1));
      sum = _mm_add_epi16(sum, _mm_unpackhi_epi64(sum, sum));
      const uint64_t four = static_cast<uint64_t>(_mm_cvtsi128_si64(sum));
      for (int k = 0; k < 4; ++k) keepTwoNearest(static_cast<int>((four >> (16 * k)) & 0xffff), t + k, &pair);
    }
  }
  // The rows past the last four, after them in row order.
  knnLoop<kBriskWords>(query, train, end_of_fours, end - end_of_fours, pairs);
}
#endif

}  // namespace

std::vector<HammingPair> hammingKnn2(const cv::Mat& query, const cv::Mat& train, int first_row, int row_count) {
  std::vector<HammingPair> pairs(static_cast<size_t>(query.rows));
  if (query.empty() || train.empty() || query.cols != train.cols || query.type() != CV_8U || train.type() != CV_8U) {
    return pairs;
  }
  first_row = std::max(0, first_row);
  row_count = std::min(row_count, train.rows - first_row);
#if defined(__x86_64__) && defined(__GNUC__)
  if (query.cols == 8 * kBriskWords && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt")) {
    knnLoopAvx2(query, train, first_row, row_count, &pairs);
    return pairs;
  }
  if (__builtin_cpu_supports("popcnt")) {
    knnLoopPopcnt(query, train, first_row, row_count, &pairs);
    return pairs;
  }
#endif
  knnLoopAnyWidth(query, train, first_row, row_count, &pairs);
  return pairs;
}

namespace {

// The patch correlation's inputs as 16-bit rows padded for whole runs of kCorrelationRun values: the
// template rows with zeros, so a run's products past the template vanish; the window rows padded too,
// so every run reads inside them. The window's own sums under the template come from its integral
// images, once per window, not once per position. Kept per thread and reused: the refinement
// correlates ~270 patches a frame.
constexpr int kCorrelationRun = 8;
struct PaddedPatches {
  int template_size = 0;
  int row_length = 0;     // template row length, padded
  int window_stride = 0;  // window row length, padded
  std::vector<int16_t> window;
  std::vector<int16_t> templ;
  int integral_stride = 0;           // window cols + 1
  std::vector<int32_t> integral;     // (rows + 1) x (cols + 1): sums of the window pixels above-left
  std::vector<int32_t> integral_sq;  // the same for their squares
};

void padPatches(const cv::Mat& window, const cv::Mat& templ, PaddedPatches* padded) {
  const int size = templ.rows;
  padded->template_size = size;
  padded->row_length = (size + kCorrelationRun - 1) / kCorrelationRun * kCorrelationRun;
  padded->window_stride = window.cols + padded->row_length;
  padded->window.assign(static_cast<size_t>(padded->window_stride) * static_cast<size_t>(window.rows), 0);
  padded->templ.assign(static_cast<size_t>(padded->row_length) * static_cast<size_t>(size), 0);
  for (int y = 0; y < window.rows; ++y) {
    const uint8_t* w = window.ptr<uint8_t>(y);
    std::copy(w, w + window.cols, padded->window.begin() + static_cast<std::ptrdiff_t>(y) * padded->window_stride);
  }
  for (int y = 0; y < size; ++y) {
    const uint8_t* t = templ.ptr<uint8_t>(y);
    std::copy(t, t + size, padded->templ.begin() + static_cast<std::ptrdiff_t>(y) * padded->row_length);
  }
}

void integrateWindow(const cv::Mat& window, PaddedPatches* padded) {
  padded->integral_stride = window.cols + 1;
  const size_t stride = static_cast<size_t>(padded->integral_stride);
  padded->integral.assign(stride * static_cast<size_t>(window.rows + 1), 0);
  padded->integral_sq.assign(stride * static_cast<size_t>(window.rows + 1), 0);
  for (int y = 0; y < window.rows; ++y) {
    const uint8_t* w = window.ptr<uint8_t>(y);
    int32_t row_sum = 0;
    int32_t row_sum_sq = 0;
    const size_t above = static_cast<size_t>(y) * stride;
    const size_t here = above + stride;
    for (int x = 0; x < window.cols; ++x) {
      row_sum += w[x];
      row_sum_sq += w[x] * w[x];
      padded->integral[here + x + 1] = padded->integral[above + x + 1] + row_sum;
      padded->integral_sq[here + x + 1] = padded->integral_sq[above + x + 1] + row_sum_sq;
    }
  }
}

// The box of the template's size at (oy, ox) from one of the window's integral images.
inline int32_t boxSum(const std::vector<int32_t>& integral, int integral_stride, int oy, int ox, int size) {
  const size_t stride = static_cast<size_t>(integral_stride);
  const size_t top = static_cast<size_t>(oy) * stride;
  const size_t bottom = static_cast<size_t>(oy + size) * stride;
  return integral[bottom + ox + size] - integral[bottom + ox] - integral[top + ox + size] + integral[top + ox];
}

// The sum of window x template at one position: dot products over the template's rows. With SSE2 each
// run of 8 is one multiply-add (pmaddwd) into an accumulator kept across the rows; elsewhere a plain loop.
// kFixedSize > 0: the template's size known when compiled (the refinement's 11), loops the compiler
// unrolls; 0: any size.
template <int kFixedSize>
inline int32_t positionCross(const PaddedPatches& p, int oy, int ox) {
  const int size = kFixedSize > 0 ? kFixedSize : p.template_size;
  const int row_length =
      kFixedSize > 0 ? (kFixedSize + kCorrelationRun - 1) / kCorrelationRun * kCorrelationRun : p.row_length;
  const int16_t* window = p.window.data() + static_cast<size_t>(oy) * p.window_stride + ox;
  const int16_t* templ = p.templ.data();
#if defined(__SSE2__)
  __m128i cross4 = _mm_setzero_si128();
  for (int y = 0; y < size; ++y) {
    const int16_t* w = window + static_cast<size_t>(y) * p.window_stride;
    const int16_t* t = templ + static_cast<size_t>(y) * row_length;
    for (int x = 0; x < row_length; x += kCorrelationRun) {
      const __m128i wv = _mm_loadu_si128(reinterpret_cast<const __m128i*>(w + x));
      const __m128i tv = _mm_loadu_si128(reinterpret_cast<const __m128i*>(t + x));
      cross4 = _mm_add_epi32(cross4, _mm_madd_epi16(wv, tv));
    }
  }
  cross4 = _mm_add_epi32(cross4, _mm_shuffle_epi32(cross4, _MM_SHUFFLE(1, 0, 3, 2)));
  cross4 = _mm_add_epi32(cross4, _mm_shuffle_epi32(cross4, _MM_SHUFFLE(2, 3, 0, 1)));
  return _mm_cvtsi128_si32(cross4);
#else
  int32_t cross = 0;
  for (int y = 0; y < size; ++y) {
    const int16_t* w = window + static_cast<size_t>(y) * p.window_stride;
    const int16_t* t = templ + static_cast<size_t>(y) * row_length;
    for (int x = 0; x < row_length; ++x) cross += static_cast<int32_t>(w[x]) * t[x];
  }
  return cross;
#endif
}

// Every position's correlation, from the template's sums and the window's integrals.
template <int kFixedSize>
void correlateAtEveryPosition(const PaddedPatches& p, int t_sum, double t_var, cv::Mat* response) {
  const int size = p.template_size;
  const double n = static_cast<double>(size * size);
  for (int oy = 0; oy < response->rows; ++oy) {
    float* out = response->ptr<float>(oy);
    for (int ox = 0; ox < response->cols; ++ox) {
      const int32_t w_sum = boxSum(p.integral, p.integral_stride, oy, ox, size);
      const int32_t w_sum2 = boxSum(p.integral_sq, p.integral_stride, oy, ox, size);
      const double w_var = w_sum2 - static_cast<double>(w_sum) * w_sum / n;
      const double covariance = positionCross<kFixedSize>(p, oy, ox) - static_cast<double>(w_sum) * t_sum / n;
      const double denominator = std::sqrt(std::max(0.0, w_var * t_var));
      out[ox] = denominator > 1e-9 ? static_cast<float>(covariance / denominator) : 0.0f;
    }
  }
}

// The level whose width is closest in ratio to the face's apparent width, among those `keep` accepts
// (the first on a tie; null when it accepts none). No list is built: it runs on every refinement.
template <typename Level, typename Keep>
const Level* nearestByWidth(const std::vector<Level>& levels, double apparent_width, Keep keep) {
  const Level* nearest = nullptr;
  for (const Level& candidate : levels) {
    if (!keep(candidate)) continue;
    if (!nearest || std::abs(std::log(candidate.width_px / apparent_width)) <
                        std::abs(std::log(nearest->width_px / apparent_width))) {
      nearest = &candidate;
    }
  }
  return nearest;
}

constexpr int kRefinementPatchRadius = 5;  // FeatureMatcher::refinePass's patches
constexpr int kRefinementPatchSize = 2 * kRefinementPatchRadius + 1;

}  // namespace

void normalisedCrossCorrelation(const cv::Mat& window, const cv::Mat& templ, cv::Mat* response) {
  const int size = templ.rows;
  const int positions = window.rows - size + 1;
  response->create(positions, positions, CV_32F);
  // 8-bit data: every sum fits in 32 bits (121 * 255^2 < 2^23; the window's integrals, 625 * 255^2 for
  // a 25x25 window, < 2^26).
  int t_sum = 0;
  int t_sum2 = 0;
  for (int y = 0; y < size; ++y) {
    const uint8_t* t = templ.ptr<uint8_t>(y);
    for (int x = 0; x < size; ++x) {
      t_sum += t[x];
      t_sum2 += t[x] * t[x];
    }
  }
  const double t_var = t_sum2 - static_cast<double>(t_sum) * t_sum / static_cast<double>(size * size);
  thread_local PaddedPatches padded_per_thread;
  PaddedPatches& padded = padded_per_thread;  // one thread-local lookup, not one per access
  padPatches(window, templ, &padded);
  integrateWindow(window, &padded);
  if (size == kRefinementPatchSize) {
    correlateAtEveryPosition<kRefinementPatchSize>(padded, t_sum, t_var, response);
  } else {
    correlateAtEveryPosition<0>(padded, t_sum, t_var, response);
  }
}

namespace {

// One patch of renderModelPatch, its pixels mapped into the model. kBorder: some bilinear neighbours
// may lie off the model (a corner within a pixel of its edge); they count as 0.
template <bool kBorder>
void samplePatch(const cv::Mat& model, const cv::Matx33d& m, cv::Point top_left, int size, cv::Mat* patch) {
  auto at = [&model](int u, int v) -> double {
    if (kBorder && !(u >= 0 && v >= 0 && u < model.cols && v < model.rows)) return 0.0;
    return model.at<uint8_t>(v, u);
  };
  for (int y = 0; y < size; ++y) {
    uint8_t* out = patch->ptr<uint8_t>(y);
    // Along a row the homogeneous point moves by the matrix's first column: additions, not products.
    const double row_x = top_left.x;
    const double row_y = top_left.y + y;
    double hu = m(0, 0) * row_x + m(0, 1) * row_y + m(0, 2);
    double hv = m(1, 0) * row_x + m(1, 1) * row_y + m(1, 2);
    double hw = m(2, 0) * row_x + m(2, 1) * row_y + m(2, 2);
    for (int x = 0; x < size; ++x, hu += m(0, 0), hv += m(1, 0), hw += m(2, 0)) {
      const double inverse_w = 1.0 / hw;
      const double u = hu * inverse_w;
      const double v = hv * inverse_w;
      // u, v >= -0.5 (checked at the corners): truncating u + 1 floors u, without a call to floor().
      const int u0 = static_cast<int>(u + 1.0) - 1;
      const int v0 = static_cast<int>(v + 1.0) - 1;
      const double fu = u - u0;
      const double fv = v - v0;
      const double value = (1.0 - fv) * ((1.0 - fu) * at(u0, v0) + fu * at(u0 + 1, v0)) +
                           fv * ((1.0 - fu) * at(u0, v0 + 1) + fu * at(u0 + 1, v0 + 1));
      out[x] = static_cast<uint8_t>(value + 0.5);  // in [0, 255]: a blend of 8-bit values
    }
  }
}

}  // namespace

bool renderModelPatch(const cv::Mat& model, const cv::Matx33d& image_to_model, cv::Point top_left, int size,
                      cv::Mat* patch) {
  const double max_u = model.cols - 0.5;
  const double max_v = model.rows - 0.5;
  // A homography maps the square patch to a convex quadrilateral: on the (convex) model iff its corners are.
  const int last = size - 1;
  bool interior = true;  // every bilinear neighbour on the model
  for (const cv::Point corner : {cv::Point(0, 0), cv::Point(last, 0), cv::Point(0, last), cv::Point(last, last)}) {
    const cv::Vec3d h = image_to_model * cv::Vec3d(top_left.x + corner.x, top_left.y + corner.y, 1.0);
    if (h[2] == 0.0) return false;
    const double u = h[0] / h[2];
    const double v = h[1] / h[2];
    if (!(u >= -0.5 && u < max_u && v >= -0.5 && v < max_v)) return false;
    interior = interior && u >= 0.0 && v >= 0.0 && u < model.cols - 1 && v < model.rows - 1;
  }
  patch->create(size, size, CV_8UC1);
  if (interior) {
    samplePatch<false>(model, image_to_model, top_left, size, patch);
  } else {
    samplePatch<true>(model, image_to_model, top_left, size, patch);
  }
  return true;
}

// BRISK is created with the model (buildModel): a matcher that never gets one (mono_pose in IR mode)
// never pays for its pattern tables.
FeatureMatcher::FeatureMatcher(const FeatureMatcherParams& params) : params_(params) {}

void FeatureMatcher::setParams(const FeatureMatcherParams& params) {
  const bool rebuild = params.upright_descriptors != params_.upright_descriptors ||
                       params.fast_threshold != params_.fast_threshold ||
                       params.model_widths_px != params_.model_widths_px ||
                       params.blurred_model_sigma_px != params_.blurred_model_sigma_px ||
                       params.search_row_smear_px != params_.search_row_smear_px ||
                       params.refinement_row_smears_px != params_.refinement_row_smears_px;
  params_ = params;
  if (rebuild && !texture_.empty()) buildModel(texture_, nullptr);
}

void FeatureMatcher::detect(const cv::Mat& image, std::vector<cv::KeyPoint>* keypoints, int max_keypoints) const {
  keypoints->clear();
  cv::FAST(image, *keypoints, params_.fast_threshold, true);
  if (max_keypoints > 0 && static_cast<int>(keypoints->size()) > max_keypoints) {
    cv::KeyPointsFilter::retainBest(*keypoints, max_keypoints);
  }
}

void FeatureMatcher::describe(const cv::Mat& image, std::vector<cv::KeyPoint>* keypoints, cv::Mat* descriptors,
                              bool blurred_set) const {
  if (params_.upright_descriptors && !blurred_set) {
    upright_descriptor_.compute(image, keypoints, descriptors);
  } else {
    brisk_->compute(image, *keypoints, *descriptors);
  }
}

bool FeatureMatcher::buildModel(const cv::Mat& texture_gray, std::string* reason) {
  texture_ = texture_gray;
  texture_size_ = texture_gray.size();
  levels_.clear();
  smeared_levels_.clear();
  model_points_.clear();
  model_descriptors_ = cv::Mat();
  if (texture_gray.empty() || texture_gray.type() != CV_8UC1) {
    if (reason) *reason = "the model texture must be a non-empty 8-bit gray image";
    return false;
  }
  brisk_ = !params_.upright_descriptors || hasBlurredModel() ? sharedBrisk() : cv::Ptr<cv::BRISK>();
  std::vector<int> widths = params_.model_widths_px;
  std::sort(widths.rbegin(), widths.rend());
  // The sharp levels, then (blurred_model_sigma_px > 0) the same widths blurred: the descriptors a
  // defocused or smeared face gives, then (search_row_smear_px > 0) those smeared along the rows. Each
  // set's rows are contiguous.
  std::vector<ModelSet> sets = {ModelSet::kSharp};
  if (hasBlurredModel()) sets.push_back(ModelSet::kBlurred);
  if (hasRowSmearedModel()) sets.push_back(ModelSet::kRowSmeared);
  for (const ModelSet set : sets) {
    for (const int width : widths) {
      if (width > 16) addModelLevel(texture_gray, set, width);
    }
  }
  addRowSmearedLevels();
  if (static_cast<int>(model_points_.size()) < params_.min_inliers) {
    if (reason) {
      *reason = "the model texture gives only " + std::to_string(model_points_.size()) +
                " keypoints (need at least min_inliers = " + std::to_string(params_.min_inliers) + ")";
    }
    return false;
  }
  return true;
}

void FeatureMatcher::addModelLevel(const cv::Mat& texture_gray, ModelSet set, int width) {
  ModelLevel level;
  level.set = set;
  level.width_px = width;
  level.scale = static_cast<double>(width) / texture_gray.cols;
  if (std::abs(level.scale - 1.0) < 1e-3) {
    level.image = texture_gray;
  } else {
    cv::resize(texture_gray, level.image, cv::Size(), level.scale, level.scale,
               level.scale < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR);
  }
  if (set != ModelSet::kSharp) {
    cv::Mat blurred;
    cv::GaussianBlur(level.image, blurred, cv::Size(0, 0), params_.blurred_model_sigma_px);
    level.image = blurred;
  }
  if (set == ModelSet::kRowSmeared) {
    cv::Mat smeared;
    cv::filter2D(level.image, smeared, -1, linearMotionKernel(params_.search_row_smear_px, 0.0), cv::Point(-1, -1), 0,
                 cv::BORDER_REPLICATE);
    level.image = smeared;
  }
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  detect(level.image, &keypoints, kMaxModelKeypointsPerLevel);
  describe(level.image, &keypoints, &descriptors, level.set != ModelSet::kSharp);
  level.first_row = model_descriptors_.rows;
  level.row_count = descriptors.rows;
  for (const cv::KeyPoint& kp : keypoints) {
    // Back to full-texture pixels (pixel centres at integers in both).
    model_points_.emplace_back(static_cast<float>((kp.pt.x + 0.5) / level.scale - 0.5),
                               static_cast<float>((kp.pt.y + 0.5) / level.scale - 0.5));
  }
  if (!descriptors.empty()) model_descriptors_.push_back(descriptors);
  levels_.push_back(level);
}

void FeatureMatcher::addRowSmearedLevels() {
  // The sharp levels smeared along their rows: the level nearest the face's width has about the image's
  // scale, so a smear in level pixels is about the same in image pixels.
  for (const int smear : params_.refinement_row_smears_px) {
    const cv::Mat kernel = linearMotionKernel(smear, 0.0);
    for (const ModelLevel& sharp : levels_) {
      if (sharp.set != ModelSet::kSharp) continue;
      ModelLevel level = sharp;
      level.smear_px = smear;
      level.first_row = 0;
      level.row_count = 0;
      level.image = cv::Mat();  // its own pixels: the copy shares the sharp level's, which must stay sharp
      cv::filter2D(sharp.image, level.image, -1, kernel, cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
      smeared_levels_.push_back(level);
    }
  }
}
void FeatureMatcher::refine(const cv::Mat& gray, FaceMatch* match) const {
  if (levels_.empty()) return;
  // Candidates: the inliers, plus the model corners of the level nearest the face's apparent size
  // (distinct, well-textured points the matcher did not pair): far more constraints for the pose at
  // the same refinement cost each.
  const double apparent_width = 0.5 * (cv::norm(match->face_outline[1] - match->face_outline[0]) +
                                       cv::norm(match->face_outline[2] - match->face_outline[3]));
  const ModelLevel* nearest = &refinementLevel(apparent_width, ModelSet::kSharp);
  std::vector<cv::Point2f> candidates = match->inlier_texture_points;
  const int extra_budget = std::max(0, kMaxRefinedPoints - static_cast<int>(candidates.size()));
  if (extra_budget > 0 && nearest->row_count > 0) {
    const int stride = std::max(1, nearest->row_count / extra_budget);
    for (int row = nearest->first_row; row < nearest->first_row + nearest->row_count; row += stride) {
      candidates.push_back(model_points_[static_cast<size_t>(row)]);
    }
  }
  match->refine_candidates = static_cast<int>(candidates.size());
  const cv::Matx33d drawn_at = match->homography;
  if (!refinePass(gray, candidates, match)) return;
  match->first_pass_kept = static_cast<int>(match->inlier_image_points.size());
  if (params_.refine_again_move_px > 0.0 &&
      largestCornerMove(drawn_at, match->homography) > params_.refine_again_move_px) {
    // Kept only when its points still span most of what the first pass's did: on a small blurred face (2 m)
    // a pass more may keep a bunch in one corner, and the pose then loses the face's spread (the tilt
    // from points in one corner is poorly observed). Its points may be fewer: at
    // 1 m it often drops a third of them and is still better.
    constexpr double kMinKeptSpreadFraction = 0.8;
    if (refineKeptAgain(gray, kMinKeptSpreadFraction, match)) match->refined_again = true;
  }
}

bool FeatureMatcher::refineKeptAgain(const cv::Mat& gray, double min_spread_fraction, FaceMatch* match) const {
  FaceMatch again = *match;
  if (!refinePass(gray, match->inlier_texture_points, &again)) return false;
  if (inlierSpread(again.inlier_texture_points, texture_size_) <
      min_spread_fraction * inlierSpread(match->inlier_texture_points, texture_size_)) {
    return false;
  }
  *match = std::move(again);
  return true;
}

double FeatureMatcher::largestCornerMove(const cv::Matx33d& from, const cv::Matx33d& to) const {
  std::vector<cv::Point2f> before;
  std::vector<cv::Point2f> after;
  cv::perspectiveTransform(textureCorners(), before, cv::Mat(from));
  cv::perspectiveTransform(textureCorners(), after, cv::Mat(to));
  double largest = 0.0;
  for (size_t i = 0; i < before.size(); ++i) largest = std::max(largest, static_cast<double>(cv::norm(after[i] - before[i])));
  return largest;
}

const FeatureMatcher::ModelLevel& FeatureMatcher::refinementLevel(double apparent_width, ModelSet set) const {
  const ModelLevel* level =
      nearestByWidth(levels_, apparent_width, [set](const ModelLevel& candidate) { return candidate.set == set; });
  return level ? *level : levels_.front();
}

FeatureMatcher::RefinedPoints FeatureMatcher::refineAgainstRowSmears(const cv::Mat& gray, double apparent_width,
                                                                     const std::vector<cv::Point2f>& candidates,
                                                                     const cv::Matx33d& homography,
                                                                     const cv::Rect& face_box,
                                                                     const RefinedPoints& to_beat,
                                                                     int* smear_px) const {
  // Judged by the correlation summed over all candidates (a point dropped counts 0), not by the mean of
  // those kept: a long smear keeps only the points along horizontal edges, and those correlate well.
  auto support = [](const RefinedPoints& points) {
    return points.mean_correlation * static_cast<double>(points.image_points.size());
  };
  // The smear is chosen on a sample of the candidates, against the blurred model on the same sample; only
  // the winner correlates them all (a third of the cost of trying every smear on every point).
  constexpr size_t kSelectionSample = 48;
  const size_t stride = std::max<size_t>(1, candidates.size() / kSelectionSample);
  std::vector<cv::Point2f> sample;
  for (size_t i = 0; i < candidates.size(); i += stride) sample.push_back(candidates[i]);
  // Only patches at least half a smear inside the face's left and right edges: nearer, the image smears
  // the background into the face, and the model (smeared with its own border) does not, which pulls the
  // points inwards and the range out (a pose 6 % too far at 1.9 m on stress seed 205).
  auto inside = [&face_box](int smear) {
    const int margin = (smear + 1) / 2;
    return cv::Rect(face_box.x + margin, face_box.y, std::max(0, face_box.width - 2 * margin), face_box.height);
  };
  double best_support =
      support(refineAgainst(gray, refinementLevel(apparent_width, ModelSet::kBlurred), sample, homography, face_box));
  const ModelLevel* best_level = nullptr;
  for (const int smear : params_.refinement_row_smears_px) {
    const ModelLevel* level = nearestByWidth(smeared_levels_, apparent_width,
                                             [smear](const ModelLevel& candidate) { return candidate.smear_px == smear; });
    if (!level) continue;
    const double sample_support = support(refineAgainst(gray, *level, sample, homography, inside(smear)));
    if (sample_support > best_support) {
      best_support = sample_support;
      best_level = level;
    }
  }
  *smear_px = 0;
  if (!best_level) return RefinedPoints();
  RefinedPoints smeared = refineAgainst(gray, *best_level, candidates, homography, inside(best_level->smear_px));
  if (static_cast<int>(smeared.image_points.size()) < params_.min_inliers || support(smeared) <= support(to_beat)) {
    return RefinedPoints();
  }
  *smear_px = best_level->smear_px;
  return smeared;
}

FeatureMatcher::RefinedPoints FeatureMatcher::refineAgainst(const cv::Mat& gray, const ModelLevel& level,
                                                            const std::vector<cv::Point2f>& candidates,
                                                            const cv::Matx33d& homography,
                                                            const cv::Rect& face_box) const {
  constexpr int kPatchRadius = kRefinementPatchRadius;
  constexpr int kSearch = 3;
  const cv::Rect image_rect(0, 0, gray.cols, gray.rows);
  // Level pixel -> texture pixel, then the homography into the image; inverted, it draws each patch.
  const double s = level.scale;
  const cv::Matx33d level_to_texture(1.0 / s, 0.0, 0.5 / s - 0.5, 0.0, 1.0 / s, 0.5 / s - 0.5, 0.0, 0.0, 1.0);
  const cv::Matx33d image_to_level = (homography * level_to_texture).inv();
  RefinedPoints out;
  double correlation_sum = 0.0;
  cv::Mat rendered;
  cv::Mat response;
  for (const cv::Point2f& texture_point : candidates) {
    const cv::Vec3d projected = homography * cv::Vec3d(texture_point.x, texture_point.y, 1.0);
    const cv::Point2d predicted(projected[0] / projected[2], projected[1] / projected[2]);
    const cv::Point centre(static_cast<int>(std::lround(predicted.x)), static_cast<int>(std::lround(predicted.y)));
    const cv::Rect patch(centre.x - kPatchRadius, centre.y - kPatchRadius, 2 * kPatchRadius + 1,
                         2 * kPatchRadius + 1);
    const cv::Rect window(centre.x - kPatchRadius - kSearch, centre.y - kPatchRadius - kSearch,
                          2 * (kPatchRadius + kSearch) + 1, 2 * (kPatchRadius + kSearch) + 1);
    if ((patch & face_box) != patch || (window & image_rect) != window) continue;
    if (!renderModelPatch(level.image, image_to_level, patch.tl(), patch.width, &rendered)) continue;
    normalisedCrossCorrelation(gray(window), rendered, &response);
    double best = 0.0;
    cv::Point peak;
    cv::minMaxLoc(response, nullptr, &best, nullptr, &peak);
    if (!(best >= params_.min_correlation)) continue;
    if (peak.x == 0 || peak.y == 0 || peak.x == response.cols - 1 || peak.y == response.rows - 1) continue;
    auto parabola = [](float left, float middle, float right) {
      const float denominator = left - 2.0f * middle + right;
      return std::abs(denominator) < 1e-6f ? 0.0f : 0.5f * (left - right) / denominator;
    };
    const float dx = parabola(response.at<float>(peak.y, peak.x - 1), response.at<float>(peak.y, peak.x),
                              response.at<float>(peak.y, peak.x + 1));
    const float dy = parabola(response.at<float>(peak.y - 1, peak.x), response.at<float>(peak.y, peak.x),
                              response.at<float>(peak.y + 1, peak.x));
    // The rendering put the model point at `predicted`; the image has it shifted by the peak offset.
    const double offset_x = peak.x - kSearch + dx;
    const double offset_y = peak.y - kSearch + dy;
    out.texture_points.push_back(texture_point);
    out.image_points.emplace_back(static_cast<float>(predicted.x + offset_x), static_cast<float>(predicted.y + offset_y));
    correlation_sum += best;
  }
  if (!out.image_points.empty()) out.mean_correlation = correlation_sum / static_cast<double>(out.image_points.size());
  return out;
}

bool FeatureMatcher::refinePass(const cv::Mat& gray, const std::vector<cv::Point2f>& candidates,
                                FaceMatch* match) const {
  std::vector<cv::Point2f> outline;
  const float tw = static_cast<float>(texture_size_.width) - 0.5f;
  const float th = static_cast<float>(texture_size_.height) - 0.5f;
  cv::perspectiveTransform(std::vector<cv::Point2f>{{-0.5f, -0.5f}, {tw, -0.5f}, {tw, th}, {-0.5f, th}}, outline,
                           cv::Mat(match->homography));
  const double apparent_width = 0.5 * (cv::norm(outline[1] - outline[0]) + cv::norm(outline[2] - outline[3]));
  const cv::Rect face_box = cv::boundingRect(outline) & cv::Rect(0, 0, gray.cols, gray.rows);
  if (face_box.area() <= 0) return false;
  const RefinedPoints refined = refineAgainstBestModel(gray, apparent_width, candidates, face_box, match);
  const std::vector<cv::Point2f>& texture_points = refined.texture_points;
  const std::vector<cv::Point2f>& image_points = refined.image_points;
  if (static_cast<int>(image_points.size()) < params_.min_inliers) return false;  // keep the unrefined ones
  // A last RANSAC on the refined points (tight threshold) drops the few that locked onto a wrong peak.
  std::vector<unsigned char> mask;
  const cv::Mat homography = cv::findHomography(texture_points, image_points, cv::RANSAC, 1.0, mask, 2000, 0.995);
  if (homography.empty()) return false;
  std::vector<cv::Point2f> kept_texture;
  std::vector<cv::Point2f> kept_image;
  for (size_t i = 0; i < mask.size(); ++i) {
    if (!mask[i]) continue;
    kept_texture.push_back(texture_points[i]);
    kept_image.push_back(image_points[i]);
  }
  if (static_cast<int>(kept_image.size()) < params_.min_inliers) return false;
  match->homography = cv::Matx33d(homography);
  match->inlier_texture_points = kept_texture;
  match->inlier_image_points = kept_image;
  match->refined = true;
  return true;
}

FeatureMatcher::RefinedPoints FeatureMatcher::refineAgainstBestModel(const cv::Mat& gray, double apparent_width,
                                                                     const std::vector<cv::Point2f>& candidates,
                                                                     const cv::Rect& face_box, FaceMatch* match) const {
  // A sharp patch correlated with a blurred image peaks off the point, each texture detail its own way,
  // and those offsets do not cancel over the face (under 2 px of defocus at 1.4 m the tilt was 1.7 deg
  // off); a blurred patch correlated with a sharp image does the same. The set (sharp or blurred model)
  // whose patches match the image better gives the points.
  RefinedPoints refined =
      refineAgainst(gray, refinementLevel(apparent_width, ModelSet::kSharp), candidates, match->homography, face_box);
  if (!params_.blur_matched_refinement || !hasBlurredModel()) return refined;
  RefinedPoints blurred =
      refineAgainst(gray, refinementLevel(apparent_width, ModelSet::kBlurred), candidates, match->homography, face_box);
  // Near sharp faces the blurred patches may correlate as well or a little better and still locate the
  // points less precisely (their peaks are broader): they must win clearly. 0.05 kept every sharp
  // condition of the stress harness's tuning seeds as it was (seeds 100-139; docs/PERFORMANCE.md).
  // The correlation is averaged over every candidate (a point dropped counts 0): over the points each
  // kept, the sharp patches on a blurred face keep only the few that still correlate, and correlate
  // well, and won at the exact homography (half the points, 0.52 px off, against 0.15 px).
  constexpr double kBlurredRefinementMinGain = 0.05;
  auto per_candidate = [&candidates](const RefinedPoints& points) {
    return points.mean_correlation * static_cast<double>(points.image_points.size()) /
           static_cast<double>(std::max<size_t>(1, candidates.size()));
  };
  if (static_cast<int>(blurred.image_points.size()) < params_.min_inliers ||
      !(per_candidate(blurred) > per_candidate(refined) + kBlurredRefinementMinGain)) {
    return refined;
  }
  match->refined_with_blurred_model = true;
  // A blurred image: its blur may be a smear along the rows rather than round.
  int smear_px = 0;
  RefinedPoints smeared =
      refineAgainstRowSmears(gray, apparent_width, candidates, match->homography, face_box, blurred, &smear_px);
  if (smear_px <= 0) return blurred;
  match->refined_with_row_smear_px = smear_px;
  return smeared;
}
FaceMatch FeatureMatcher::match(const cv::Mat& gray, const cv::Rect& roi_in, double expected_face_width_px,
                                int pyramid_level, ModelSet model_set) const {
  FaceMatch result;
  const cv::Rect roi = searchRegion(gray, roi_in, &result.status);
  if (!result.status.empty()) return result;
  const ModelSet set = hasModelSet(model_set) ? model_set : ModelSet::kSharp;
  result.model_set = set;
  const bool half = pyramid_level > 0;
  result.pyramid_level = half ? 1 : 0;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  describeRegion(gray, roi, half, set != ModelSet::kSharp, &keypoints, &descriptors);
  result.keypoints = static_cast<int>(keypoints.size());
  if (keypoints.size() < 4) {
    result.status = "too few image keypoints (" + std::to_string(keypoints.size()) + ")";
    return result;
  }
  std::vector<cv::Point2f> texture_points;
  std::vector<cv::Point2f> image_points;
  const ModelRows rows = modelRows(set, half ? 0.5 * expected_face_width_px : expected_face_width_px);
  ratioTestMatches(descriptors, keypoints, rows, half, roi.tl(), &texture_points, &image_points);
  result.matches = static_cast<int>(image_points.size());
  result.matched_image_points = image_points;
  if (result.matches < params_.min_inliers) {
    result.status = "too few matches (" + std::to_string(result.matches) + " < " +
                    std::to_string(params_.min_inliers) + ")";
    return result;
  }
  if (!fitHomography(texture_points, image_points, half, &result)) return result;
  const std::vector<cv::Point2f> corners = textureCorners();
  cv::perspectiveTransform(corners, result.face_outline, cv::Mat(result.homography));
  result.status = outlineProblem(result.face_outline);
  if (!result.status.empty()) return result;
  refine(gray, &result);
  cv::perspectiveTransform(corners, result.face_outline, cv::Mat(result.homography));
  result.found = true;
  return result;
}

cv::Rect FeatureMatcher::searchRegion(const cv::Mat& gray, const cv::Rect& roi_in, std::string* problem) const {
  if (model_descriptors_.empty()) {
    *problem = "no model features";
  } else if (gray.empty() || gray.type() != CV_8UC1) {
    *problem = "image is not 8-bit gray";
  }
  if (!problem->empty()) return cv::Rect();
  const cv::Rect full(0, 0, gray.cols, gray.rows);
  const cv::Rect roi = roi_in.area() > 0 ? (roi_in & full) : full;
  if (roi.width < 16 || roi.height < 16) *problem = "search region too small";
  return roi;
}

void FeatureMatcher::describeRegion(const cv::Mat& gray, const cv::Rect& roi, bool half, bool blurred_set,
                                    std::vector<cv::KeyPoint>* keypoints, cv::Mat* descriptors) const {
  // BRISK's descriptor code mis-reads sub-matrix views (measured: almost no matches on a region view,
  // normal matches on its copy), so it gets a continuous copy; FAST and the upright descriptor read
  // the view itself.
  const bool full = roi == cv::Rect(0, 0, gray.cols, gray.rows);
  cv::Mat view = full || (params_.upright_descriptors && !blurred_set) ? gray(roi) : gray(roi).clone();
  if (half) cv::pyrDown(view, view);
  detect(view, keypoints, kMaxImageKeypoints);
  describe(view, keypoints, descriptors, blurred_set);
}

FeatureMatcher::ModelRows FeatureMatcher::modelRows(ModelSet set, double expected_face_width_px) const {
  // The levels of the requested set (sharp / blurred), all of them or those near the expected apparent width.
  for (const bool by_width : {expected_face_width_px > 0.0, false}) {
    int begin = -1;
    int end = -1;
    for (const ModelLevel& level : levels_) {
      if (level.set != set) continue;
      if (by_width && std::abs(std::log(level.width_px / expected_face_width_px)) > std::log(1.6)) continue;
      if (begin < 0) begin = level.first_row;
      end = level.first_row + level.row_count;
    }
    if (begin >= 0) return ModelRows{begin, end - begin};
  }
  return ModelRows{};
}

void FeatureMatcher::ratioTestMatches(const cv::Mat& descriptors, const std::vector<cv::KeyPoint>& keypoints,
                                      const ModelRows& rows, bool half, cv::Point offset,
                                      std::vector<cv::Point2f>* texture_points,
                                      std::vector<cv::Point2f>* image_points) const {
  const std::vector<HammingPair> pairs = hammingKnn2(descriptors, model_descriptors_, rows.first, rows.count);
  for (size_t q = 0; q < pairs.size(); ++q) {
    const HammingPair& pair = pairs[q];
    if (pair.best_index < 0 || pair.second_distance >= (1 << 30)) continue;
    if (pair.best_distance >= kLoweRatio * pair.second_distance) continue;
    // Half resolution: pyrDown's pixel x is its 5-tap kernel centred on full-resolution pixel 2x.
    const cv::Point2f p = half ? 2.0f * keypoints[q].pt : keypoints[q].pt;
    texture_points->push_back(model_points_[static_cast<size_t>(pair.best_index)]);
    image_points->emplace_back(p.x + offset.x, p.y + offset.y);
  }
}

bool FeatureMatcher::fitHomography(const std::vector<cv::Point2f>& texture_points,
                                   const std::vector<cv::Point2f>& image_points, bool half, FaceMatch* result) const {
  std::vector<unsigned char> inlier_mask;
  const cv::Mat homography = cv::findHomography(texture_points, image_points, cv::RANSAC,
                                                kRansacThresholdPx * (half ? 2.0 : 1.0), inlier_mask, 2000,
                                                0.995);
  if (homography.empty()) {
    result->status = "no homography";
    return false;
  }
  for (size_t i = 0; i < inlier_mask.size(); ++i) {
    if (!inlier_mask[i]) continue;
    result->inlier_texture_points.push_back(texture_points[i]);
    result->inlier_image_points.push_back(image_points[i]);
  }
  result->inliers = static_cast<int>(result->inlier_image_points.size());
  if (result->inliers < params_.min_inliers) {
    result->status = "too few inliers (" + std::to_string(result->inliers) + " < " +
                     std::to_string(params_.min_inliers) + ")";
    return false;
  }
  result->homography = cv::Matx33d(homography);
  return true;
}
std::vector<cv::Point2f> FeatureMatcher::textureCorners() const {
  const float w = static_cast<float>(texture_size_.width) - 0.5f;
  const float h = static_cast<float>(texture_size_.height) - 0.5f;
  return {{-0.5f, -0.5f}, {w, -0.5f}, {w, h}, {-0.5f, h}};
}

std::string FeatureMatcher::outlineProblem(const std::vector<cv::Point2f>& outline) const {
  // A real view of the face: a convex outline of plausible size, not mirrored.
  const double area = signedArea(outline);
  if (!cv::isContourConvex(outline)) return "matched face outline is not convex";
  if (area * signedArea(textureCorners()) <= 0.0) return "matched face is mirrored";
  return "";
}

FaceMatch FeatureMatcher::matchAtPrediction(const cv::Mat& gray, const cv::Matx33d& predicted_homography,
                                            double min_kept_fraction) const {
  FaceMatch result;
  result.from_prediction = true;
  if (levels_.empty() || gray.empty() || gray.type() != CV_8UC1) {
    result.status = levels_.empty() ? "no model features" : "image is not 8-bit gray";
    return result;
  }
  result.homography = predicted_homography;
  cv::perspectiveTransform(textureCorners(), result.face_outline, cv::Mat(predicted_homography));
  result.status = outlineProblem(result.face_outline);
  if (!result.status.empty()) return result;
  refine(gray, &result);
  const int needed = std::max(params_.min_inliers,
                              static_cast<int>(std::ceil(min_kept_fraction * result.refine_candidates)));
  result.inliers = static_cast<int>(result.inlier_image_points.size());
  // Whether the prediction held is the first pass's answer; a pass more may drop points it located less
  // well, which says nothing against the prediction.
  if (!result.refined || result.first_pass_kept < needed || result.inliers < params_.min_inliers) {
    result.status = "the predicted face kept " + std::to_string(result.first_pass_kept) + " of " +
                    std::to_string(result.refine_candidates) + " refined points (need " + std::to_string(needed) + ")";
    result.refined = false;
    result.inlier_image_points.clear();
    result.inlier_texture_points.clear();
    return result;
  }
  cv::perspectiveTransform(textureCorners(), result.face_outline, cv::Mat(result.homography));
  result.found = true;
  return result;
}

}  // namespace mono
}  // namespace docking_perception
