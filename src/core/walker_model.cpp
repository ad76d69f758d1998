#include "kneed_walker/core/walker_model.h"

#include <opencv2/core.hpp>

#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

#include "read_file_storage.h"

namespace kneed_walker {
namespace {

void checkSegment(std::vector<std::string>& problems, const std::string& name, const Segment& s) {
  auto positive = [&](const char* field, double v) {
    if (!(std::isfinite(v) && v > 0))
      problems.push_back(name + "." + field + " = " + std::to_string(v) + " must be > 0");
  };
  positive("mass", s.mass);
  positive("length", s.length);
  positive("radius_of_gyration", s.radius_of_gyration);
  if (!(std::isfinite(s.com_along) && s.com_along >= 0 && s.com_along <= s.length))
    problems.push_back(name + ".com_along = " + std::to_string(s.com_along) +
                       " must lie in [0, length]");
  if (!(std::isfinite(s.com_forward) && std::abs(s.com_forward) <= s.length))
    problems.push_back(name + ".com_forward = " + std::to_string(s.com_forward) +
                       " must be finite and at most the segment length in size");
}

Segment scaled(const Segment& fraction, double length_scale, double mass_scale) {
  return Segment{fraction.mass * mass_scale, fraction.length * length_scale,
                 fraction.com_along * length_scale, fraction.com_forward * length_scale,
                 fraction.radius_of_gyration * length_scale};
}

// Proportions times a leg length and a body mass, in whatever units those are given.
WalkerModel scaleProportions(const BodyProportions& p, double leg_length, double mass,
                             double gravity) {
  WalkerModel model;
  model.gravity = gravity;
  model.torso = scaled(p.torso, leg_length, mass);
  model.thigh = scaled(p.thigh, leg_length, mass);
  model.shank = scaled(p.shank, leg_length, mass);
  model.foot_radius = p.foot_radius * leg_length;
  model.foot_offset_angle = p.foot_offset_angle;
  return model;
}

}  // namespace

std::vector<std::string> validate(const BodyProportions& p) {
  std::vector<std::string> problems;
  if (!(std::isfinite(p.leg_length_per_height) && p.leg_length_per_height > 0.3 &&
        p.leg_length_per_height < 0.7))
    problems.push_back("leg_length_per_height = " + std::to_string(p.leg_length_per_height) +
                       " is outside (0.3, 0.7)");
  checkSegment(problems, "torso", p.torso);
  checkSegment(problems, "thigh", p.thigh);
  checkSegment(problems, "shank", p.shank);
  const double mass_sum = p.torso.mass + 2 * (p.thigh.mass + p.shank.mass);
  if (std::abs(mass_sum - 1.0) > 0.01)
    problems.push_back("segment mass fractions add up to " + std::to_string(mass_sum) +
                       " (torso + 2 thighs + 2 shanks), not 1");
  if (std::abs(p.thigh.length + p.shank.length - 1.0) > 0.01)
    problems.push_back("thigh.length + shank.length = " +
                       std::to_string(p.thigh.length + p.shank.length) +
                       " must be 1 (lengths are fractions of leg length)");
  if (!(std::isfinite(p.foot_radius) && p.foot_radius > 0 && p.foot_radius < p.shank.length))
    problems.push_back("foot_radius = " + std::to_string(p.foot_radius) +
                       " must lie in (0, shank.length)");
  if (!(std::isfinite(p.foot_offset_angle) && std::abs(p.foot_offset_angle) < 0.6))
    problems.push_back("foot_offset_angle = " + std::to_string(p.foot_offset_angle) +
                       " must lie in (-0.6, 0.6) rad");
  return problems;
}

BodyProportions loadBodyProportions(const std::string& path) {
  cv::FileStorage file = readFileStorage(path, "body-proportion file");

  BodyProportions p;
  std::vector<std::string> problems;
  auto readNumber = [&](const cv::FileNode& node, const std::string& name, double& value) {
    if (!node.isReal() && !node.isInt()) {
      problems.push_back(name + " must be a number");
      return;
    }
    value = static_cast<double>(node);
  };
  const std::map<std::string, double*> scalars = {
      {"leg_length_per_height", &p.leg_length_per_height},
      {"foot_radius", &p.foot_radius},
      {"foot_offset_angle", &p.foot_offset_angle}};
  const std::map<std::string, Segment*> segments = {
      {"torso", &p.torso}, {"thigh", &p.thigh}, {"shank", &p.shank}};

  const cv::FileNode root = file.root();
  for (auto it = root.begin(); it != root.end(); ++it) {
    const cv::FileNode node = *it;
    const std::string key = node.name();
    if (scalars.count(key)) {
      readNumber(node, key, *scalars.at(key));
    } else if (segments.count(key)) {
      Segment& s = *segments.at(key);
      const std::map<std::string, double*> fields = {
          {"mass", &s.mass}, {"length", &s.length}, {"com_along", &s.com_along},
          {"com_forward", &s.com_forward}, {"radius_of_gyration", &s.radius_of_gyration}};
      if (!node.isMap()) {
        problems.push_back(key + " must be a map of segment fields");
        continue;
      }
      for (auto f = node.begin(); f != node.end(); ++f) {
        const std::string field = (*f).name();
        if (fields.count(field))
          readNumber(*f, key + "." + field, *fields.at(field));
        else
          problems.push_back(key + "." + field + " is not a segment field");
      }
    } else {
      problems.push_back(key + " is not a body-proportion parameter");
    }
  }
  for (const auto& problem : validate(p)) problems.push_back(problem);
  throwIfProblems(path, "body proportions", problems);
  return p;
}

WalkerModel scaleToPerson(const BodyProportions& p, double height_m, double mass_kg,
                          double gravity) {
  if (!(height_m > 0.5 && height_m < 3.0) || !(mass_kg > 5 && mass_kg < 400))
    throw std::invalid_argument("scaleToPerson: height " + std::to_string(height_m) +
                                " m or mass " + std::to_string(mass_kg) +
                                " kg is not a person's");
  const auto problems = validate(p);
  if (!problems.empty()) throw std::invalid_argument("scaleToPerson: " + problems.front());
  return scaleProportions(p, p.leg_length_per_height * height_m, mass_kg, gravity);
}

BodyProportions mcGeerProportions() {
  BodyProportions p;
  p.torso.com_along = 0.0;  // the torso becomes McGeer's hip point mass
  return p;
}

WalkerModel dimensionlessWalker(const BodyProportions& proportions) {
  const auto problems = validate(proportions);
  if (!problems.empty()) throw std::invalid_argument("dimensionlessWalker: " + problems.front());
  return scaleProportions(proportions, 1.0, 1.0, 1.0);
}

WalkerModel mcGeerPassiveWalker() { return dimensionlessWalker(mcGeerProportions()); }

}  // namespace kneed_walker
