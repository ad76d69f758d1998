#include "kneed_walker/core/gait/gait_norms.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace kneed_walker::core::gait {

namespace {

std::vector<std::string> splitCsvRow(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream row(line);
  for (std::string cell; std::getline(row, cell, ',');) {
    if (!cell.empty() && cell.back() == '\r') cell.pop_back();
    cells.push_back(cell);
  }
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

double parseNumber(const std::string& text, const std::string& where) {
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(value))
    throw std::runtime_error(where + ": '" + text + "' is not a finite number");
  return value;
}

}  // namespace

double NormCurve::meanAt(double phase) const {
  const double p = phase - std::floor(phase);
  const auto upper = std::upper_bound(cycle.begin(), cycle.end(), p);
  if (upper == cycle.end()) return mean.back();
  const std::size_t i = static_cast<std::size_t>(upper - cycle.begin());  // cycle[i-1] <= p < cycle[i]
  const double f = (p - cycle[i - 1]) / (cycle[i] - cycle[i - 1]);
  return (1 - f) * mean[i - 1] + f * mean[i];
}

const NormCurve& NormSpeedClass::curve(const std::string& angle) const {
  const auto found = curves.find(angle);
  if (found == curves.end()) throw std::out_of_range("gait norms: speed class '" + name + "' has no '" + angle + "' curve");
  return found->second;
}

const NormSpeedClass& GaitNorms::speedClass(const std::string& name) const {
  for (const NormSpeedClass& c : classes)
    if (c.name == name) return c;
  std::string known;
  for (const NormSpeedClass& c : classes) known += (known.empty() ? "'" : ", '") + c.name + "'";
  throw std::out_of_range(source + " has no speed class '" + name + "' (it has " + known + ")");
}

GaitNorms loadGaitNorms(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error(path + ": cannot read the gait norms");
  GaitNorms norms;
  norms.source = path;
  std::string header, subheader, line;
  if (!std::getline(file, header) || !std::getline(file, subheader))
    throw std::runtime_error(path + ": not a gait-norms table (no header rows)");
  const std::vector<std::string> names = splitCsvRow(header);
  std::vector<std::size_t> first_column;  // each class's −1sd column
  for (std::size_t c = 2; c < names.size(); ++c)
    if (!names[c].empty()) {
      norms.classes.push_back({names[c], {}});
      first_column.push_back(c);
    }
  if (norms.classes.empty()) throw std::runtime_error(path + ": not a gait-norms table (no speed classes in the header)");
  const std::size_t columns = first_column.back() + 3;
  for (int row = 3; std::getline(file, line); ++row) {
    if (line.empty() || line == "\r") continue;
    const std::vector<std::string> cells = splitCsvRow(line);
    const std::string where = path + " row " + std::to_string(row);
    if (cells.size() < columns)
      throw std::runtime_error(where + ": " + std::to_string(cells.size()) + " columns, expected " + std::to_string(columns));
    const double cycle = parseNumber(cells[1], where);
    for (std::size_t k = 0; k < norms.classes.size(); ++k) {
      NormCurve& curve = norms.classes[k].curves[cells[0]];
      if (!curve.cycle.empty() && !(cycle > curve.cycle.back()))
        throw std::runtime_error(where + ": '" + cells[0] + "' cycle fractions must increase");
      curve.cycle.push_back(cycle);
      curve.low.push_back(parseNumber(cells[first_column[k]], where));
      curve.mean.push_back(parseNumber(cells[first_column[k] + 1], where));
      curve.high.push_back(parseNumber(cells[first_column[k] + 2], where));
    }
  }
  for (const auto& [angle, curve] : norms.classes.front().curves)
    if (curve.cycle.size() < 2 || curve.cycle.front() != 0.0 || curve.cycle.back() != 1.0)
      throw std::runtime_error(path + ": '" + angle + "' must run from cycle 0 to 1");
  if (norms.classes.front().curves.empty()) throw std::runtime_error(path + ": no curves");
  return norms;
}

}  // namespace kneed_walker::core::gait
