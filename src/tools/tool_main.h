// One way for a tool's main to end: an exception from the tool's work becomes one line
// "<tool>: <message>" on stderr and exit status 1, never an abort.
#pragma once

#include <cstdio>
#include <exception>

namespace kneed_walker::tools {

inline int runTool(const char* name, int (*run)(int, char**), int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return 1;
  }
}

}  // namespace kneed_walker::tools
