// A periodic gait in the form the runtime uses (paper §3.3–3.4): the controls and the start of
// one periodic stride, which the prior walks around. The optimiser (optimizer/optimal_gaits.h)
// makes them; the gait table (gait_table.h) stores and interpolates them. Dimensionless units:
// leg length 1, body mass 1, g 1, time √(L/g).
#pragma once

#include <array>

#include "kneed_walker/core/dynamics/walker_simulation.h"

namespace kneed_walker::core::gait {

// What a gait must achieve: speed v/√(gL), step length ℓ/L, slope γ (rad, positive uphill).
struct GaitTarget {
  double speed = 0;
  double step_length = 0;
  double slope = 0;
};

struct Gait {
  GaitTarget target;
  dynamics::WalkerControls controls;  // θ, ι and γ (no torque offsets)
  dynamics::WalkerState start;        // post-heel-strike state x0 of the periodic stride
  double stride_duration = 0;         // of the periodic stride, natural time units
};

// The controls that the prior holds fixed (paper §3.4): knee dampings dK1 = dK2, the torso's
// rest angle φ⁰To = torso_rest_per_slope × γ and its damping dTo; the swing knee's rest angle is
// held at 0 (straight). Gaits optimised with them held are the ones the prior can follow
// (config/prior_gait_table.yaml).
//
// The paper also holds the swing knee's stiffness κK2 at 0. In our units that leaves the prior no
// brisk walk: with κK2 = 0 the optimiser closes no level cycle at 5–7 km/h below 0.9 m steps
// (105 of the paper's 270 grid points in all), and most free optima there stiffen the swing knee
// (16 of 20 at 0.5–0.8 m: κK2 of 1.4–5 M g L/rad), which straightens the leg in time for a short,
// quick step. So the prior's table optimises κK2 at each grid point (204 of the 270).
//
// The paper's φ⁰To = γ/3 is a lean of γ/3 into the slope from the vertical ("a slight lean of
// the torso into the slope", its Fig. 5; forward uphill, back downhill, §3.3); walker angles
// are measured from the slope's normal, counter-clockwise (an upright torso is at −γ, a forward
// lean negative), so that is φ⁰To = −γ − γ/3 = −4γ/3. Read as +γ/3 in the walker's frame, the
// torso leaned back 4γ/3 = 5.7° from the vertical on a 4.3° climb (evaluate's torso_lean_deg on
// the uphill walk).
struct FixedControls {
  double knee_damping = 0.05;
  double torso_rest_per_slope = -4.0 / 3;
  double torso_damping = 1.5;
  bool operator==(const FixedControls& other) const;
  bool operator!=(const FixedControls& other) const { return !(*this == other); }
};

// The spring parameters θ (eqs. 1–3) and the toe-off impulse ι as one flat vector, in the one
// order that the gait table files and the optimiser's variables use.
enum Control : int {
  kStanceKneeStiffness = 0,
  kStanceKneeDamping,
  kSwingKneeStiffness,
  kSwingKneeRestAngle,
  kSwingKneeDamping,
  kHipStiffness,
  kTorsoStiffness,
  kTorsoRestAngle,
  kTorsoDamping,
  kToeOffImpulse,
  kNumControls
};
using ControlVector = std::array<double, kNumControls>;
const char* controlName(Control control);  // "stance_knee_stiffness", ...
ControlVector toControlVector(const dynamics::WalkerControls& controls);
// Controls from the vector, on a slope γ, with no torque offsets.
dynamics::WalkerControls fromControlVector(const ControlVector& vector, double slope);

// Whether a control is one of the fixed ones (set by withFixedControls).
bool isFixed(Control control);

// The controls with the fixed ones held at their values for the gait's slope.
dynamics::WalkerControls withFixedControls(dynamics::WalkerControls controls,
                                           const FixedControls& fixed);

}  // namespace kneed_walker::core::gait
