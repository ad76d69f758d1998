#include "kneed_walker/core/common/config_file.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace kneed_walker::core::common {

struct ConfigNode::Shared {
  std::string file_path, what;
  std::vector<std::string> problems;
  std::set<std::string> read;        // full names of the keys read (maps and sequences too)
  std::set<std::string> containers;  // of those, the maps and sequences of maps read into
};

ConfigNode::ConfigNode(std::shared_ptr<Shared> shared, cv::FileNode node, std::string path)
    : shared_(std::move(shared)), node_(node), path_(std::move(path)) {}

std::string ConfigNode::name(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

void ConfigNode::problem(const std::string& key, const std::string& message) {
  shared_->problems.push_back(name(key) + " " + message);
}

cv::FileNode ConfigNode::find(const std::string& key, Need need) {
  if (node_.empty()) return cv::FileNode();
  if (!shared_->read.insert(name(key)).second) {
    problem(key, "is read twice (a program error)");
    return cv::FileNode();
  }
  cv::FileNode node = node_[key];
  if (node.empty() && need == Need::kRequired) problem(key, "is missing");
  return node;
}

bool ConfigNode::read(const std::string& key, double& value, Need need, bool allow_infinite) {
  const cv::FileNode node = find(key, need);
  if (node.empty()) return false;
  if (!node.isReal() && !node.isInt()) {
    problem(key, "must be a number");
    return false;
  }
  const double v = static_cast<double>(node);
  if (std::isnan(v) || (!allow_infinite && std::isinf(v))) {
    problem(key, "must be finite");
    return false;
  }
  value = v;
  return true;
}

bool ConfigNode::read(const std::string& key, int& value, Need need) {
  const cv::FileNode node = find(key, need);
  if (node.empty()) return false;
  if (!node.isInt()) {
    problem(key, "must be an integer");
    return false;
  }
  value = static_cast<int>(node);
  return true;
}

bool ConfigNode::read(const std::string& key, bool& value, Need need) {
  const cv::FileNode node = find(key, need);
  if (node.empty()) return false;
  if (!node.isInt() || (static_cast<int>(node) != 0 && static_cast<int>(node) != 1)) {
    problem(key, "must be 0 or 1");
    return false;
  }
  value = static_cast<int>(node) != 0;
  return true;
}

bool ConfigNode::read(const std::string& key, std::string& value, Need need) {
  const cv::FileNode node = find(key, need);
  if (node.empty()) return false;
  if (!node.isString()) {
    problem(key, "must be a string");
    return false;
  }
  value = static_cast<std::string>(node);
  return true;
}

bool ConfigNode::read(const std::string& key, std::vector<double>& values, Need need, int size) {
  const cv::FileNode node = find(key, need);
  if (node.empty()) return false;
  std::vector<double> v;
  bool numbers = node.isSeq();
  for (auto it = node.begin(); numbers && it != node.end(); ++it) {
    numbers = (*it).isReal() || (*it).isInt();
    if (numbers) v.push_back(static_cast<double>(*it));
  }
  if (!numbers || (size >= 0 && static_cast<int>(v.size()) != size)) {
    problem(key, size >= 0 ? "must list " + std::to_string(size) + " numbers"
                           : "must be a list of numbers");
    return false;
  }
  for (double x : v)
    if (!std::isfinite(x)) {
      problem(key, "must hold finite numbers");
      return false;
    }
  values = std::move(v);
  return true;
}

bool ConfigNode::read(const std::string& key, cv::Mat& matrix, Need need) {
  const cv::FileNode node = find(key, need);
  if (node.empty()) return false;
  cv::Mat m;
  try {
    node >> m;
  } catch (const cv::Exception&) {
    m.release();
  }
  if (m.empty() || m.channels() != 1) {
    problem(key, "must be a matrix (!!opencv-matrix)");
    return false;
  }
  m.convertTo(m, CV_64F);
  if (!cv::checkRange(m)) {
    problem(key, "must hold finite numbers");
    return false;
  }
  matrix = m;
  return true;
}

ConfigNode ConfigNode::map(const std::string& key, Need need) {
  const cv::FileNode node = find(key, need);
  if (!node.empty() && !node.isMap()) {
    problem(key, "must be a map");
    return ConfigNode(shared_, cv::FileNode(), name(key));
  }
  shared_->containers.insert(name(key));
  return ConfigNode(shared_, node, name(key));
}

std::vector<ConfigNode> ConfigNode::maps(const std::string& key, Need need) {
  const cv::FileNode node = find(key, need);
  std::vector<ConfigNode> result;
  if (node.empty()) return result;
  if (!node.isSeq()) {
    problem(key, "must be a list of maps");
    return result;
  }
  shared_->containers.insert(name(key));
  for (int i = 0; i < static_cast<int>(node.size()); ++i) {
    const std::string item = name(key) + "[" + std::to_string(i) + "]";
    shared_->read.insert(item);
    shared_->containers.insert(item);
    if (!node[i].isMap()) {
      shared_->problems.push_back(item + " must be a map");
      result.push_back(ConfigNode(shared_, cv::FileNode(), item));
    } else {
      result.push_back(ConfigNode(shared_, node[i], item));
    }
  }
  return result;
}

ConfigFile::ConfigFile(const std::string& path, const std::string& what)
    : ConfigNode(std::make_shared<Shared>(), cv::FileNode(), "") {
  shared_->file_path = path;
  shared_->what = what;
  // OpenCV's YAML reader needs the "%YAML:1.0" directive, which other programs' YAML (ROS's
  // camera_info files) leaves out: such a file is read with the directive put before it.
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot open the " + what);
  std::ostringstream text;
  text << in.rdbuf();
  const bool yaml_directive = text.str().rfind("%YAML", 0) == 0;
  const bool yaml_name = path.size() >= 5 && (path.substr(path.size() - 5) == ".yaml" || path.substr(path.size() - 4) == ".yml");
  try {
    if (!yaml_directive && yaml_name)
      storage_.open("%YAML:1.0\n" + text.str(), cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
    else
      storage_.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    throw std::invalid_argument(path + ": not a readable " + what + ": " + e.what());
  }
  if (!storage_.isOpened()) throw std::invalid_argument(path + ": cannot open the " + what);
  node_ = storage_.root();
  if (!node_.isMap()) throw std::invalid_argument(path + ": not a readable " + what + ": not a YAML map");
}

ConfigFile::~ConfigFile() = default;

namespace {

// Every key below `node` (at `path`) that was not read, into `unknown`.
void collectUnread(const cv::FileNode& node, const std::string& path,
                   const std::set<std::string>& read, const std::set<std::string>& containers,
                   std::vector<std::string>& unknown) {
  if (node.isMap()) {
    for (auto it = node.begin(); it != node.end(); ++it) {
      const std::string full = path.empty() ? (*it).name() : path + "." + (*it).name();
      if (!read.count(full))
        unknown.push_back(full + " is not a known key");
      else if (containers.count(full))
        collectUnread(*it, full, read, containers, unknown);
    }
  } else if (node.isSeq()) {
    for (int i = 0; i < static_cast<int>(node.size()); ++i) {
      const std::string item = path + "[" + std::to_string(i) + "]";
      if (containers.count(item)) collectUnread(node[i], item, read, containers, unknown);
    }
  }
}

}  // namespace

void ConfigFile::finish(const std::vector<std::string>& more, bool allow_other_keys) {
  std::vector<std::string> problems = shared_->problems;
  if (!allow_other_keys) collectUnread(storage_.root(), "", shared_->read, shared_->containers, problems);
  problems.insert(problems.end(), more.begin(), more.end());
  throwIfProblems(shared_->file_path, shared_->what, problems);
}

void throwIfInvalid(const std::string& context, const std::vector<std::string>& problems) {
  if (problems.empty()) return;
  std::string message = context + ":";
  for (size_t i = 0; i < problems.size(); ++i) message += (i ? "; " : " ") + problems[i];
  throw std::invalid_argument(message);
}

void throwIfProblems(const std::string& path, const std::string& what,
                     const std::vector<std::string>& problems) {
  if (problems.empty()) return;
  std::ostringstream message;
  message << path << ": invalid " << what << ":";
  for (const auto& problem : problems) message << "\n  " << problem;
  throw std::invalid_argument(message.str());
}

}  // namespace kneed_walker::core::common
