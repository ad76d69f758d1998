// The table of optimal gaits over the paper's grid (§3.3): speeds 3–7 km/h, step lengths
// 0.5–1.0 m, slopes −4.3°…+4.3°, for a reference person; the prior's backbone. The table is
// computed once by `rosrun kneed_walker optimize_gaits` and shipped in config/, so users never
// run the optimiser. Gaits are stored in dimensionless units and scale to any person by Froude
// similarity (speed ∝ √(gL), step length ∝ L).
#pragma once

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "kneed_walker/core/dynamics/walker_model.h"
#include "kneed_walker/core/gait/gait.h"

namespace kneed_walker::core::gait {

struct GaitGrid {
  double reference_height_m = 1.75;     // the person the physical axes refer to
  double leg_length_per_height = 0.53;  // L / H of the walker model (GaitTable::body's)
  double gravity = 9.81;                // m/s²
  std::vector<double> speeds_kmh;       // ascending
  std::vector<double> step_lengths_m;   // ascending
  std::vector<double> slopes_rad;       // ascending, positive uphill

  // 9 speeds × 6 step lengths × 5 slopes, as in the paper.
  static GaitGrid paper();

  int size() const {
    return static_cast<int>(speeds_kmh.size() * step_lengths_m.size() * slopes_rad.size());
  }
  int index(int speed, int step_length, int slope) const {
    return (speed * static_cast<int>(step_lengths_m.size()) + step_length) *
               static_cast<int>(slopes_rad.size()) + slope;
  }
  // Grid coordinates (speed, step length, slope) of an index.
  std::array<int, 3> cell(int index) const;
  double referenceLegLength() const { return leg_length_per_height * reference_height_m; }
  // The dimensionless target of a grid point, and of any physical (km/h, m, rad) triple.
  GaitTarget target(int index) const;
  GaitTarget target(double speed_kmh, double step_length_m, double slope_rad) const;
};

// How an optimised gait met its targets, as the optimiser recorded it (dimensionless).
struct GaitQuality {
  double speed = 0;                 // achieved V/√(gL)
  double step_length = 0;           // achieved ℓ/L
  double effort = 0;                // E of eq. 9
  double periodicity_residual = 0;  // max |S(x0) − x0|
  int solver_status = 0;            // the optimiser's result code (NLopt's)
  int evaluations = 0;              // strides simulated
};

// A grid point's result: `gait` and `quality` are meaningful when `solved`; `feasible` when
// the gait met the constraints of eq. 10.
struct GaitTableEntry {
  bool solved = false;
  bool feasible = false;
  Gait gait;
  GaitQuality quality;
};

// Bounds on the swing that the optimiser held beside eq. 10 (optimizer::GaitOptimizerOptions,
// issue 13): the swing sole's lowest height while it passes the stance foot, leg lengths, and
// the swing knee's largest flexion, rad. Infinite: not bounded.
struct SwingBounds {
  double min_passing_clearance = -std::numeric_limits<double>::infinity();
  double max_swing_knee_flexion = std::numeric_limits<double>::infinity();
  bool operator==(const SwingBounds& other) const {
    return min_passing_clearance == other.min_passing_clearance &&
           max_swing_knee_flexion == other.max_swing_knee_flexion;
  }
  bool operator!=(const SwingBounds& other) const { return !(*this == other); }
};

struct GaitTable {
  GaitGrid grid;
  dynamics::BodyProportions body;      // the walker the gaits were optimised for
  std::optional<FixedControls> fixed;  // controls held while optimising (the prior's table)
  SwingBounds swing_bounds;            // held while optimising
  std::vector<GaitTableEntry> entries;  // grid.size() of them, in grid.index() order
};

void saveGaitTable(const std::string& path, const GaitTable& table);
// Throws std::invalid_argument naming every problem for a missing, malformed or inconsistent
// file, and for a table made for other body proportions than `body` (a table belongs to the
// walker model it was optimised for: config/walker_model.yaml for the shipped ones).
GaitTable loadGaitTable(const std::string& path, const dynamics::BodyProportions& body);

// Folds `other`'s feasible gaits into `table` where they have the lower effort (eq. 9): the
// optimiser finds local optima, and of two runs the lower effort is the better optimum.
// Returns how many grid points were taken from `other`. Throws std::invalid_argument when the
// tables' grids, body models, fixed controls or swing bounds differ.
int keepLowerEffort(GaitTable& table, const GaitTable& other);

// `table` on another grid (a grid extended to slower speeds, say): each of its entries whose grid
// point is also one of `grid`'s is kept, the other points of `grid` are unsolved. Throws
// std::invalid_argument when the grids' reference person or gravity differ.
GaitTable regridded(const GaitTable& table, const GaitGrid& grid);

// What interpolateGait did at a hole in the table (a grid point without a feasible gait).
struct InterpolationNote {
  std::vector<int> missing;  // grid points the target's cell needed and has no feasible gait at
  int nearest = -1;          // when the cell has none: the nearest feasible grid point taken
  bool exact() const { return missing.empty(); }
  // "" when exact; else what was done, naming the grid points in km/h, m and rad.
  std::string describe(const GaitGrid& grid) const;
};

// The gait at any (speed, step length, slope) inside the grid: controls and start state
// interpolated trilinearly between the eight surrounding gaits (dimensionless). At a hole it
// degrades gracefully: the feasible corners' weights are scaled up to sum to 1, and if the cell
// has no feasible corner that weighs, the nearest feasible grid point's gait (in grid steps) is
// taken, on the grid slope nearest the target's if that slope has any (a gait of another slope
// carries that slope's torso rest and impulse: with the tables at ±10°, a hole at −4.3° took the
// −7.16° gait, and sample_prior at 3.5 km/h, 0.6 m walked 0.972 of strides and 27 % of chains
// of 10 there, against 1.000 and 86 % with the −4.3° layer's own nearest, 3.5 km/h, 0.7 m);
// `note` (if given) says which points were missing. Throws std::out_of_range naming the
// axis for a target outside the grid, or when the table has no feasible gait at all.
// The result's stride_duration is 0: interpolated controls and start are close to, but not
// exactly on, a periodic stride; simulate one to know its duration.
Gait interpolateGait(const GaitTable& table, double speed_kmh, double step_length_m,
                     double slope_rad, InterpolationNote* note = nullptr);

}  // namespace kneed_walker::core::gait
