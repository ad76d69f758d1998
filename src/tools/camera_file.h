// A tool's calibration file: loaded, with the warning of a rounded rotation on stderr.
#pragma once

#include <cstdio>
#include <string>

#include "kneed_walker/core/vision/camera.h"

namespace kneed_walker::tools {

inline core::vision::Camera loadCamera(const char* tool, const std::string& path, double file_length_unit_m) {
  std::string warning;
  core::vision::Camera camera = core::vision::Camera::load(path, file_length_unit_m, &warning);
  if (!warning.empty()) std::fprintf(stderr, "%s: warning: %s\n", tool, warning.c_str());
  return camera;
}

}  // namespace kneed_walker::tools
