// A long run's progress on standard error, as command-line tools show it: on a terminal a bar
// redrawn in place; in a log (standard error not a terminal) a line every tenth of the work or
// every 10 s, whichever comes first, and the last, so that a log holds a few lines, not one a
// frame.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>

namespace kneed_walker::tools {

class ProgressReport {
 public:
  explicit ProgressReport(bool terminal = isatty(STDERR_FILENO) != 0, double line_interval_s = 10.0,
                          double line_fraction = 0.1)
      : terminal_(terminal), line_interval_s_(line_interval_s), line_fraction_(line_fraction) {}

  // `done` of `total` units; `text` follows the bar.
  void update(int done, int total, const std::string& text) {
    constexpr int kWidth = 30;
    const int filled = total > 0 ? std::min(kWidth, std::max(0, kWidth * done / total)) : kWidth;
    const std::string line = "[" + std::string(filled, '#') + std::string(kWidth - filled, '-') + "] " +
                             std::to_string(done) + "/" + std::to_string(total) + " " + text;
    if (terminal_) {
      std::fprintf(stderr, "\r%s        ", line.c_str());
      drawn_ = true;
      return;
    }
    const auto now = std::chrono::steady_clock::now();
    const bool first = last_done_ < 0, last = done >= total;
    const bool step = total > 0 && done - last_done_ >= line_fraction_ * total;
    const bool late = std::chrono::duration<double>(now - last_line_).count() >= line_interval_s_;
    if (!(first || last || step || late) || done == last_done_) return;
    std::fprintf(stderr, "%s\n", line.c_str());
    last_done_ = done;
    last_line_ = now;
  }
  // Ends the bar's line on a terminal.
  void finish() {
    if (terminal_ && drawn_) std::fprintf(stderr, "\n");
    drawn_ = false;
  }

 private:
  bool terminal_;
  double line_interval_s_, line_fraction_;
  int last_done_ = -1;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_line_{};
};

}  // namespace kneed_walker::tools
