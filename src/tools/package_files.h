// Where the tools find the package's own files (config/*.yaml), from any working directory:
// the package's source directory, fixed at build time (the catkin workspace links it).
#pragma once

#include <string>

namespace kneed_walker::tools {

inline std::string packageFile(const std::string& relative_path) {
  return std::string(KNEED_WALKER_PACKAGE_DIR) + "/" + relative_path;
}

}  // namespace kneed_walker::tools
