#include "kneed_walker/core/gait_table.h"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "read_file_storage.h"

namespace kneed_walker {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::vector<double> linspace(double from, double to, int n) {
  std::vector<double> v(n);
  for (int i = 0; i < n; ++i) v[i] = from + (to - from) * i / (n - 1);
  return v;
}

// The spring parameters and impulse as a flat list, in a fixed order (file and interpolation).
constexpr int kNumControls = 10;
std::array<double, kNumControls> flatten(const WalkerControls& c) {
  const SpringParameters& s = c.springs;
  return {s.stance_knee_stiffness, s.stance_knee_damping, s.swing_knee_stiffness,
          s.swing_knee_rest_angle, s.swing_knee_damping,  s.hip_stiffness,
          s.torso_stiffness,       s.torso_rest_angle,    s.torso_damping,
          c.toe_off_impulse};
}
WalkerControls unflatten(const std::array<double, kNumControls>& v, double slope) {
  WalkerControls c;
  SpringParameters& s = c.springs;
  s.stance_knee_stiffness = v[0];
  s.stance_knee_damping = v[1];
  s.swing_knee_stiffness = v[2];
  s.swing_knee_rest_angle = v[3];
  s.swing_knee_damping = v[4];
  s.hip_stiffness = v[5];
  s.torso_stiffness = v[6];
  s.torso_rest_angle = v[7];
  s.torso_damping = v[8];
  c.toe_off_impulse = v[9];
  c.ground_slope = slope;
  return c;
}

std::vector<double> toVector(const Vector5& v) { return {v.data(), v.data() + v.size()}; }

// Reads a list of exactly n numbers, or throws naming the key.
std::vector<double> readList(const cv::FileNode& node, const std::string& key, size_t n,
                             const std::string& where) {
  std::vector<double> v;
  if (!node[key].empty()) node[key] >> v;
  if (v.size() != n && n != 0)
    throw std::invalid_argument(where + ": " + key + " must hold " + std::to_string(n) +
                                " numbers, holds " + std::to_string(v.size()));
  return v;
}

void requireAscending(const std::vector<double>& axis, const std::string& name,
                      const std::string& path) {
  if (axis.size() < 2 || !std::is_sorted(axis.begin(), axis.end()) ||
      std::adjacent_find(axis.begin(), axis.end()) != axis.end())
    throw std::invalid_argument(path + ": " + name + " must hold at least two ascending values");
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

GaitTarget GaitGrid::target(double speed_kmh, double step_length_m, double slope_rad) const {
  const double leg = referenceLegLength();
  return {speed_kmh / 3.6 / std::sqrt(gravity * leg), step_length_m / leg, slope_rad};
}

GaitTarget GaitGrid::target(int index) const {
  const auto c = cell(index);
  return target(speeds_kmh[c[0]], step_lengths_m[c[1]], slopes_rad[c[2]]);
}

void saveGaitTable(const std::string& path, const GaitTable& table) {
  cv::FileStorage file(path, cv::FileStorage::WRITE);
  if (!file.isOpened()) throw std::invalid_argument(path + ": cannot write");
  const GaitGrid& g = table.grid;
  file.writeComment(
      "Optimal cyclic gaits of the Kneed Walker (paper 3.3), written by\n"
      "`rosrun kneed_walker optimize_gaits`. Dimensionless units: leg length 1, body mass 1,\n"
      "g 1; the axes are for a person of reference_height_m. controls: stance knee stiffness,\n"
      "damping; swing knee stiffness, rest angle, damping; hip stiffness; torso stiffness,\n"
      "rest angle, damping; toe-off impulse. q, qdot: post-heel-strike state x0.");
  file << "reference_height_m" << g.reference_height_m;
  file << "leg_length_per_height" << g.leg_length_per_height;
  file << "gravity" << g.gravity;
  file << "speeds_kmh" << g.speeds_kmh << "step_lengths_m" << g.step_lengths_m << "slopes_rad"
       << g.slopes_rad;
  if (table.fixed.enabled) {
    file.writeComment("Held fixed while optimising (the prior's values, paper 3.4): knee damping,\n"
                      "swing knee stiffness, torso rest angle per slope, torso damping.");
    file << "fixed_controls"
         << std::vector<double>{table.fixed.knee_damping, table.fixed.swing_knee_stiffness,
                                table.fixed.torso_rest_per_slope, table.fixed.torso_damping};
  }
  file << "gaits" << "[";
  for (size_t i = 0; i < table.entries.size(); ++i) {
    const GaitTableEntry& e = table.entries[i];
    file << "{" << "index" << static_cast<int>(i) << "solved" << static_cast<int>(e.solved)
         << "feasible" << static_cast<int>(e.feasible);
    if (e.solved) {
      const OptimalGait& gait = e.gait;
      const auto controls = flatten(gait.controls);
      file << "target"
           << std::vector<double>{gait.target.speed, gait.target.step_length, gait.target.slope}
           << "controls" << std::vector<double>(controls.begin(), controls.end()) << "q"
           << toVector(gait.start.q) << "qdot" << toVector(gait.start.qdot) << "knees_locked"
           << std::vector<int>{gait.start.knee_on_limit[0], gait.start.knee_on_limit[1]}
           << "duration" << gait.stride.duration << "speed" << gait.stride.speed
           << "step_length" << gait.stride.step_length << "effort" << gait.effort
           << "periodicity_residual" << gait.periodicity_residual << "nlopt_result"
           << gait.nlopt_result << "evaluations" << gait.evaluations;
    }
    file << "}";
  }
  file << "]";
}

GaitTable loadGaitTable(const std::string& path) {
  cv::FileStorage file = readFileStorage(path, "gait table");
  GaitTable table;
  GaitGrid& g = table.grid;
  file["reference_height_m"] >> g.reference_height_m;
  file["leg_length_per_height"] >> g.leg_length_per_height;
  file["gravity"] >> g.gravity;
  const cv::FileNode root = file.root();
  g.speeds_kmh = readList(root, "speeds_kmh", 0, path);
  g.step_lengths_m = readList(root, "step_lengths_m", 0, path);
  g.slopes_rad = readList(root, "slopes_rad", 0, path);
  requireAscending(g.speeds_kmh, "speeds_kmh", path);
  requireAscending(g.step_lengths_m, "step_lengths_m", path);
  requireAscending(g.slopes_rad, "slopes_rad", path);
  if (!(g.reference_height_m > 0 && g.leg_length_per_height > 0 && g.gravity > 0))
    throw std::invalid_argument(path + ": reference_height_m, leg_length_per_height and gravity "
                                "must be positive");

  if (!file["fixed_controls"].empty()) {
    const auto fixed = readList(root, "fixed_controls", 4, path);
    table.fixed = {true, fixed[0], fixed[1], fixed[2], fixed[3]};
  }

  const cv::FileNode gaits = file["gaits"];
  if (!gaits.isSeq() || static_cast<int>(gaits.size()) != g.size())
    throw std::invalid_argument(path + ": gaits must list " + std::to_string(g.size()) +
                                " grid points");
  table.entries.resize(g.size());
  for (int i = 0; i < g.size(); ++i) {
    const cv::FileNode node = gaits[i];
    const std::string where = path + ": gait " + std::to_string(i);
    if (static_cast<int>(node["index"]) != i)
      throw std::invalid_argument(where + " is out of order (index " +
                                  std::to_string(static_cast<int>(node["index"])) + ")");
    GaitTableEntry& e = table.entries[i];
    e.solved = static_cast<int>(node["solved"]) != 0;
    e.feasible = static_cast<int>(node["feasible"]) != 0;
    if (!e.solved) continue;
    OptimalGait& gait = e.gait;
    const auto target = readList(node, "target", 3, where);
    gait.target = {target[0], target[1], target[2]};
    const auto controls = readList(node, "controls", kNumControls, where);
    std::array<double, kNumControls> flat;
    std::copy(controls.begin(), controls.end(), flat.begin());
    gait.controls = unflatten(flat, gait.target.slope);
    const auto q = readList(node, "q", kNumCoordinates, where);
    const auto qdot = readList(node, "qdot", kNumCoordinates, where);
    for (int j = 0; j < kNumCoordinates; ++j) {
      gait.start.q[j] = q[j];
      gait.start.qdot[j] = qdot[j];
    }
    std::vector<int> knees;
    node["knees_locked"] >> knees;
    if (knees.size() != kNumKnees) throw std::invalid_argument(where + ": knees_locked needs 2 flags");
    gait.start.knee_on_limit = {knees[0] != 0, knees[1] != 0};
    node["duration"] >> gait.stride.duration;
    node["speed"] >> gait.stride.speed;
    node["step_length"] >> gait.stride.step_length;
    node["effort"] >> gait.effort;
    node["periodicity_residual"] >> gait.periodicity_residual;
    node["nlopt_result"] >> gait.nlopt_result;
    node["evaluations"] >> gait.evaluations;
  }
  return table;
}

int keepLowerEffort(GaitTable& table, const GaitTable& other) {
  const GaitGrid &a = table.grid, &b = other.grid;
  if (a.speeds_kmh != b.speeds_kmh || a.step_lengths_m != b.step_lengths_m ||
      a.slopes_rad != b.slopes_rad || a.reference_height_m != b.reference_height_m ||
      a.leg_length_per_height != b.leg_length_per_height || a.gravity != b.gravity)
    throw std::invalid_argument("keepLowerEffort: the gait tables have different grids");
  const FixedControls &fa = table.fixed, &fb = other.fixed;
  if (fa.enabled != fb.enabled ||
      (fa.enabled && (fa.knee_damping != fb.knee_damping || fa.swing_knee_stiffness != fb.swing_knee_stiffness ||
                      fa.torso_rest_per_slope != fb.torso_rest_per_slope || fa.torso_damping != fb.torso_damping)))
    throw std::invalid_argument("keepLowerEffort: the gait tables hold different controls fixed");
  int taken = 0;
  for (size_t i = 0; i < table.entries.size(); ++i) {
    const GaitTableEntry& theirs = other.entries[i];
    GaitTableEntry& ours = table.entries[i];
    if (theirs.feasible && (!ours.feasible || theirs.gait.effort < ours.gait.effort)) {
      ours = theirs;
      ++taken;
    }
  }
  return taken;
}

OptimalGait interpolateGait(const GaitTable& table, double speed_kmh, double step_length_m,
                            double slope_rad) {
  const GaitGrid& g = table.grid;
  const auto [iv, tv] = locate(g.speeds_kmh, speed_kmh, "speed", "km/h");
  const auto [il, tl] = locate(g.step_lengths_m, step_length_m, "step length", "m");
  const auto [is, ts] = locate(g.slopes_rad, slope_rad, "slope", "rad");

  std::array<double, kNumControls> controls{};
  OptimalGait result;
  result.start.q.setZero();
  result.start.qdot.setZero();
  double best_weight = -1;
  for (int corner = 0; corner < 8; ++corner) {
    const int dv = corner & 1, dl = (corner >> 1) & 1, ds = (corner >> 2) & 1;
    const double w = (dv ? tv : 1 - tv) * (dl ? tl : 1 - tl) * (ds ? ts : 1 - ts);
    const int index = g.index(iv + dv, il + dl, is + ds);
    const GaitTableEntry& e = table.entries.at(index);
    if (!e.feasible) {
      if (w == 0) continue;  // exactly on a face: this corner does not contribute
      std::ostringstream message;
      message << "the gait table has no feasible gait at " << g.speeds_kmh[iv + dv] << " km/h, "
              << g.step_lengths_m[il + dl] << " m, " << g.slopes_rad[is + ds]
              << " rad, which the target needs";
      throw std::out_of_range(message.str());
    }
    const auto c = flatten(e.gait.controls);
    for (int k = 0; k < kNumControls; ++k) controls[k] += w * c[k];
    result.start.q += w * e.gait.start.q;
    result.start.qdot += w * e.gait.start.qdot;
    if (w > best_weight) {
      best_weight = w;
      result.start.knee_on_limit = e.gait.start.knee_on_limit;
    }
  }
  result.target = g.target(speed_kmh, step_length_m, slope_rad);
  result.controls = unflatten(controls, slope_rad);
  return result;
}

}  // namespace kneed_walker
