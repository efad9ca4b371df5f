// The latency of one stage of the guidance chain: from an image's stamp to the moment a node publishes
// what it made of that image (an estimate, the arbiter's output, a cmd_vel), over the stage's latest
// samples. Each node keeps one and reports it in its diagnostics, so the chain's latency is measured
// stage by stage by the nodes themselves (issue 15). The clock is ROS time: on the robot, wall time;
// in the simulator, sim time (wall latency = sim latency / the real-time factor). ROS-free; one copy
// for the estimators, the arbiter and the planner.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace docking_msgs {

class LatencyWindow {
 public:
  /// 10 s of a 30 Hz stage: the diagnostics (1 Hz) describe the recent past, not the whole run.
  static constexpr std::size_t kDefaultCapacity = 300;

  struct Summary {
    std::size_t samples = 0;  ///< in the window (0: the figures below are 0)
    double median_ms = 0.0;
    double p95_ms = 0.0;
    double max_ms = 0.0;
  };

  /// Throws std::invalid_argument for capacity 0.
  explicit LatencyWindow(std::size_t capacity = kDefaultCapacity);

  /// One latency, seconds. NaN or infinite (a broken stamp) is no latency: counted apart, not kept.
  void add(double latency_s);
  Summary summary() const;
  std::size_t total() const { return total_; }
  std::size_t notFinite() const { return not_finite_; }

 private:
  std::vector<double> samples_ms_;  // a ring once full
  std::size_t capacity_;
  std::size_t next_ = 0;
  std::size_t total_ = 0;
  std::size_t not_finite_ = 0;
};

/// The window as diagnostic key-values ("latency image->estimate p95 ms", ...): `Status` is anything with
/// add(key, value), e.g. diagnostic_updater::DiagnosticStatusWrapper.
template <class Status>
void addLatency(Status& status, const std::string& stage, const LatencyWindow& window) {
  const LatencyWindow::Summary s = window.summary();
  const std::string prefix = "latency " + stage;
  status.add(prefix + " median ms", s.median_ms);
  status.add(prefix + " p95 ms", s.p95_ms);
  status.add(prefix + " max ms", s.max_ms);
  status.add(prefix + " samples", s.samples);
}

}  // namespace docking_msgs
