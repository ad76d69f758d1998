// Checks of the tools' numeric options: CLI11's Range and PositiveNumber let NaN through (a NaN
// compares false), so every numeric option of a tool is checked here for finiteness too. The
// message CLI11 prints names the option: "--fps: nan is not a finite number in [1, 240]".
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <type_traits>
#include <variant>

#include "kneed_walker/core/common/option_table.h"

namespace kneed_walker::tools {

// Refuses an empty argument ("") before CLI11 parses: CLI11 2.1 loops forever on one inside a
// multi-value option followed by another option (--init-box 1 2 3 "" --out-csv e.csv). Prints
// "<tool>: ..." naming the option it follows and returns false.
inline bool refuseEmptyArguments(const char* tool, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (argv[i][0] != '\0') continue;
    int option = i - 1;
    while (option > 0 && argv[option][0] != '-') --option;
    std::fprintf(stderr, "%s: argument %d is empty%s%s: give a value\n", tool, i, option > 0 ? " after " : "",
                 option > 0 ? argv[option] : "");
    return false;
  }
  return true;
}

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

// Every option of a table as a command-line option: the table's snake_case name in kebab-case
// (num_particles: --num-particles), its help and unit, its default shown, numbers checked against
// its range, flags given as true or false (--use-optical-flow false).
template <class Options>
void addTableOptions(CLI::App& app, const core::common::OptionTable<Options>& table, Options& options) {
  for (const core::common::OptionSpec<Options>& spec : table) {
    std::string help = spec.help;
    if (*spec.unit) help += std::string(", ") + spec.unit;
    std::visit(
        [&](auto* value) {
          CLI::Option* option =
              app.add_option("--" + core::common::kebabCase(spec.name), *value, help)->capture_default_str();
          if constexpr (!std::is_same_v<decltype(value), bool*>) option->check(FiniteRange(spec.min, spec.max));
        },
        spec.field(options));
  }
}

}  // namespace kneed_walker::tools
