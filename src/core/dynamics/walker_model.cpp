#include "kneed_walker/core/dynamics/walker_model.h"

#include <opencv2/core.hpp>

#include <cmath>
#include <tuple>
#include <sstream>
#include <stdexcept>


namespace kneed_walker::core::dynamics {
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

namespace {

// The segment fields, by their names in the files.
const std::pair<const char*, double Segment::*> kSegmentFields[] = {
    {"mass", &Segment::mass},
    {"length", &Segment::length},
    {"com_along", &Segment::com_along},
    {"com_forward", &Segment::com_forward},
    {"radius_of_gyration", &Segment::radius_of_gyration}};

}  // namespace

BodyProportions readBodyProportions(common::ConfigNode& node) {
  BodyProportions p;
  node.read("leg_length_per_height", p.leg_length_per_height);
  node.read("foot_radius", p.foot_radius);
  node.read("foot_offset_angle", p.foot_offset_angle);
  for (auto [name, segment] : {std::pair<const char*, Segment*>{"torso", &p.torso},
                               {"thigh", &p.thigh}, {"shank", &p.shank}}) {
    common::ConfigNode fields = node.map(name);
    for (const auto& [field, member] : kSegmentFields) fields.read(field, segment->*member);
  }
  return p;
}

void writeBodyProportions(cv::FileStorage& file, const BodyProportions& p) {
  file << "leg_length_per_height" << p.leg_length_per_height;
  for (auto [name, segment] : {std::pair<const char*, const Segment*>{"torso", &p.torso},
                               {"thigh", &p.thigh}, {"shank", &p.shank}}) {
    file << name << "{";
    for (const auto& [field, member] : kSegmentFields) file << field << segment->*member;
    file << "}";
  }
  file << "foot_radius" << p.foot_radius << "foot_offset_angle" << p.foot_offset_angle;
}

std::vector<std::string> differences(const BodyProportions& a, const BodyProportions& b) {
  std::vector<std::string> fields;
  auto compare = [&](const std::string& name, double x, double y) {
    if (x != y) fields.push_back(name + " " + std::to_string(x) + " vs " + std::to_string(y));
  };
  compare("leg_length_per_height", a.leg_length_per_height, b.leg_length_per_height);
  for (auto [name, x, y] : {std::tuple<const char*, const Segment*, const Segment*>{"torso", &a.torso, &b.torso},
                            {"thigh", &a.thigh, &b.thigh}, {"shank", &a.shank, &b.shank}})
    for (const auto& [field, member] : kSegmentFields)
      compare(std::string(name) + "." + field, x->*member, y->*member);
  compare("foot_radius", a.foot_radius, b.foot_radius);
  compare("foot_offset_angle", a.foot_offset_angle, b.foot_offset_angle);
  return fields;
}

BodyProportions loadBodyProportions(const std::string& path) {
  common::ConfigFile file(path, "body proportions");
  const BodyProportions p = readBodyProportions(file);
  file.finish(validate(p));
  return p;
}

WalkerModel scaleToPerson(const BodyProportions& p, double height_m, double mass_kg,
                          double gravity) {
  if (!(height_m > 0.5 && height_m < 3.0) || !(mass_kg > 5 && mass_kg < 400))
    throw std::invalid_argument("scaleToPerson: height " + std::to_string(height_m) +
                                " m or mass " + std::to_string(mass_kg) +
                                " kg is not a person's");
  const auto problems = validate(p);
  common::throwIfInvalid("scaleToPerson", problems);
  return scaleProportions(p, p.leg_length_per_height * height_m, mass_kg, gravity);
}

BodyProportions mcGeerProportions() {
  BodyProportions p;
  p.torso.com_along = 0.0;  // the torso becomes McGeer's hip point mass
  // McGeer turns the shank's whole frame by e, its centre of mass as well as the foot centre,
  // and puts the centre of mass c = 0.24 along the turned axis u and w = 0.01 behind it
  // (../shared/reference/walker-model.md, "The shank's frame"). With d(φ + e) = cos e d(φ) +
  // sin e n(φ) and n(φ + e) = cos e n(φ) − sin e d(φ), c u − w n(u) is, on the untilted
  // axis of this model's convention, (c cos e + w sin e) along and (c sin e − w cos e) ahead:
  // 0.2372 and 0.0379. Only with this frame is his cycle stable (Table 1).
  constexpr double kAlongTurnedAxis = 0.24, kBehindTurnedAxis = 0.01;
  const double e = p.foot_offset_angle;
  p.shank.com_along = kAlongTurnedAxis * std::cos(e) + kBehindTurnedAxis * std::sin(e);
  p.shank.com_forward = kAlongTurnedAxis * std::sin(e) - kBehindTurnedAxis * std::cos(e);
  return p;
}

WalkerModel dimensionlessWalker(const BodyProportions& proportions) {
  const auto problems = validate(proportions);
  common::throwIfInvalid("dimensionlessWalker", problems);
  return scaleProportions(proportions, 1.0, 1.0, 1.0);
}

WalkerModel mcGeerPassiveWalker() { return dimensionlessWalker(mcGeerProportions()); }

}  // namespace kneed_walker::core::dynamics
