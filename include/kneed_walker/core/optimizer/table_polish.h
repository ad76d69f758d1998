// Lowering the effort of a solved gait table (paper §3.3: each gait minimises eq. 9).
//
// optimize_gaits solves each grid point from the first of its neighbours' gaits that leads to
// a feasible one, and SLSQP finds the local optimum nearest that start: a point reached early
// from a far branch keeps a gait whose effort a neighbour's warm start beats by up to a hundred
// times (the level 4.5 km/h 0.7 m gait of the table shipped before its polish, c9015b0: 0.282 against 0.048
// from the 4 km/h neighbour's). polishTable re-solves every feasible gait from its neighbours'
// gaits and keeps the lowest effort, sweep after sweep, until no gait improves.
#pragma once

#include <functional>

#include "kneed_walker/core/gait/gait_table.h"
#include "kneed_walker/core/optimizer/optimal_gaits.h"

namespace kneed_walker::core::optimizer {

struct PolishProgress {
  int sweep = 0;       // 1-based
  int done = 0;        // points of this sweep solved
  int points = 0;      // points this sweep solves
  int improved = 0;    // of those, improved so far
};

struct PolishReport {
  int sweeps = 0;            // sweeps run (the last improved nothing, unless max_sweeps stopped it)
  int improved_points = 0;   // grid points whose gait was replaced at least once
  int solves = 0;            // optimizeGait calls
};

// Jacobi sweeps over the feasible gaits of `table`: in each, every point with a feasible face
// neighbour (one step along one axis of the grid) that is new since the point's last solve,
// i.e. every feasible point in the first sweep, then those next to a gait replaced in the
// sweep before, is solved warm-started from each of those neighbours' gaits (as the previous
// sweep left them), and its gait is replaced by the least-effort feasible result whose effort
// is below its own by more than a relative `min_improvement`. Points that had no feasible gait
// stay as they are. The results of a sweep depend only on the table the sweep began with, so
// the outcome is the same on any number of threads. The gaits are solved for the table's body,
// with its fixed controls and swing bounds; the rest of `options` (the effort's weights, the
// solver's settings) as given. `progress`, if given, is called after each point, from one
// thread at a time; `after_sweep`, if given, after each sweep with the table as it then is (a
// long run can save it). Throws std::invalid_argument for threads < 0, max_sweeps < 1 or
// min_improvement outside [0, 1).
PolishReport polishTable(gait::GaitTable& table, const GaitOptimizerOptions& options, int threads,
                         int max_sweeps = 20, double min_improvement = 1e-3,
                         const std::function<void(const PolishProgress&)>& progress = {},
                         const std::function<void(const gait::GaitTable&)>& after_sweep = {});

}  // namespace kneed_walker::core::optimizer
