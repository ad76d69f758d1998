// Checks of the tools' numeric options: CLI11's Range and PositiveNumber let NaN through (a NaN
// compares false), so every numeric option of a tool is checked here for finiteness too. The
// message CLI11 prints names the option: "--fps: nan is not a finite number in [1, 240]".
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <sstream>
#include <string>

namespace kneed_walker::tools {

// A finite number in [min, max].
inline CLI::Validator FiniteRange(double min, double max) {
  std::ostringstream range;
  range << "[" << min << ", " << max << "]";
  return CLI::Validator(
      [min, max, range = range.str()](std::string& text) -> std::string {
        double value = 0;
        try {
          size_t used = 0;
          value = std::stod(text, &used);
          if (used != text.size()) return text + " is not a number";
        } catch (const std::exception&) {
          return text + " is not a number";
        }
        if (!std::isfinite(value) || value < min || value > max)
          return text + " is not a finite number in " + range;
        return std::string();
      },
      "FINITE in " + range.str());
}

}  // namespace kneed_walker::tools
