// Opening a YAML file with OpenCV's FileStorage for the core's loaders, and reporting what is
// wrong in it (private to the core).
#pragma once

#include <opencv2/core.hpp>

#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

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

// Throws std::invalid_argument "<path>: invalid <what>:" with one problem per line, if any.
inline void throwIfProblems(const std::string& path, const std::string& what,
                            const std::vector<std::string>& problems) {
  if (problems.empty()) return;
  std::ostringstream message;
  message << path << ": invalid " << what << ":";
  for (const auto& problem : problems) message << "\n  " << problem;
  throw std::invalid_argument(message.str());
}

}  // namespace kneed_walker
