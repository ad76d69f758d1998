// Opening a YAML file with OpenCV's FileStorage for the core's loaders (private to the core).
#pragma once

#include <opencv2/core.hpp>

#include <stdexcept>
#include <string>

namespace kneed_walker {

// Opens `path` for reading; throws std::invalid_argument saying which `what` (e.g. "gait
// table") could not be read and why.
inline cv::FileStorage readFileStorage(const std::string& path, const std::string& what) {
  cv::FileStorage file;
  try {
    file.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    throw std::invalid_argument(path + ": not a readable " + what + ": " + e.what());
  }
  if (!file.isOpened()) throw std::invalid_argument(path + ": cannot open the " + what);
  return file;
}

}  // namespace kneed_walker
