#include "kneed_walker/ros/rate_diagnostic.h"

#include <gtest/gtest.h>

namespace kneed_walker::ros_glue {
namespace {

// Ten events a second for three seconds, from an arbitrary (large) start: 10 Hz over the time
// since the first event, then over the 5 s window; the window forgets what is older.
TEST(RateWindow, CountsEventsPerSecondOverTheWindow) {
  RateWindow window(5.0);
  EXPECT_EQ(window.rateHz(1.7e9), 0.0) << "no event yet";
  const double start_s = 1.7e9;
  for (int i = 0; i < 30; ++i) window.tick(start_s + 0.1 * i);
  EXPECT_NEAR(window.rateHz(start_s + 3.0), 10.0, 0.01);
  for (int i = 30; i < 100; ++i) window.tick(start_s + 0.1 * i);
  EXPECT_NEAR(window.rateHz(start_s + 10.05), 10.0, 0.25);
  EXPECT_EQ(window.events(start_s + 10.05), 49) << "the ticks in (5.05, 10.05] s";
  EXPECT_EQ(window.events(start_s + 20.0), 0) << "a stream that stopped";
  EXPECT_EQ(window.rateHz(start_s + 20.0), 0.0);
}

// The diagnostic task's verdict: OK inside the expected range, WARN outside it or without events.
TEST(RateDiagnostic, WarnsWithoutEventsAndOutsideItsRange) {
  RateDiagnostic quiet("input rate", 1.0, 120.0);
  diagnostic_updater::DiagnosticStatusWrapper status;
  quiet.run(status);
  EXPECT_EQ(status.level, diagnostic_msgs::DiagnosticStatus::WARN);
  EXPECT_EQ(status.message, "none in the last window");
  RateDiagnostic busy("input rate", 0.001, 1.0);
  for (int i = 0; i < 50; ++i) busy.tick();  // at once: far above 1 Hz
  diagnostic_updater::DiagnosticStatusWrapper fast;
  busy.run(fast);
  EXPECT_EQ(fast.level, diagnostic_msgs::DiagnosticStatus::WARN);
  EXPECT_NE(fast.message.find("outside"), std::string::npos) << fast.message;
  RateDiagnostic fine("input rate", 0.0, 1e9);
  fine.tick();
  fine.tick();
  diagnostic_updater::DiagnosticStatusWrapper ok;
  fine.run(ok);
  EXPECT_EQ(ok.level, diagnostic_msgs::DiagnosticStatus::OK) << ok.message;
}

}  // namespace
}  // namespace kneed_walker::ros_glue
