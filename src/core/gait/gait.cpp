#include "kneed_walker/core/gait/gait.h"

namespace kneed_walker::core::gait {
namespace {

// The one place that ties each entry of the control vector to its field.
double& field(dynamics::WalkerControls& c, int control) {
  dynamics::SpringParameters& s = c.springs;
  switch (control) {
    case kStanceKneeStiffness: return s.stance_knee_stiffness;
    case kStanceKneeDamping: return s.stance_knee_damping;
    case kSwingKneeStiffness: return s.swing_knee_stiffness;
    case kSwingKneeRestAngle: return s.swing_knee_rest_angle;
    case kSwingKneeDamping: return s.swing_knee_damping;
    case kHipStiffness: return s.hip_stiffness;
    case kTorsoStiffness: return s.torso_stiffness;
    case kTorsoRestAngle: return s.torso_rest_angle;
    case kTorsoDamping: return s.torso_damping;
    default: return c.toe_off_impulse;
  }
}

}  // namespace

bool FixedControls::operator==(const FixedControls& o) const {
  return knee_damping == o.knee_damping && torso_rest_per_slope == o.torso_rest_per_slope &&
         torso_damping == o.torso_damping;
}

const char* controlName(Control control) {
  static const char* const kNames[kNumControls] = {
      "stance_knee_stiffness", "stance_knee_damping", "swing_knee_stiffness",
      "swing_knee_rest_angle", "swing_knee_damping",  "hip_stiffness",
      "torso_stiffness",       "torso_rest_angle",    "torso_damping",
      "toe_off_impulse"};
  return kNames[control];
}

ControlVector toControlVector(const dynamics::WalkerControls& controls) {
  dynamics::WalkerControls c = controls;
  ControlVector v;
  for (int i = 0; i < kNumControls; ++i) v[i] = field(c, i);
  return v;
}

dynamics::WalkerControls fromControlVector(const ControlVector& vector, double slope) {
  dynamics::WalkerControls c;
  for (int i = 0; i < kNumControls; ++i) field(c, i) = vector[i];
  c.ground_slope = slope;
  return c;
}

bool isFixed(Control control) {
  switch (control) {
    case kStanceKneeDamping:
    case kSwingKneeDamping:
    case kSwingKneeRestAngle:
    case kTorsoRestAngle:
    case kTorsoDamping:
      return true;
    default:
      return false;
  }
}

dynamics::WalkerControls withFixedControls(dynamics::WalkerControls c, const FixedControls& fixed) {
  c.springs.stance_knee_damping = fixed.knee_damping;
  c.springs.swing_knee_damping = fixed.knee_damping;
  c.springs.swing_knee_rest_angle = 0.0;
  c.springs.torso_rest_angle = fixed.torso_rest_per_slope * c.ground_slope;
  c.springs.torso_damping = fixed.torso_damping;
  return c;
}

}  // namespace kneed_walker::core::gait
