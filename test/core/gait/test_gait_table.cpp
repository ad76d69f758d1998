#include "kneed_walker/core/gait/gait_table.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "shipped_config.h"

namespace kneed_walker::core::gait {
namespace {

const std::string kShippedTable = std::string(KNEED_WALKER_SOURCE_DIR) + "/config/gait_table.yaml";


const GaitTable& shipped() {
  static const GaitTable table = loadGaitTable(kShippedTable, test::shippedWalkerModel());
  return table;
}

// The shipped table on the paper's grid (3-7 km/h, 0.5-1.0 m): where the paper's findings are
// stated.
const GaitTable& papersGrid() {
  static const GaitTable table = regridded(shipped(), GaitGrid::paper());
  return table;
}

// Both shipped tables: the free optimum (config/gait_table.yaml, issue 4) and the prior's,
// optimised with the prior's fixed controls held (config/prior_gait_table.yaml).
class ShippedGaitTable : public ::testing::TestWithParam<const char*> {
 protected:
  GaitTable table = loadGaitTable(std::string(KNEED_WALKER_SOURCE_DIR) + "/config/" + GetParam(), test::shippedWalkerModel());
};

TEST_P(ShippedGaitTable, CoversThePapersGridAndSlowWalks) {
  // The paper's grid (3-7 km/h, 0.5-1.0 m, +-4.3 deg), extended to slow walks on short steps
  // (1.5-2.5 km/h, 0.3-0.4 m: a person strolling or pausing, as in PETS 2009) and to 10° hills
  // (the paper's Fig. 5 climb) through 7.16°.
  EXPECT_EQ(table.grid.speeds_kmh.size(), 12u);
  EXPECT_EQ(table.grid.step_lengths_m.size(), 8u);
  const std::vector<double> slopes_deg{-10, -0.125 * 180 / M_PI, -4.3, -2.15, 0, 2.15, 4.3, 0.125 * 180 / M_PI, 10};
  ASSERT_EQ(table.grid.slopes_rad.size(), slopes_deg.size());
  for (size_t s = 0; s < slopes_deg.size(); ++s)
    EXPECT_NEAR(table.grid.slopes_rad[s], slopes_deg[s] * M_PI / 180, 1e-12) << s;
  EXPECT_DOUBLE_EQ(table.grid.speeds_kmh.front(), 1.5);
  EXPECT_DOUBLE_EQ(table.grid.speeds_kmh.back(), 7.0);
  EXPECT_DOUBLE_EQ(table.grid.step_lengths_m.front(), 0.3);
  EXPECT_DOUBLE_EQ(table.grid.step_lengths_m.back(), 1.0);
  const GaitTable papers = regridded(table, GaitGrid::paper());
  int feasible = 0, papers_feasible = 0;
  for (const auto& e : table.entries) feasible += e.feasible;
  for (const auto& e : papers.entries) papers_feasible += e.feasible;
  std::cout << feasible << " of " << table.grid.size() << " gaits feasible, " << papers_feasible << " of "
            << papers.grid.size() << " on the paper's grid\n";
  RecordProperty("feasible_gaits", feasible);
  // The counts the README states for the shipped tables (a table regenerated with fewer gaits
  // must say so there): on the paper's grid 270 free (clearing the ground since 2026-12-05;
  // 269 before, scraping), 204 with the prior's fixed controls; on the whole grid 805 (798
  // before) and 388 of 864 (before the 7.16° and 10° slopes: 263 of 270, 413 and
  // 252 of 480). The prior's were 105 and 113 with the paper's swing knee stiffness of 0
  // (gait::FixedControls).
  EXPECT_GE(papers_feasible, table.fixed ? 204 : 270);
  EXPECT_GE(feasible, table.fixed ? 388 : 805);
}

// regridded carries a table's gaits to the points a new grid shares with it.
TEST(GaitTable, RegriddedKeepsTheSharedPointsAndLeavesTheNewOnesUnsolved) {
  GaitGrid slow = shipped().grid;
  slow.speeds_kmh = {1.0, 1.5, 7.0, 8.0};
  const GaitTable moved = regridded(shipped(), slow);
  ASSERT_EQ(static_cast<int>(moved.entries.size()), slow.size());
  for (int i = 0; i < slow.size(); ++i) {
    const auto c = slow.cell(i);
    const GaitTableEntry& e = moved.entries[i];
    if (c[0] == 1 || c[0] == 2) {
      const int from = shipped().grid.index(c[0] == 1 ? 0 : 11, c[1], c[2]);
      EXPECT_EQ(e.solved, shipped().entries[from].solved) << i;
      EXPECT_EQ(e.feasible, shipped().entries[from].feasible) << i;
      EXPECT_EQ(e.gait.start.q, shipped().entries[from].gait.start.q) << i;
    } else {
      EXPECT_FALSE(e.solved) << i;
    }
  }
  GaitGrid other = slow;
  other.reference_height_m = 1.8;
  EXPECT_THROW(regridded(shipped(), other), std::invalid_argument);
}

// Every shipped gait is re-simulated from its stored state and controls: it must be periodic
// and meet its speed and step length; the prior's gaits hold its fixed controls.
TEST_P(ShippedGaitTable, EveryGaitIsPeriodicAndOnTarget) {
  const dynamics::WalkerSimulator sim(dynamics::dimensionlessWalker(table.body));
  double worst_residual = 0, worst_speed = 0, worst_step = 0;
  double lowest_landing = std::numeric_limits<double>::infinity();
  double lowest_passing = std::numeric_limits<double>::infinity();  // sole height passing the stance foot, L
  int feasible = 0, inside_margin = 0, through_ground = 0;  // passing the stance foot
  for (int i = 0; i < table.grid.size(); ++i) {
    const GaitTableEntry& e = table.entries[i];
    if (!e.feasible) continue;
    const gait::GaitTarget target = table.grid.target(i);
    EXPECT_NEAR(e.gait.target.speed, target.speed, 1e-12) << "gait " << i;
    if (table.fixed) {
      const dynamics::SpringParameters& springs = e.gait.controls.springs;
      EXPECT_EQ(springs.stance_knee_damping, table.fixed->knee_damping) << "gait " << i;
      EXPECT_EQ(springs.swing_knee_damping, table.fixed->knee_damping) << "gait " << i;
      EXPECT_EQ(springs.swing_knee_rest_angle, 0.0) << "gait " << i;
      EXPECT_NEAR(springs.torso_rest_angle, table.fixed->torso_rest_per_slope * target.slope, 1e-15) << "gait " << i;
      EXPECT_EQ(springs.torso_damping, table.fixed->torso_damping) << "gait " << i;
    }
    const dynamics::StrideResult stride = sim.stride(e.gait.controls, e.gait.start);
    // A landing on a pulling ground would be a fall: not completed.
    ASSERT_TRUE(stride.completed) << "gait " << i << (stride.pulling_heel_strike ? " lands on a pulling ground" : "");
    lowest_landing = std::min(lowest_landing, stride.landing_impulse);
    ++feasible;
    inside_margin += stride.integrals.passing_clearance < dynamics::SimulationOptions{}.clearance_margin;  // dimensionless: L = 1
    through_ground += stride.integrals.passing_clearance < 0;
    lowest_passing = std::min(lowest_passing, stride.integrals.passing_clearance);
    // The swing bounds the table was optimised with hold for every gait (within SLSQP's 1e-6).
    EXPECT_GE(stride.integrals.passing_clearance, table.swing_bounds.min_passing_clearance - 1e-6) << "gait " << i;
    EXPECT_LE(stride.integrals.max_swing_knee_flexion, table.swing_bounds.max_swing_knee_flexion + 1e-6) << "gait " << i;
    const double residual = std::max((stride.end.q - e.gait.start.q).lpNorm<Eigen::Infinity>(),
                                     (stride.end.qdot - e.gait.start.qdot).lpNorm<Eigen::Infinity>());
    worst_residual = std::max(worst_residual, residual);
    worst_speed = std::max(worst_speed, std::abs(stride.speed / target.speed - 1));
    worst_step = std::max(worst_step, std::abs(stride.step_length / target.step_length - 1));
    EXPECT_LT(residual, 1e-6) << "gait " << i;
    EXPECT_LT(std::abs(stride.speed / target.speed - 1), 0.01) << "gait " << i;
    EXPECT_LT(std::abs(stride.step_length / target.step_length - 1), 0.01) << "gait " << i;
  }
  std::cout << "worst fixed-point residual " << worst_residual << ", speed error " << worst_speed
            << ", step length error " << worst_step << "; lowest ground impulse at a landing "
            << lowest_landing << "; of " << feasible << " gaits " << inside_margin
            << " pass the stance foot inside the clearance margin, " << through_ground << " through the ground, lowest "
            << lowest_passing << " L\n";
  // The optimiser asks for at least 0.01 (GaitOptimizerOptions::min_landing_impulse) and
  // SLSQP stops within its tolerance of an active bound: measured 0.00068 (free) and 0.0060
  // (prior's; 0.0051 and 0.0010 before the tables reached ±10°).
  EXPECT_GT(lowest_landing, 0.0);
  // The free table is optimised with the clearance bound (0.01 L, issue 13; 2026-12-05) and
  // the swing knee's flexion bound (1.31 rad), both recorded in the table: no gait passes the
  // stance foot below 0.01 L (checked per gait above). The prior's table is not yet: measured
  // 2026-12-03, 348 of its 388 gaits pass the stance foot with the swing sole below the ground
  // (lowest -2.40 cm of leg length). No more, and no deeper.
  const bool free_table = GetParam() == std::string("gait_table.yaml");
  if (free_table) {
    EXPECT_EQ(table.swing_bounds.min_passing_clearance, 0.01);
    EXPECT_EQ(table.swing_bounds.max_swing_knee_flexion, 1.31);
    EXPECT_EQ(through_ground, 0);
  } else {
    EXPECT_LE(through_ground, 348);
    EXPECT_GE(lowest_passing, -0.0245);
  }
}

// The tracker advances its particles frame by frame, the optimiser a stride at once: every
// shipped gait walks the same stride in 1/30 s frames of the reference person as at once
// (the integrator's steps lie on a grid from the last event, not from each call). Before that
// grid (2026-12-05), a free knee touching its limit within one step was caught or missed
// depending on where the frames split the steps: 37 free and 9 prior gaits fell in frames.
TEST_P(ShippedGaitTable, EveryGaitWalksTheSameStrideInFrames) {
  const dynamics::WalkerSimulator sim(dynamics::dimensionlessWalker(table.body));
  const double frame = (1.0 / 30) / std::sqrt(table.grid.referenceLegLength() / table.grid.gravity);
  int fell = 0, differ = 0, gaits = 0;
  double worst = 0;
  for (const GaitTableEntry& e : table.entries) {
    if (!e.feasible) continue;
    ++gaits;
    const dynamics::StrideResult at_once = sim.stride(e.gait.controls, e.gait.start);
    dynamics::WalkerState in_frames = e.gait.start;
    double elapsed = 0;
    int heel_strikes = 0, knee_events = 0;
    while (heel_strikes == 0 && !in_frames.fallen && elapsed < 10) {
      const dynamics::AdvanceReport report = sim.advance(e.gait.controls, in_frames, frame);
      heel_strikes += report.heel_strikes;
      knee_events += report.knee_limit_events;
      elapsed += report.elapsed;
    }
    // The stride at once, then advanced on to the frames' end.
    dynamics::WalkerState reference = at_once.end;
    sim.advance(e.gait.controls, reference, elapsed - at_once.duration);
    const double difference = std::max((in_frames.q - reference.q).lpNorm<Eigen::Infinity>(),
                                       (in_frames.qdot - reference.qdot).lpNorm<Eigen::Infinity>());
    fell += in_frames.fallen;
    if (!in_frames.fallen) {
      worst = std::max(worst, difference);
      differ += difference > 1e-9;
    }
  }
  std::cout << gaits << " gaits walked a stride in frames: " << fell << " fell, " << differ
            << " ended more than 1e-9 from the stride at once (worst " << worst << ")\n";
  EXPECT_EQ(fell, 0);
  EXPECT_EQ(differ, 0);
}

INSTANTIATE_TEST_SUITE_P(Config, ShippedGaitTable,
                         ::testing::Values("gait_table.yaml", "prior_gait_table.yaml"),
                         [](const auto& info) { return std::string(info.param).substr(0, std::string(info.param).find('.')); });

// Mean of f over the feasible gaits of one slope index whose (speed, step) partner at the
// other slope is feasible too.
template <typename F>
std::pair<double, double> pairedMeans(const GaitTable& table, int slope_a, int slope_b, F f) {
  double a = 0, b = 0;
  int n = 0;
  for (size_t v = 0; v < table.grid.speeds_kmh.size(); ++v)
    for (size_t l = 0; l < table.grid.step_lengths_m.size(); ++l) {
      const auto& ea = table.entries[table.grid.index(v, l, slope_a)];
      const auto& eb = table.entries[table.grid.index(v, l, slope_b)];
      if (!ea.feasible || !eb.feasible) continue;
      a += f(ea.gait);
      b += f(eb.gait);
      ++n;
    }
  EXPECT_GT(n, 0) << "no (speed, step) with both slopes feasible";
  return {a / std::max(n, 1), b / std::max(n, 1)};
}

// Paper §3.3, Fig. 2: the knee is more bent at contact uphill than downhill. At contact the
// landing knee becomes the stance knee, so its flexion is that of x0's stance knee.
TEST(GaitTable, KneeIsMoreBentAtContactUphillThanDownhill) {
  const GaitTable& table = papersGrid();
  const int down = 0, up = static_cast<int>(table.grid.slopes_rad.size()) - 1;
  const auto [uphill, downhill] = pairedMeans(table, up, down, [](const Gait& g) {
    return dynamics::kneeFlexion(g.start.q, 0);
  });
  std::cout << "mean knee flexion at contact: uphill " << uphill << " rad, downhill " << downhill
            << " rad\n";
  EXPECT_GT(uphill, downhill);
}

// Paper §3.3: "the stereotypical lean of the upper body can be seen, including a forward lean
// when climbing up a hill and a slight backwards lean when walking down". Lean is measured
// against gravity, as a picture shows it: an upright torso is at −γ in the walker's slope
// frame, so the forward lean is −(φTo + γ), averaged over the stride.
double meanForwardLean(const Gait& g) {
  static const dynamics::WalkerSimulator sim(dynamics::dimensionlessWalker(test::shippedWalkerModel()));
  dynamics::WalkerState s = g.start;
  const double dt = g.stride_duration / 40;
  double sum = 0;
  for (int k = 0; k < 40; ++k) {
    sum += -(s.q[dynamics::kTorso] + g.target.slope);
    sim.advance(g.controls, s, dt);
  }
  return sum / 40;
}

TEST(GaitTable, TorsoLeansFurtherForwardUphillThanOnTheLevel) {
  const GaitTable& table = papersGrid();
  const int level = static_cast<int>(table.grid.slopes_rad.size()) / 2;
  const int up = static_cast<int>(table.grid.slopes_rad.size()) - 1;
  const auto [uphill, flat] = pairedMeans(table, up, level, meanForwardLean);
  std::cout << "mean forward lean of the torso from the vertical: uphill " << uphill << " rad, level "
            << flat << " rad\n";
  EXPECT_GT(uphill, flat);
}

TEST(GaitTable, TorsoLeansLessForwardDownhillThanOnTheLevel) {
  const GaitTable& table = papersGrid();
  const int level = static_cast<int>(table.grid.slopes_rad.size()) / 2;
  const auto [downhill, flat] = pairedMeans(table, 0, level, meanForwardLean);
  std::cout << "mean forward lean of the torso from the vertical: downhill " << downhill << " rad, level "
            << flat << " rad\n";
  EXPECT_LT(downhill, flat);
}

// Paper §3.3: the optimal swing-knee stiffness is small compared with the stance knee's.
TEST(GaitTable, SwingKneeIsNearlyPassive) {
  std::vector<double> swing, stance;
  for (const auto& e : papersGrid().entries) {
    if (!e.feasible) continue;
    swing.push_back(e.gait.controls.springs.swing_knee_stiffness);
    stance.push_back(e.gait.controls.springs.stance_knee_stiffness);
  }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  std::cout << "median stiffness: swing knee " << median(swing) << ", stance knee "
            << median(stance) << " (M g L per rad)\n";
  EXPECT_LT(median(swing), median(stance));
}

TEST(GaitTable, InterpolatesInsideTheGridAndRefusesOutside) {
  const GaitTable& table = shipped();
  const GaitGrid& g = table.grid;
  // At a feasible grid point the interpolation is that gait.
  for (int i = 0; i < g.size(); ++i) {
    const auto& e = table.entries[i];
    if (!e.feasible) continue;
    const auto c = g.cell(i);
    bool corners_feasible = true;  // the interpolation needs the cell's other corners too
    for (int corner = 0; corner < 8; ++corner) {
      const int v = std::min<int>(c[0] + (corner & 1), g.speeds_kmh.size() - 1);
      const int l = std::min<int>(c[1] + ((corner >> 1) & 1), g.step_lengths_m.size() - 1);
      const int s = std::min<int>(c[2] + ((corner >> 2) & 1), g.slopes_rad.size() - 1);
      corners_feasible = corners_feasible && table.entries[g.index(v, l, s)].feasible;
    }
    if (!corners_feasible) continue;
    const Gait at = interpolateGait(table, g.speeds_kmh[c[0]], g.step_lengths_m[c[1]],
                                           g.slopes_rad[c[2]]);
    EXPECT_NEAR((at.start.q - e.gait.start.q).norm(), 0, 1e-12);
    EXPECT_NEAR(at.controls.springs.hip_stiffness, e.gait.controls.springs.hip_stiffness, 1e-12);
    break;
  }
  try {
    interpolateGait(table, 9.0, 0.7, 0.0);
    FAIL() << "9 km/h accepted";
  } catch (const std::out_of_range& e) {
    EXPECT_NE(std::string(e.what()).find("speed 9 km/h is outside"), std::string::npos) << e.what();
  }
  EXPECT_THROW(interpolateGait(table, 5.0, 1.2, 0.0), std::out_of_range);
  EXPECT_THROW(interpolateGait(table, 5.0, 0.7, 0.2), std::out_of_range);
}

// Interpolation between a cell's corners: the middle of a cell with four feasible corners (on a
// slope of the grid) is their mean; with one corner missing it is the mean of the other three,
// and the note names the missing grid point.
TEST(GaitTable, ACellsMiddleIsTheMeanOfItsFeasibleCornersAndAMissingCornerIsNamed) {
  const GaitTable& table = shipped();
  const GaitGrid& g = table.grid;
  bool found_full = false, found_hole = false;
  for (int v = 0; v + 1 < static_cast<int>(g.speeds_kmh.size()); ++v)
    for (int l = 0; l + 1 < static_cast<int>(g.step_lengths_m.size()); ++l)
      for (int sl = 0; sl < static_cast<int>(g.slopes_rad.size()); ++sl) {
        int feasible = 0, missing = -1;
        for (int corner = 0; corner < 4; ++corner) {
          const bool ok = table.entries[g.index(v + (corner & 1), l + (corner >> 1), sl)].feasible;
          feasible += ok;
          if (!ok) missing = corner;
        }
        if ((feasible == 4 && found_full) || (feasible == 3 && found_hole) || feasible < 3) continue;
        const double speed = 0.5 * (g.speeds_kmh[v] + g.speeds_kmh[v + 1]);
        const double step = 0.5 * (g.step_lengths_m[l] + g.step_lengths_m[l + 1]);
        InterpolationNote note;
        const Gait middle = interpolateGait(table, speed, step, g.slopes_rad[sl], &note);
        double hip = 0;
        dynamics::Vector5 q = dynamics::Vector5::Zero();
        for (int corner = 0; corner < 4; ++corner) {
          const GaitTableEntry& c = table.entries[g.index(v + (corner & 1), l + (corner >> 1), sl)];
          if (!c.feasible) continue;
          hip += c.gait.controls.springs.hip_stiffness / feasible;
          q += c.gait.start.q / feasible;
        }
        EXPECT_NEAR(middle.controls.springs.hip_stiffness, hip, 1e-12 * std::abs(hip));
        EXPECT_LT((middle.start.q - q).norm(), 1e-12);
        if (feasible == 4) {
          found_full = true;
          EXPECT_TRUE(note.exact());
          EXPECT_EQ(note.describe(g), "");
        } else {
          found_hole = true;
          ASSERT_EQ(note.missing.size(), 1u);
          EXPECT_EQ(note.missing[0], g.index(v + (missing & 1), l + (missing >> 1), sl));
          EXPECT_EQ(note.nearest, -1);
          std::ostringstream named;
          named << "no feasible gait at " << g.speeds_kmh[v + (missing & 1)] << " km/h, "
                << g.step_lengths_m[l + (missing >> 1)] << " m";
          EXPECT_NE(note.describe(g).find(named.str()), std::string::npos) << note.describe(g);
        }
      }
  EXPECT_TRUE(found_full && found_hole);
}

// A target with no feasible gait around it (here: at an infeasible grid point, which alone
// weighs) takes the nearest feasible grid point's gait, in grid steps, and the note says so.
TEST(GaitTable, ATargetInAHoleTakesTheNearestFeasibleGait) {
  const GaitTable& table = shipped();
  const GaitGrid& g = table.grid;
  int hole = -1;
  for (int i = 0; i < g.size() && hole < 0; ++i)
    if (!table.entries[i].feasible) hole = i;
  ASSERT_GE(hole, 0);
  const auto h = g.cell(hole);
  InterpolationNote note;
  const Gait taken = interpolateGait(table, g.speeds_kmh[h[0]], g.step_lengths_m[h[1]], g.slopes_rad[h[2]], &note);
  ASSERT_EQ(note.missing, std::vector<int>{hole});
  ASSERT_GE(note.nearest, 0);
  const GaitTableEntry& nearest = table.entries[note.nearest];
  EXPECT_TRUE(nearest.feasible);
  EXPECT_EQ(taken.start.q, nearest.gait.start.q);
  EXPECT_EQ(taken.controls.springs.hip_stiffness, nearest.gait.controls.springs.hip_stiffness);
  auto steps2 = [&](int i) {
    const auto c = g.cell(i);
    return (c[0] - h[0]) * (c[0] - h[0]) + (c[1] - h[1]) * (c[1] - h[1]) + (c[2] - h[2]) * (c[2] - h[2]);
  };
  // The nearest on the hole's own slope (it has feasible gaits).
  EXPECT_EQ(g.cell(note.nearest)[2], h[2]);
  for (int i = 0; i < g.size(); ++i)
    if (table.entries[i].feasible && g.cell(i)[2] == h[2])
      EXPECT_GE(steps2(i), steps2(note.nearest)) << "grid point " << i << " is nearer";
  EXPECT_NE(note.describe(g).find("took the nearest feasible gait"), std::string::npos) << note.describe(g);
  std::cout << note.describe(g) << "\n";
  // A slope with no feasible gait at all takes the nearest over all slopes.
  GaitTable bare = table;
  for (int i = 0; i < g.size(); ++i)
    if (g.cell(i)[2] == h[2]) bare.entries[i].feasible = false;
  InterpolationNote elsewhere;
  interpolateGait(bare, g.speeds_kmh[h[0]], g.step_lengths_m[h[1]], g.slopes_rad[h[2]], &elsewhere);
  ASSERT_GE(elsewhere.nearest, 0);
  EXPECT_NE(g.cell(elsewhere.nearest)[2], h[2]);
  for (int i = 0; i < g.size(); ++i)
    if (bare.entries[i].feasible) EXPECT_GE(steps2(i), steps2(elsewhere.nearest)) << "grid point " << i << " is nearer";
}

// Of two runs, the lower effort wins per grid point; a feasible gait beats none; tables of
// other grids or other fixed controls are refused.
TEST(GaitTable, KeepsTheLowerEffortOfTwoRuns) {
  GaitTable table = shipped(), other = shipped();
  int first = -1, second = -1;
  for (int i = 1; i < table.grid.size() && second < 0; ++i)
    if (table.entries[i].feasible) (first < 0 ? first : second) = i;
  other.entries[first].quality.effort -= 1.0;    // better in the other run
  other.entries[second].quality.effort += 1.0;   // worse in the other run
  table.entries[0].feasible = false;          // missing here, present there (if feasible)
  const bool zero_feasible = other.entries[0].feasible;
  EXPECT_EQ(keepLowerEffort(table, other), 1 + (zero_feasible ? 1 : 0));
  EXPECT_EQ(table.entries[first].quality.effort, other.entries[first].quality.effort);
  EXPECT_EQ(table.entries[second].quality.effort, shipped().entries[second].quality.effort);
  other.grid.slopes_rad.back() += 0.01;
  EXPECT_THROW(keepLowerEffort(table, other), std::invalid_argument);
  EXPECT_THROW(keepLowerEffort(table, loadGaitTable(std::string(KNEED_WALKER_SOURCE_DIR) + "/config/prior_gait_table.yaml", test::shippedWalkerModel())),
               std::invalid_argument);
}

TEST(GaitTable, SavesAndLoadsLosslessly) {
  const std::string path = testing::TempDir() + "gait_table_round_trip.yaml";
  saveGaitTable(path, shipped());
  const GaitTable back = loadGaitTable(path, test::shippedWalkerModel());
  EXPECT_EQ(back.swing_bounds, shipped().swing_bounds);
  EXPECT_EQ(back.fixed, shipped().fixed);
  ASSERT_EQ(back.entries.size(), shipped().entries.size());
  for (size_t i = 0; i < back.entries.size(); ++i) {
    EXPECT_EQ(back.entries[i].feasible, shipped().entries[i].feasible);
    if (!back.entries[i].solved) continue;
    EXPECT_EQ(back.entries[i].gait.start.q, shipped().entries[i].gait.start.q) << i;
    EXPECT_EQ(back.entries[i].gait.controls.springs.torso_damping,
              shipped().entries[i].gait.controls.springs.torso_damping);
  }
  std::remove(path.c_str());
  // A table without swing bounds (the prior's) is read back unbounded; a bound alone is kept
  // alone.
  GaitTable one_bound = shipped();
  one_bound.swing_bounds = SwingBounds{};
  one_bound.swing_bounds.max_swing_knee_flexion = 1.2;
  saveGaitTable(path, one_bound);
  const SwingBounds read = loadGaitTable(path, test::shippedWalkerModel()).swing_bounds;
  EXPECT_EQ(read.max_swing_knee_flexion, 1.2);
  EXPECT_EQ(read.min_passing_clearance, -std::numeric_limits<double>::infinity());
  std::remove(path.c_str());
}

TEST(GaitTable, MalformedTablesAreRefusedWithTheReason) {
  const std::string path = testing::TempDir() + "bad_gait_table.yaml";
  {
    FILE* f = std::fopen(path.c_str(), "w");
    std::fputs("%YAML:1.0\nreference_height_m: 1.75\nbody_model: {}\ngravity: 9.81\n"
               "speeds_kmh: [3, 5]\nstep_lengths_m: [0.7, 0.5]\nslopes_rad: [0, 0.1]\ngaits: []\n",
               f);
    std::fclose(f);
  }
  try {
    loadGaitTable(path, test::shippedWalkerModel());
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("step_lengths_m must hold at least two ascending"),
              std::string::npos)
        << e.what();
  }
  std::remove(path.c_str());
  EXPECT_THROW(loadGaitTable(path, test::shippedWalkerModel()), std::invalid_argument);

  // The shipped table spoilt three ways: a grid point left out, two out of order, a knee flag 2.
  std::ifstream in(kShippedTable);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto refusal = [&](const std::string& text) {
    const std::string spoilt = testing::TempDir() + "spoilt_gait_table.yaml";
    std::ofstream(spoilt) << text;
    try {
      loadGaitTable(spoilt, test::shippedWalkerModel());
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::size_t second = good.find("   -\n      index: 1\n"), third = good.find("   -\n      index: 2\n");
  ASSERT_NE(second, std::string::npos);
  ASSERT_NE(third, std::string::npos);
  const std::string without_one = good.substr(0, second) + good.substr(third);
  EXPECT_NE(refusal(without_one).find("must list " + std::to_string(shipped().grid.size()) + " grid points"),
            std::string::npos) << refusal(without_one);
  std::string swapped = good;
  swapped.replace(swapped.find("      index: 1\n"), 15, "      index: 2\n");
  EXPECT_NE(refusal(swapped).find("out of order"), std::string::npos) << refusal(swapped);
  std::string bad_knees = good;
  bad_knees.replace(bad_knees.find("knees_locked: [ 1, 0 ]"), 22, "knees_locked: [ 2, 0 ]");
  EXPECT_NE(refusal(bad_knees).find("knees_locked must hold two flags, 0 or 1"), std::string::npos) << refusal(bad_knees);
  std::string bad_bound = good;
  const std::size_t bound_at = bad_bound.find("min_passing_clearance: ");
  ASSERT_NE(bound_at, std::string::npos);
  bad_bound.replace(bound_at, bad_bound.find('\n', bound_at) - bound_at, "min_passing_clearance: .nan");
  EXPECT_NE(refusal(bad_bound).find("min_passing_clearance"), std::string::npos) << refusal(bad_bound);
}

}  // namespace
}  // namespace kneed_walker::core::gait
