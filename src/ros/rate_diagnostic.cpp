#include "kneed_walker/ros/rate_diagnostic.h"

#include <algorithm>
#include <chrono>
#include <cstdio>

namespace kneed_walker::ros_glue {

void RateWindow::tick(double now_s) {
  if (first_s_ < 0) first_s_ = now_s;
  ticks_s_.push_back(now_s);
  forget(now_s);
}

void RateWindow::forget(double now_s) {
  while (!ticks_s_.empty() && ticks_s_.front() <= now_s - window_s_) ticks_s_.pop_front();
}

int RateWindow::events(double now_s) {
  forget(now_s);
  return static_cast<int>(ticks_s_.size());
}

double RateWindow::rateHz(double now_s) {
  if (first_s_ < 0) return 0;
  const double span_s = std::min(window_s_, now_s - first_s_);
  return span_s > 0 ? events(now_s) / span_s : 0;
}

double steadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void RateDiagnostic::tick() {
  std::lock_guard<std::mutex> lock(mutex_);
  window_.tick(steadySeconds());
}

void RateDiagnostic::run(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  const double now_s = steadySeconds();
  const double rate_hz = window_.rateHz(now_s);
  const int events = window_.events(now_s);
  char text[96];
  if (events == 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "none in the last window");
  } else if (rate_hz < min_hz_ || rate_hz > max_hz_) {
    std::snprintf(text, sizeof text, "%.1f Hz, outside [%g, %g] Hz", rate_hz, min_hz_, max_hz_);
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, text);
  } else {
    std::snprintf(text, sizeof text, "%.1f Hz", rate_hz);
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, text);
  }
  status.add("rate (Hz, wall time)", rate_hz);
  status.add("events in window", events);
  status.add("expected min (Hz)", min_hz_);
  status.add("expected max (Hz)", max_hz_);
}

}  // namespace kneed_walker::ros_glue
