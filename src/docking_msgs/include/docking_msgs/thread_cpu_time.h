// CPU time of the calling thread, ms: what one frame cost, whatever else its process runs (the
// nodelet manager hosts several estimators; the simulator renders beside its physics). Header-only and
// ROS-free; one copy for the renderer and the estimators.
#pragma once

#include <ctime>

namespace docking_msgs {

inline double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

}  // namespace docking_msgs
