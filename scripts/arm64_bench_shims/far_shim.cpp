// scripts/arm64_bench_instructions.sh: LD_PRELOAD shim for bench_disparity under callgrind: a dump (CALLGRIND_DUMP_STATS_AT) before and after every call
// of the far stage's library functions that bench_disparity calls (cv::cvtColor and rectifyWindow: rectify;
// detect: detection; confirmByAppearance: appearance). Each dump holds the instructions since the previous one, so
// the dumps labelled with a function's name are exactly the instructions inside its calls, and the one before
// detect holds computeDisparity (with the loop's few clock reads). Needs no call-stack tracking.
#include <dlfcn.h>
#include <valgrind/callgrind.h>
#include <opencv2/imgproc.hpp>
#include "docking_perception/disparity/window_rectifier.h"
#include "docking_perception/disparity/disparity_detector.h"
#include "docking_perception/disparity/face_appearance.h"
namespace dd = docking_perception::disparity;
template <typename Fn> Fn real(const char* name) { return reinterpret_cast<Fn>(dlsym(RTLD_NEXT, name)); }

#define CVT "_ZN2cv8cvtColorERKNS_11_InputArrayERKNS_12_OutputArrayEii"
void shim_cvt(cv::InputArray src, cv::OutputArray dst, int code, int dcn) __asm__(CVT);
void shim_cvt(cv::InputArray src, cv::OutputArray dst, int code, int dcn) {
  static auto fn = real<void (*)(cv::InputArray, cv::OutputArray, int, int)>(CVT);
  CALLGRIND_DUMP_STATS_AT("cvtColor_pre");
  fn(src, dst, code, dcn);
  CALLGRIND_DUMP_STATS_AT("cvtColor");
}
#define RW "_ZNK18docking_perception9disparity15WindowRectifier13rectifyWindowERKN2cv3MatERKNS2_5Rect_IiEEPS3_"
void shim_rw(const dd::WindowRectifier* self, const cv::Mat& grey, const cv::Rect& window, cv::Mat* out) __asm__(RW);
void shim_rw(const dd::WindowRectifier* self, const cv::Mat& grey, const cv::Rect& window, cv::Mat* out) {
  static auto fn = real<void (*)(const dd::WindowRectifier*, const cv::Mat&, const cv::Rect&, cv::Mat*)>(RW);
  CALLGRIND_DUMP_STATS_AT("rectifyWindow_pre");
  fn(self, grey, window, out);
  CALLGRIND_DUMP_STATS_AT("rectifyWindow");
}
#define DET "_ZNK18docking_perception9disparity17DisparityDetector6detectERKN2cv3MatERKNS0_14StereoGeometryEddNS2_5Rect_IiEERKNS0_10SearchHintERKNS0_11ImageWindowE"
dd::Detection shim_det(const dd::DisparityDetector* self, const cv::Mat& disparity, const dd::StereoGeometry& g,
                       double a, double b, cv::Rect r, const dd::SearchHint& h, const dd::ImageWindow& w) __asm__(DET);
dd::Detection shim_det(const dd::DisparityDetector* self, const cv::Mat& disparity, const dd::StereoGeometry& g,
                       double a, double b, cv::Rect r, const dd::SearchHint& h, const dd::ImageWindow& w) {
  static auto fn = real<dd::Detection (*)(const dd::DisparityDetector*, const cv::Mat&, const dd::StereoGeometry&,
                                          double, double, cv::Rect, const dd::SearchHint&, const dd::ImageWindow&)>(DET);
  CALLGRIND_DUMP_STATS_AT("detect_pre");
  dd::Detection result = fn(self, disparity, g, a, b, r, h, w);
  CALLGRIND_DUMP_STATS_AT("detect");
  return result;
}
#define APP "_ZN18docking_perception9disparity19confirmByAppearanceERKNS0_19FaceAppearanceCheckERKN2cv3MatES7_RKNS0_14StereoGeometryERKNS0_20FaceAppearanceParamsEPNS0_9DetectionE"
dd::AppearanceResult shim_app(const dd::FaceAppearanceCheck& c, const cv::Mat& l, const cv::Mat& d,
                              const dd::StereoGeometry& g, const dd::FaceAppearanceParams& p, dd::Detection* det) __asm__(APP);
dd::AppearanceResult shim_app(const dd::FaceAppearanceCheck& c, const cv::Mat& l, const cv::Mat& d,
                              const dd::StereoGeometry& g, const dd::FaceAppearanceParams& p, dd::Detection* det) {
  static auto fn = real<dd::AppearanceResult (*)(const dd::FaceAppearanceCheck&, const cv::Mat&, const cv::Mat&,
                                                 const dd::StereoGeometry&, const dd::FaceAppearanceParams&,
                                                 dd::Detection*)>(APP);
  CALLGRIND_DUMP_STATS_AT("appearance_pre");
  dd::AppearanceResult result = fn(c, l, d, g, p, det);
  CALLGRIND_DUMP_STATS_AT("appearance");
  return result;
}
