// scripts/arm64_bench_instructions.sh: LD_PRELOAD shim for bench_mono, callgrind client requests around every MonoPoseEstimator::process call (collection on inside
// the call only, run with --collect-atstart=no), and instrumentation on at the estimator's construction (run with
// --instr-atstart=no). Counts the stage without callgrind's call-stack tracking (--toggle-collect relies on it).
#include <dlfcn.h>
#include <valgrind/callgrind.h>
#include "docking_perception/mono/mono_pose_estimator.h"
using docking_perception::mono::MonoPoseEstimator;
using docking_perception::mono::MonoPoseResult;
#define PROCESS "_ZN18docking_perception4mono17MonoPoseEstimator7processERKN2cv3MatEd"
#define CTOR "_ZN18docking_perception4mono17MonoPoseEstimatorC1ERKNS0_11TargetModelERKNS0_16CameraIntrinsicsERKNS0_14MonoPoseParamsE"
MonoPoseResult shim_process(MonoPoseEstimator* self, const cv::Mat& image, double stamp) __asm__(PROCESS);
MonoPoseResult shim_process(MonoPoseEstimator* self, const cv::Mat& image, double stamp) {
  using Fn = MonoPoseResult (*)(MonoPoseEstimator*, const cv::Mat&, double);
  static Fn real = reinterpret_cast<Fn>(dlsym(RTLD_NEXT, PROCESS));
  CALLGRIND_TOGGLE_COLLECT;
  MonoPoseResult result = real(self, image, stamp);
  CALLGRIND_TOGGLE_COLLECT;
  return result;
}
extern "C" void shim_ctor(void* self, const void* a, const void* b, const void* c) __asm__(CTOR);
extern "C" void shim_ctor(void* self, const void* a, const void* b, const void* c) {
  using Fn = void (*)(void*, const void*, const void*, const void*);
  static Fn real = reinterpret_cast<Fn>(dlsym(RTLD_NEXT, CTOR));
  CALLGRIND_START_INSTRUMENTATION;
  real(self, a, b, c);
}
