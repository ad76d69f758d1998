// The one reader of the package's YAML files (config/*.yaml, gait tables, calibrations), over
// OpenCV's FileStorage: typed reads of named keys, every problem collected and reported at
// once, naming the file and the key, and keys that nobody reads refused as unknown (a typo).
//
//   ConfigFile file(path, "prior parameters");
//   file.read("knee_damping", options.knee_damping);       // optional: absent keeps the default
//   file.read("noise_decay", options.noise_decay);          // a list of exactly N numbers
//   ConfigNode torso = file.map("torso");                   // a nested map: keys "torso.mass", ...
//   file.finish(validate(options));                         // throws std::invalid_argument
//
// Numbers must be finite. A key read twice, or a required key that is missing, is a problem.
#pragma once

#include <opencv2/core.hpp>

#include <array>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace kneed_walker::core::common {

enum class Need { kOptional, kRequired };

class ConfigNode {
 public:
  // Reads a number (finite), an integer, a flag (0 or 1), a string, a list of numbers of any
  // length (or exactly `size`), a list of exactly N numbers, a matrix (!!opencv-matrix).
  // Returns whether the key was present and read without problem.
  bool read(const std::string& key, double& value, Need need = Need::kOptional,
            bool allow_infinite = false);  // ±inf only where it means something (a residual)
  bool read(const std::string& key, int& value, Need need = Need::kOptional);
  bool read(const std::string& key, bool& value, Need need = Need::kOptional);
  bool read(const std::string& key, std::string& value, Need need = Need::kOptional);
  bool read(const std::string& key, std::vector<double>& values, Need need = Need::kOptional,
            int size = -1);
  template <std::size_t N>
  bool read(const std::string& key, std::array<double, N>& values, Need need = Need::kOptional) {
    std::vector<double> v;
    if (!read(key, v, need, static_cast<int>(N))) return false;
    for (std::size_t i = 0; i < N; ++i) values[i] = v[i];
    return true;
  }
  bool read(const std::string& key, cv::Mat& matrix, Need need = Need::kOptional);

  // A nested map (its keys are reported as "key.field"); an empty node when absent or wrong.
  ConfigNode map(const std::string& key, Need need = Need::kOptional);
  // A sequence of maps (reported as "key[i].field").
  std::vector<ConfigNode> maps(const std::string& key, Need need = Need::kOptional);

  // Records a problem with a key of this node (e.g. a value out of range).
  void problem(const std::string& key, const std::string& message);
  // The full name of a key of this node, as problems report it.
  std::string name(const std::string& key) const;

 protected:
  struct Shared;
  ConfigNode(std::shared_ptr<Shared> shared, cv::FileNode node, std::string path);
  cv::FileNode find(const std::string& key, Need need);

  std::shared_ptr<Shared> shared_;
  cv::FileNode node_;
  std::string path_;  // "" for the root, "torso", "gaits[3]", ...
};

class ConfigFile : public ConfigNode {
 public:
  // Opens `path`; `what` names its kind in messages ("gait table"). Throws
  // std::invalid_argument when the file cannot be read as YAML.
  ConfigFile(const std::string& path, const std::string& what);
  ~ConfigFile();

  // Throws std::invalid_argument "<path>: invalid <what>:" listing every problem (one per line):
  // those recorded, `more` (e.g. from validate()), and, unless `allow_other_keys`, every key
  // that was not read.
  void finish(const std::vector<std::string>& more = {}, bool allow_other_keys = false);

 private:
  cv::FileStorage storage_;
};

// Throws std::invalid_argument "<context>: <problem>; <problem>; ..." naming every problem, if
// any (for options checked by a validate() function).
void throwIfInvalid(const std::string& context, const std::vector<std::string>& problems);

// Throws std::invalid_argument "<path>: invalid <what>:" with one problem per line, if any.
void throwIfProblems(const std::string& path, const std::string& what,
                     const std::vector<std::string>& problems);

}  // namespace kneed_walker::core::common
