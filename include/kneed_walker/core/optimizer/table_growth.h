// Growing the grid of optimal gaits (paper §3.3) from one gait: the scheduler that solves a
// gait table point by point, each warm-started from its solved neighbours, on all cores.
//
// A first gait is found at the seed point (seedTable): from a given gait there or near it, else
// by continuation from McGeer's passive walker. growTable then solves every other point
// warm-started from its already feasible neighbours (Chebyshev distance 1), the points with the
// most warm starts first (nearest the seed on ties), and where those fail, by continuation from
// the nearest neighbour through the midpoint target. A point that failed is tried again
// whenever neighbours have become feasible since its last try (a point solved early, from one
// neighbour, often succeeds from the ones solved after it). table_polish.h then lowers the
// effort of what was grown.
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "kneed_walker/core/gait/gait_table.h"
#include "kneed_walker/core/optimizer/optimal_gaits.h"

namespace kneed_walker::core::optimizer {

struct GrowthOptions {
  int threads = 0;       // workers; 0: all cores
  int max_attempts = 4;  // warm starts tried per point, [1, 26]
  int seed_point = 0;    // grid index the table grows from (ties are broken nearest it)
  // Per grid point (empty, or the grid's size): a gait tried first there, before any neighbour's
  // (e.g. another table's gait at the point).
  std::vector<std::optional<gait::Gait>> first_tries;
};

struct GrowthProgress {
  int solved = 0;    // points solved (feasible or not)
  int feasible = 0;  // of them, feasible
  int points = 0;    // the grid's
};

// Keeps only the first try nearest growth.seed_point (grid cells): a table grown from that one
// gait.
void keepOnlyNearestFirstTry(GrowthOptions& growth, const gait::GaitGrid& grid);

// The grid point nearest a walk (the squares of the differences summed in km/h, m and rad).
int nearestGridPoint(const gait::GaitGrid& grid, double speed_kmh, double step_length_m, double slope_rad);

// The table's first gait, at growth.seed_point: from growth.first_tries nearest the seed point
// first (up to 12 of them; the point moves to the one that led to a gait), else by continuation
// from McGeer's passive gait. Writes the result (feasible or not) into the table and returns
// it. Gaits are solved for the table's body, fixed controls and swing bounds.
OptimalGait seedTable(gait::GaitTable& table, const GaitOptimizerOptions& options, GrowthOptions& growth);

// Solves every unsolved point of `table` (and failed ones, when new neighbours allow) as the
// header says, for the table's body, fixed controls and swing bounds; the rest of `options` as
// given. A failed gait already in the table counts as tried from its neighbours as they are.
// `after_point`, if given, is called after each point with the table as it then is, from one
// thread at a time (a long run saves it). Returns the final counts. Throws
// std::invalid_argument for threads < 0, max_attempts outside [1, 26] or first_tries of another
// size than the grid.
GrowthProgress growTable(gait::GaitTable& table, const GaitOptimizerOptions& options, const GrowthOptions& growth,
                         const std::function<void(const gait::GaitTable&, const GrowthProgress&)>& after_point = {});

// Re-simulates every feasible gait and marks those that no longer meet the constraints of
// `options` with the table's swing bounds (a table written before a rule was added) as failed.
// Returns how many were marked.
int markStaleGaits(gait::GaitTable& table, const GaitOptimizerOptions& options);

}  // namespace kneed_walker::core::optimizer
