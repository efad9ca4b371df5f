#include "docking_msgs/latency_window.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace docking_msgs {

LatencyWindow::LatencyWindow(std::size_t capacity) : capacity_(capacity) {
  if (capacity == 0) throw std::invalid_argument("LatencyWindow: capacity must be at least 1");
  samples_ms_.reserve(capacity);
}

void LatencyWindow::add(double latency_s) {
  if (!std::isfinite(latency_s)) {
    ++not_finite_;
    return;
  }
  const double ms = 1e3 * latency_s;
  if (samples_ms_.size() < capacity_) {
    samples_ms_.push_back(ms);
  } else {
    samples_ms_[next_] = ms;
  }
  next_ = (next_ + 1) % capacity_;
  ++total_;
}

LatencyWindow::Summary LatencyWindow::summary() const {
  Summary s;
  s.samples = samples_ms_.size();
  if (samples_ms_.empty()) return s;
  std::vector<double> sorted = samples_ms_;
  std::sort(sorted.begin(), sorted.end());
  // Nearest rank: the smallest sample with at least q of the samples at or below it.
  const auto rank = [&sorted](double q) {
    const auto index = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
    return sorted[std::min(sorted.size(), std::max<std::size_t>(index, 1)) - 1];
  };
  s.median_ms = rank(0.5);
  s.p95_ms = rank(0.95);
  s.max_ms = sorted.back();
  return s;
}

}  // namespace docking_msgs
