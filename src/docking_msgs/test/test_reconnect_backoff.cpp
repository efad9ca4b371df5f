#include <docking_msgs/reconnect_backoff.h>

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

using docking_msgs::BackoffParams;
using docking_msgs::ReconnectBackoff;

TEST(ReconnectBackoff, DoublesUpToTheMaximum) {
  ReconnectBackoff backoff(BackoffParams{0.5, 3.0, 2.0});
  EXPECT_DOUBLE_EQ(backoff.nextDelay(), 0.5);
  EXPECT_DOUBLE_EQ(backoff.nextDelay(), 1.0);
  EXPECT_DOUBLE_EQ(backoff.nextDelay(), 2.0);
  EXPECT_DOUBLE_EQ(backoff.nextDelay(), 3.0);
  EXPECT_DOUBLE_EQ(backoff.nextDelay(), 3.0);
  EXPECT_EQ(backoff.failures(), 5);
}

TEST(ReconnectBackoff, ResetStartsAgainFromInitial) {
  ReconnectBackoff backoff(BackoffParams{0.2, 10.0, 3.0});
  backoff.nextDelay();
  backoff.nextDelay();
  backoff.reset();
  EXPECT_EQ(backoff.failures(), 0);
  EXPECT_DOUBLE_EQ(backoff.nextDelay(), 0.2);
  EXPECT_NEAR(backoff.nextDelay(), 0.6, 1e-12);
}

TEST(ReconnectBackoff, FactorOneIsAFixedDelay) {
  ReconnectBackoff backoff(BackoffParams{1.5, 1.5, 1.0});
  for (int i = 0; i < 4; ++i) EXPECT_DOUBLE_EQ(backoff.nextDelay(), 1.5);
}

TEST(ReconnectBackoff, InvalidParametersNameTheField) {
  auto message = [](const BackoffParams& params) {
    try {
      ReconnectBackoff backoff(params);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_EQ(message(BackoffParams{0.0, 1.0, 2.0}).rfind("initial_s", 0), 0u);
  EXPECT_EQ(message(BackoffParams{2.0, 1.0, 2.0}).rfind("max_s", 0), 0u);
  EXPECT_EQ(message(BackoffParams{0.5, 1.0, 0.5}).rfind("factor", 0), 0u);
}
