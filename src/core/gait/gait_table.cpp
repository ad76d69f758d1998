#include "kneed_walker/core/gait/gait_table.h"

#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "kneed_walker/core/common/config_file.h"

namespace kneed_walker::core::gait {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::vector<double> linspace(double from, double to, int n) {
  std::vector<double> v(n);
  for (int i = 0; i < n; ++i) v[i] = from + (to - from) * i / (n - 1);
  return v;
}

std::vector<double> toVector(const dynamics::Vector5& v) { return {v.data(), v.data() + v.size()}; }

void requireAscending(common::ConfigNode& file, const std::string& key, std::vector<double>& axis) {
  if (!file.read(key, axis, common::Need::kRequired)) return;
  if (axis.size() < 2 || !std::is_sorted(axis.begin(), axis.end()) ||
      std::adjacent_find(axis.begin(), axis.end()) != axis.end())
    file.problem(key, "must hold at least two ascending values");
}

// Where x falls on an axis: the lower index and the weight of the upper neighbour.
std::pair<int, double> locate(const std::vector<double>& axis, double x, const char* name,
                              const char* unit) {
  if (!(x >= axis.front() && x <= axis.back())) {
    std::ostringstream message;
    message << name << " " << x << " " << unit << " is outside the gait table's range "
            << axis.front() << "–" << axis.back() << " " << unit;
    throw std::out_of_range(message.str());
  }
  const int last = static_cast<int>(axis.size()) - 2;
  int i = static_cast<int>(std::upper_bound(axis.begin(), axis.end(), x) - axis.begin()) - 1;
  i = std::clamp(i, 0, last);
  return {i, (x - axis[i]) / (axis[i + 1] - axis[i])};
}

}  // namespace

GaitGrid GaitGrid::paper() {
  GaitGrid grid;
  grid.speeds_kmh = linspace(3.0, 7.0, 9);
  grid.step_lengths_m = linspace(0.5, 1.0, 6);
  grid.slopes_rad = linspace(-4.3 * kPi / 180, 4.3 * kPi / 180, 5);
  return grid;
}

std::array<int, 3> GaitGrid::cell(int index) const {
  const int n_slope = static_cast<int>(slopes_rad.size());
  const int n_step = static_cast<int>(step_lengths_m.size());
  return {index / (n_step * n_slope), (index / n_slope) % n_step, index % n_slope};
}

gait::GaitTarget GaitGrid::target(double speed_kmh, double step_length_m, double slope_rad) const {
  const double leg = referenceLegLength();
  return {speed_kmh / 3.6 / std::sqrt(gravity * leg), step_length_m / leg, slope_rad};
}

gait::GaitTarget GaitGrid::target(int index) const {
  const auto c = cell(index);
  return target(speeds_kmh[c[0]], step_lengths_m[c[1]], slopes_rad[c[2]]);
}

void saveGaitTable(const std::string& path, const GaitTable& table) {
  const GaitGrid& g = table.grid;
  if (g.leg_length_per_height != table.body.leg_length_per_height)
    throw std::invalid_argument(path + ": the grid's leg_length_per_height differs from the body model's");
  cv::FileStorage file(path, cv::FileStorage::WRITE);
  if (!file.isOpened()) throw std::invalid_argument(path + ": cannot write");
  std::string controls = "controls:";
  for (int c = 0; c < kNumControls; ++c)
    controls += std::string(c % 4 == 0 ? "\n  " : " ") + controlName(static_cast<Control>(c)) +
                (c + 1 < kNumControls ? "," : ".");
  file.writeComment(
      "Optimal cyclic gaits of the Kneed Walker (paper 3.3), written by\n"
      "`rosrun kneed_walker optimize_gaits`. Dimensionless units: leg length 1, body mass 1,\n"
      "g 1; the axes are for a person of reference_height_m with the body model below.\n" +
      controls + "\nq, qdot: post-heel-strike state x0.");
  file << "reference_height_m" << g.reference_height_m;
  file << "gravity" << g.gravity;
  file << "body_model" << "{";
  dynamics::writeBodyProportions(file, table.body);
  file << "}";
  file << "speeds_kmh" << g.speeds_kmh << "step_lengths_m" << g.step_lengths_m << "slopes_rad"
       << g.slopes_rad;
  if (table.fixed) {
    file.writeComment("Held fixed while optimising (the prior's values, paper 3.4): knee damping,\n"
                      "torso rest angle per slope, torso damping.");
    file << "fixed_controls"
         << std::vector<double>{table.fixed->knee_damping, table.fixed->torso_rest_per_slope,
                                table.fixed->torso_damping};
  }
  const SwingBounds& bounds = table.swing_bounds;
  if (std::isfinite(bounds.min_passing_clearance) || std::isfinite(bounds.max_swing_knee_flexion))
    file.writeComment("Bounds on the swing held while optimising (absent: not bounded): the swing sole's\n"
                      "lowest height passing the stance foot, leg lengths; the swing knee's peak flexion, rad.");
  if (std::isfinite(bounds.min_passing_clearance)) file << "min_passing_clearance" << bounds.min_passing_clearance;
  if (std::isfinite(bounds.max_swing_knee_flexion)) file << "max_swing_knee_flexion" << bounds.max_swing_knee_flexion;
  file << "gaits" << "[";
  for (size_t i = 0; i < table.entries.size(); ++i) {
    const GaitTableEntry& e = table.entries[i];
    file << "{" << "index" << static_cast<int>(i) << "solved" << static_cast<int>(e.solved)
         << "feasible" << static_cast<int>(e.feasible);
    if (e.solved) {
      const Gait& gait = e.gait;
      const GaitQuality& quality = e.quality;
      const ControlVector controls = toControlVector(gait.controls);
      file << "target"
           << std::vector<double>{gait.target.speed, gait.target.step_length, gait.target.slope}
           << "controls" << std::vector<double>(controls.begin(), controls.end()) << "q"
           << toVector(gait.start.q) << "qdot" << toVector(gait.start.qdot) << "knees_locked"
           << std::vector<int>{gait.start.knee_on_limit[0], gait.start.knee_on_limit[1]}
           << "duration" << gait.stride_duration << "speed" << quality.speed
           << "step_length" << quality.step_length << "effort" << quality.effort
           << "periodicity_residual" << quality.periodicity_residual << "nlopt_result"
           << quality.solver_status << "evaluations" << quality.evaluations;
    }
    file << "}";
  }
  file << "]";
}

GaitTable loadGaitTable(const std::string& path, const dynamics::BodyProportions& body) {
  common::ConfigFile file(path, "gait table");
  GaitTable table;
  GaitGrid& g = table.grid;
  file.read("reference_height_m", g.reference_height_m, common::Need::kRequired);
  file.read("gravity", g.gravity, common::Need::kRequired);
  if (!(g.reference_height_m > 0 && g.gravity > 0))
    file.problem("reference_height_m", "and gravity must be positive");
  common::ConfigNode body_node = file.map("body_model", common::Need::kRequired);
  table.body = dynamics::readBodyProportions(body_node);
  g.leg_length_per_height = table.body.leg_length_per_height;
  requireAscending(file, "speeds_kmh", g.speeds_kmh);
  requireAscending(file, "step_lengths_m", g.step_lengths_m);
  requireAscending(file, "slopes_rad", g.slopes_rad);
  std::array<double, 3> fixed;
  if (file.read("fixed_controls", fixed)) table.fixed = FixedControls{fixed[0], fixed[1], fixed[2]};
  for (const auto& [key, bound] : {std::pair{"min_passing_clearance", &table.swing_bounds.min_passing_clearance},
                                   std::pair{"max_swing_knee_flexion", &table.swing_bounds.max_swing_knee_flexion}})
    file.read(key, *bound);  // finite: absent means not bounded

  std::vector<common::ConfigNode> gaits = file.maps("gaits", common::Need::kRequired);
  if (static_cast<int>(gaits.size()) != g.size())
    file.problem("gaits", "must list " + std::to_string(g.size()) + " grid points, lists " +
                              std::to_string(gaits.size()));
  table.entries.resize(gaits.size());
  for (int i = 0; i < static_cast<int>(gaits.size()); ++i) {
    common::ConfigNode& node = gaits[i];
    int index = -1;
    node.read("index", index, common::Need::kRequired);
    if (index != i) node.problem("index", "is " + std::to_string(index) + ": the gait is out of order");
    GaitTableEntry& e = table.entries[i];
    node.read("solved", e.solved, common::Need::kRequired);
    node.read("feasible", e.feasible, common::Need::kRequired);
    if (!e.solved) continue;
    Gait& gait = e.gait;
    std::array<double, 3> target{};
    node.read("target", target, common::Need::kRequired);
    gait.target = {target[0], target[1], target[2]};
    ControlVector controls{};
    node.read("controls", controls, common::Need::kRequired);
    gait.controls = fromControlVector(controls, gait.target.slope);
    std::array<double, dynamics::kNumCoordinates> q{}, qdot{};
    node.read("q", q, common::Need::kRequired);
    node.read("qdot", qdot, common::Need::kRequired);
    for (int j = 0; j < dynamics::kNumCoordinates; ++j) {
      gait.start.q[j] = q[j];
      gait.start.qdot[j] = qdot[j];
    }
    std::array<double, dynamics::kNumKnees> knees{};
    if (node.read("knees_locked", knees, common::Need::kRequired)) {
      for (int k = 0; k < dynamics::kNumKnees; ++k) {
        if (knees[k] != 0 && knees[k] != 1) node.problem("knees_locked", "must hold two flags, 0 or 1");
        gait.start.knee_on_limit[k] = knees[k] == 1;
      }
    }
    GaitQuality& quality = e.quality;
    node.read("duration", gait.stride_duration, common::Need::kRequired);
    node.read("speed", quality.speed, common::Need::kRequired);
    node.read("step_length", quality.step_length, common::Need::kRequired);
    // An infeasible gait may have diverged (unbounded effort) or be infinitely far from
    // periodic (it fell, or its knees changed).
    node.read("effort", quality.effort, common::Need::kRequired, true);
    node.read("periodicity_residual", quality.periodicity_residual, common::Need::kRequired, true);
    node.read("nlopt_result", quality.solver_status, common::Need::kRequired);
    node.read("evaluations", quality.evaluations, common::Need::kRequired);
  }
  std::vector<std::string> problems = dynamics::validate(table.body);
  for (auto& problem : problems) problem = "body_model." + problem;
  const std::vector<std::string> differ = dynamics::differences(table.body, body);
  if (!differ.empty()) {
    std::string list;
    for (const auto& d : differ) list += (list.empty() ? "" : "; ") + d;
    problems.push_back("body_model differs from the walker model in use (table vs model: " + list +
                       "): optimise a table for this model with optimize_gaits");
  }
  file.finish(problems);
  return table;
}

int keepLowerEffort(GaitTable& table, const GaitTable& other) {
  const GaitGrid &a = table.grid, &b = other.grid;
  if (a.speeds_kmh != b.speeds_kmh || a.step_lengths_m != b.step_lengths_m ||
      a.slopes_rad != b.slopes_rad || a.reference_height_m != b.reference_height_m ||
      a.leg_length_per_height != b.leg_length_per_height || a.gravity != b.gravity)
    throw std::invalid_argument("keepLowerEffort: the gait tables have different grids");
  if (!dynamics::differences(table.body, other.body).empty())
    throw std::invalid_argument("keepLowerEffort: the gait tables are for different body models");
  if (table.fixed != other.fixed)
    throw std::invalid_argument("keepLowerEffort: the gait tables hold different controls fixed");
  if (table.swing_bounds != other.swing_bounds)
    throw std::invalid_argument("keepLowerEffort: the gait tables were optimised with different swing bounds");
  int taken = 0;
  for (size_t i = 0; i < table.entries.size(); ++i) {
    const GaitTableEntry& theirs = other.entries[i];
    GaitTableEntry& ours = table.entries[i];
    if (theirs.feasible && (!ours.feasible || theirs.quality.effort < ours.quality.effort)) {
      ours = theirs;
      ++taken;
    }
  }
  return taken;
}

GaitTable regridded(const GaitTable& table, const GaitGrid& grid) {
  const GaitGrid& from = table.grid;
  if (from.reference_height_m != grid.reference_height_m ||
      from.leg_length_per_height != grid.leg_length_per_height || from.gravity != grid.gravity)
    throw std::invalid_argument("regridded: the grids are for different reference people or gravity");
  // The index of each of `to`'s values in `from`, or -1.
  auto match = [](const std::vector<double>& from_axis, const std::vector<double>& to_axis) {
    std::vector<int> indices;
    for (const double x : to_axis) {
      const auto it = std::find_if(from_axis.begin(), from_axis.end(),
                                   [x](double y) { return std::abs(x - y) <= 1e-9 * std::max(1.0, std::abs(x)); });
      indices.push_back(it == from_axis.end() ? -1 : static_cast<int>(it - from_axis.begin()));
    }
    return indices;
  };
  const std::vector<int> speeds = match(from.speeds_kmh, grid.speeds_kmh);
  const std::vector<int> steps = match(from.step_lengths_m, grid.step_lengths_m);
  const std::vector<int> slopes = match(from.slopes_rad, grid.slopes_rad);
  GaitTable result;
  result.grid = grid;
  result.body = table.body;
  result.fixed = table.fixed;
  result.swing_bounds = table.swing_bounds;
  result.entries.resize(grid.size());
  for (int i = 0; i < grid.size(); ++i) {
    const auto c = grid.cell(i);
    if (speeds[c[0]] >= 0 && steps[c[1]] >= 0 && slopes[c[2]] >= 0)
      result.entries[i] = table.entries[from.index(speeds[c[0]], steps[c[1]], slopes[c[2]])];
  }
  return result;
}

std::string InterpolationNote::describe(const GaitGrid& grid) const {
  if (exact()) return "";
  auto point = [&](int index) {
    const auto c = grid.cell(index);
    std::ostringstream p;
    p << grid.speeds_kmh[c[0]] << " km/h, " << grid.step_lengths_m[c[1]] << " m, " << grid.slopes_rad[c[2]] << " rad";
    return p.str();
  };
  std::ostringstream message;
  message << "the gait table has no feasible gait at ";
  for (size_t i = 0; i < missing.size(); ++i) message << (i ? "; " : "") << point(missing[i]);
  if (nearest >= 0)
    message << ", and none around the target: took the nearest feasible gait, at " << point(nearest);
  else
    message << ": interpolated between the cell's other gaits";
  return message.str();
}

Gait interpolateGait(const GaitTable& table, double speed_kmh, double step_length_m,
                     double slope_rad, InterpolationNote* note) {
  const GaitGrid& g = table.grid;
  const auto [iv, tv] = locate(g.speeds_kmh, speed_kmh, "speed", "km/h");
  const auto [il, tl] = locate(g.step_lengths_m, step_length_m, "step length", "m");
  const auto [is, ts] = locate(g.slopes_rad, slope_rad, "slope", "rad");

  // The corners that weigh, and how much of their weight has a feasible gait.
  std::array<double, 8> weight{};
  std::array<int, 8> index{};
  InterpolationNote found;
  double feasible_weight = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const int dv = corner & 1, dl = (corner >> 1) & 1, ds = (corner >> 2) & 1;
    weight[corner] = (dv ? tv : 1 - tv) * (dl ? tl : 1 - tl) * (ds ? ts : 1 - ts);
    index[corner] = g.index(iv + dv, il + dl, is + ds);
    if (weight[corner] == 0) continue;  // exactly on a face: this corner does not contribute
    if (table.entries.at(index[corner]).feasible)
      feasible_weight += weight[corner];
    else
      found.missing.push_back(index[corner]);
  }
  if (feasible_weight == 0) {
    // No feasible gait around the target: the nearest feasible grid point, in grid steps, at
    // the grid slope nearest the target's if it has one (see the header).
    const std::array<double, 3> at{iv + tv, il + tl, is + ts};
    const int target_slope = static_cast<int>(std::lround(is + ts));
    double best = std::numeric_limits<double>::infinity();
    for (const bool same_slope : {true, false}) {
      for (int i = 0; i < g.size(); ++i) {
        if (!table.entries[i].feasible) continue;
        const auto c = g.cell(i);
        if (same_slope && c[2] != target_slope) continue;
        double d = 0;
        for (int axis = 0; axis < 3; ++axis) d += (c[axis] - at[axis]) * (c[axis] - at[axis]);
        if (d < best) best = d, found.nearest = i;
      }
      if (found.nearest >= 0) break;
    }
    if (found.nearest < 0) throw std::out_of_range("the gait table has no feasible gait");
    weight.fill(0);
    weight[0] = 1;
    index[0] = found.nearest;
    feasible_weight = 1;
  }

  ControlVector controls{};
  Gait result;
  result.start.q.setZero();
  result.start.qdot.setZero();
  double best_weight = -1;
  for (int corner = 0; corner < 8; ++corner) {
    const GaitTableEntry& e = table.entries.at(index[corner]);
    if (weight[corner] == 0 || !e.feasible) continue;
    const double w = weight[corner] / feasible_weight;
    const ControlVector c = toControlVector(e.gait.controls);
    for (int k = 0; k < kNumControls; ++k) controls[k] += w * c[k];
    result.start.q += w * e.gait.start.q;
    result.start.qdot += w * e.gait.start.qdot;
    if (w > best_weight) {
      best_weight = w;
      result.start.knee_on_limit = e.gait.start.knee_on_limit;
    }
  }
  result.target = g.target(speed_kmh, step_length_m, slope_rad);
  result.controls = fromControlVector(controls, slope_rad);
  if (note) *note = found;
  return result;
}

}  // namespace kneed_walker::core::gait
