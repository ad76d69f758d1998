// One table per options struct: each option's name, range, unit and help beside the member it
// sets. Its default is the struct's member initialiser and nowhere else. From the table come
// the range checks of validate(), the nodelet's parameter reader (the snake_case name), the
// tools' command-line options (the same words in kebab-case: `--min-gait-speed-kmh`) and the
// documentation; a test checks config/tracker.yaml and cfg/Tracker.cfg against the tables.
//
//   const OptionTable<FooOptions>& fooOptionTable() {
//     static const OptionTable<FooOptions> table{
//         {"rate_hz", [](FooOptions& o) -> OptionField { return &o.rate_hz; }, 0.1, 100, "Hz", "how often"}};
//     return table;
//   }
#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

namespace kneed_walker::core::common {

// Where an option's value lives inside its struct.
using OptionField = std::variant<int*, double*, bool*, std::uint64_t*>;

template <class Options>
struct OptionSpec {
  const char* name;                // snake_case, as the ROS parameter
  OptionField (*field)(Options&);  // the member it sets
  double min = 0, max = 0;         // numbers: the allowed range, inclusive (flags: unused)
  const char* unit = "";           // "m", "km/h", ...; "" for counts, fractions and flags
  const char* help = "";           // one line for people
};

template <class Options>
using OptionTable = std::vector<OptionSpec<Options>>;

// "min_gait_speed_kmh" -> "min-gait-speed-kmh".
std::string kebabCase(const std::string& snake_case);

// The value as people write it: "5000", "0.95", "true".
std::string valueText(const OptionField& field);

// Whether a field's value is a finite number inside [min, max] (flags: always).
bool inRange(const OptionField& field, double min, double max);

// "name = value is outside [min, max] (help)" for every option of `options` that is not a finite
// number in its range.
template <class Options>
std::vector<std::string> rangeProblems(const Options& options, const OptionTable<Options>& table) {
  Options& readable = const_cast<Options&>(options);  // the fields are only read
  std::vector<std::string> problems;
  for (const OptionSpec<Options>& spec : table) {
    const OptionField field = spec.field(readable);
    if (inRange(field, spec.min, spec.max)) continue;
    problems.push_back(std::string(spec.name) + " = " + valueText(field) + " is outside [" +
                       valueText(OptionField(const_cast<double*>(&spec.min))) + ", " +
                       valueText(OptionField(const_cast<double*>(&spec.max))) + "] (" + spec.help + ")");
  }
  return problems;
}

}  // namespace kneed_walker::core::common
