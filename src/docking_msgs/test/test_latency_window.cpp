#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

#include "docking_msgs/latency_window.h"

using docking_msgs::LatencyWindow;

TEST(LatencyWindow, EmptyReportsNoSamples) {
  const LatencyWindow window(10);
  const LatencyWindow::Summary s = window.summary();
  EXPECT_EQ(s.samples, 0u);
  EXPECT_EQ(s.median_ms, 0.0);
  EXPECT_EQ(s.p95_ms, 0.0);
}

TEST(LatencyWindow, NearestRankPercentilesInMilliseconds) {
  LatencyWindow window(100);
  for (int i = 100; i >= 1; --i) window.add(i * 1e-3);  // 1..100 ms, in reverse order
  const LatencyWindow::Summary s = window.summary();
  EXPECT_EQ(s.samples, 100u);
  EXPECT_NEAR(s.median_ms, 50.0, 1e-9);
  EXPECT_NEAR(s.p95_ms, 95.0, 1e-9);
  EXPECT_NEAR(s.max_ms, 100.0, 1e-9);
}

TEST(LatencyWindow, KeepsOnlyTheLatestSamples) {
  LatencyWindow window(4);
  for (double ms : {500.0, 400.0, 1.0, 2.0, 3.0, 4.0}) window.add(ms * 1e-3);
  const LatencyWindow::Summary s = window.summary();
  EXPECT_EQ(s.samples, 4u);
  EXPECT_NEAR(s.max_ms, 4.0, 1e-9);  // the two slow ones have left the window
  EXPECT_EQ(window.total(), 6u);
}

TEST(LatencyWindow, NotFiniteIsCountedApart) {
  LatencyWindow window(4);
  window.add(std::numeric_limits<double>::quiet_NaN());
  window.add(std::numeric_limits<double>::infinity());
  window.add(0.010);
  EXPECT_EQ(window.notFinite(), 2u);
  EXPECT_EQ(window.summary().samples, 1u);
  EXPECT_NEAR(window.summary().max_ms, 10.0, 1e-9);
}

TEST(LatencyWindow, ZeroCapacityIsRefused) { EXPECT_THROW(LatencyWindow(0), std::invalid_argument); }

struct RecordingStatus {
  std::map<std::string, double> values;
  template <class T>
  void add(const std::string& key, T value) {
    values[key] = static_cast<double>(value);
  }
};

TEST(LatencyWindow, DiagnosticKeysNameTheStage) {
  LatencyWindow window(10);
  window.add(0.020);
  RecordingStatus status;
  docking_msgs::addLatency(status, "image->estimate", window);
  EXPECT_NEAR(status.values.at("latency image->estimate median ms"), 20.0, 1e-9);
  EXPECT_NEAR(status.values.at("latency image->estimate p95 ms"), 20.0, 1e-9);
  EXPECT_NEAR(status.values.at("latency image->estimate max ms"), 20.0, 1e-9);
  EXPECT_EQ(status.values.at("latency image->estimate samples"), 1.0);
}
