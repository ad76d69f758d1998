// The Kneed Walker's kinematic and inertial parameters (paper §3, Fig. 1): the constant
// model, kept apart from the per-particle state (walker_dynamics.h) as in MuJoCo's
// mjModel / mjData split.
//
// Units are consistent but not fixed: SI (m, kg, s) for a model scaled to a person, or
// McGeer's dimensionless units (leg length 1, body mass 1, g 1) for mcGeerPassiveWalker().
// Angles are in radians.
#pragma once

#include <string>
#include <vector>

#include "kneed_walker/core/common/config_file.h"

namespace kneed_walker::core::dynamics {

// One rigid segment of the planar walker.
struct Segment {
  double mass = 0;                // kg
  double length = 0;              // proximal joint to distal end, m (shank: knee to sole)
  double com_along = 0;           // centre of mass from the proximal joint along the axis, m
  double com_forward = 0;         // centre of mass offset along the forward normal, m
  double radius_of_gyration = 0;  // about the centre of mass, m
  double inertia() const { return mass * radius_of_gyration * radius_of_gyration; }  // kg·m²
};

// The whole walker. The torso points up from the hip (com_along measured upwards); thighs
// and shanks hang from hip and knee. The shank includes the foot: an arc of radius
// foot_radius whose centre lies (shank.length − foot_radius) from the knee, on the shank
// axis turned by foot_offset_angle (positive: foot centre ahead of the shank axis).
struct WalkerModel {
  double gravity = 9.81;  // m/s²
  Segment torso;
  Segment thigh;
  Segment shank;
  double foot_radius = 0;        // R, m
  double foot_offset_angle = 0;  // e, rad

  double legLength() const { return thigh.length + shank.length; }        // L, m
  double totalMass() const { return torso.mass + 2 * (thigh.mass + shank.mass); }  // kg
};

// Body proportions as fractions, from which a model is scaled to a person's height and
// mass. Defaults: McGeer's kneed walker ("Passive walking with knees", ICRA 1990) for the
// legs, in units of leg length L and body mass; a torso from Dempster's HAT segment
// (Winter's table) above it; leg length from Drillis & Contini (L = 0.530 H). See
// ../shared/reference/walker-model.md §1 and config/walker_model.yaml.
struct BodyProportions {
  double leg_length_per_height = 0.530;  // L / H (greater trochanter height)
  // Segments: mass / body mass; lengths / L.
  Segment torso{0.676, 0.55, 0.34, 0.0, 0.27};
  Segment thigh{0.100, 0.46, 0.20, 0.00, 0.135};
  // The shank's centre of mass 0.24 along the untilted axis and 0.01 ahead: McGeer's figures
  // read in the untilted frame, the geometry the shipped gait tables were optimised for.
  // McGeer's own frame is turned by e (mcGeerProportions); moving the person to it means
  // regenerating both gait tables (issue 13).
  Segment shank{0.062, 0.54, 0.24, 0.01, 0.186};
  double foot_radius = 0.2;        // R / L
  double foot_offset_angle = 0.2;  // e, rad
};

// Every problem with the proportions (non-positive masses and lengths, masses that do not
// add up to 1, a foot larger than the shank, ...), each naming the field.
std::vector<std::string> validate(const BodyProportions& proportions);

// Reads proportions from a YAML file such as config/walker_model.yaml. Keys not given keep
// their defaults; unknown keys, wrong types and invalid values throw std::invalid_argument
// naming them all.
BodyProportions loadBodyProportions(const std::string& path);

// The same keys read from, and written into, a part of another file (the gait tables record
// the proportions they were optimised for).
BodyProportions readBodyProportions(common::ConfigNode& node);
void writeBodyProportions(cv::FileStorage& file, const BodyProportions& proportions);

// The fields in which two sets of proportions differ ("torso.mass 0.676 vs 0.7"); empty when
// they are the same.
std::vector<std::string> differences(const BodyProportions& a, const BodyProportions& b);

// A walker for a person of the given standing height (m) and mass (kg), SI units.
WalkerModel scaleToPerson(const BodyProportions& proportions, double height_m, double mass_kg,
                          double gravity = 9.81);

// McGeer's passive kneed walker's proportions: the defaults with the torso reduced to his
// hip mass (centre of mass at the hip, com_along = 0), so that it no longer couples to the
// legs, and his shank's centre of mass (0.24 along the shank frame turned by e, 0.01 behind
// it: 0.2372 along and 0.0379 ahead of the untilted axis). It walks passively down a
// 0.0456 rad slope in the stable cycle of his Table 1.
BodyProportions mcGeerProportions();

// A walker with these proportions in dimensionless units (leg length 1, body mass 1, g = 1),
// the units of the gait optimisation (paper §3.3) and of McGeer's walkers.
WalkerModel dimensionlessWalker(const BodyProportions& proportions);

// McGeer's passive kneed walker in dimensionless units.
WalkerModel mcGeerPassiveWalker();

}  // namespace kneed_walker::core::dynamics
