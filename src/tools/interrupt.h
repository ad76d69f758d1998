// SIGINT and SIGTERM noted instead of ending the process at once: a tool that calls
// stopOnSignals() checks stopSignal() between frames, finishes the one it is on, writes whole
// outputs for what it did, says so, and exits with 128 + the signal (130, 143), as a shell
// reports a process a signal ended.
#pragma once

#include <csignal>

namespace kneed_walker::tools {

// The signal that asked the tool to stop, or 0.
inline volatile std::sig_atomic_t& stopSignal() {
  static volatile std::sig_atomic_t signal = 0;
  return signal;
}

inline void stopOnSignals() {
  std::signal(SIGINT, [](int signal) { stopSignal() = signal; });
  std::signal(SIGTERM, [](int signal) { stopSignal() = signal; });
}

inline const char* stopSignalName(int signal) { return signal == SIGINT ? "interrupted (SIGINT)" : "terminated (SIGTERM)"; }

}  // namespace kneed_walker::tools
