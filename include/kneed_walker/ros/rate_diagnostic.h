// The nodelet's input and output rates for /diagnostics, counted in steady (wall) time.
// diagnostic_updater::FrequencyStatus counts in ros::Time: under simulated time (a bag played
// with --clock) that starts at 0, which made a window of ~1.7e9 s and an ERROR for the whole
// playback, and it goes back when a bag loops. Wall time does neither.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>

#include <deque>
#include <mutex>
#include <string>

namespace kneed_walker::ros_glue {

// Events per second over the last `window_s` seconds of steady time.
class RateWindow {
 public:
  explicit RateWindow(double window_s = 5.0) : window_s_(window_s) {}
  // An event at `now_s` (steady seconds, non-decreasing).
  void tick(double now_s);
  // The rate at `now_s`: events in the window over the window's length (or over the time since
  // the first event, when that is shorter); 0 before the first event.
  double rateHz(double now_s);
  // Events in the window at `now_s`.
  int events(double now_s);

 private:
  void forget(double now_s);
  double window_s_;
  std::deque<double> ticks_s_;
  double first_s_ = -1;
};

// A diagnostic task: the rate of an event (frames in, poses out) with its expected range;
// OK inside it, WARN outside or when nothing came in the window. Thread-safe.
class RateDiagnostic : public diagnostic_updater::DiagnosticTask {
 public:
  RateDiagnostic(const std::string& name, double min_hz, double max_hz, double window_s = 5.0)
      : DiagnosticTask(name), min_hz_(min_hz), max_hz_(max_hz), window_(window_s) {}
  void tick();
  void run(diagnostic_updater::DiagnosticStatusWrapper& status) override;

 private:
  double min_hz_, max_hz_;
  std::mutex mutex_;
  RateWindow window_;
};

// Steady seconds since an arbitrary start.
double steadySeconds();

}  // namespace kneed_walker::ros_glue
