#include "kneed_walker/core/common/option_table.h"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace kneed_walker::core::common {

std::string kebabCase(const std::string& snake_case) {
  std::string kebab = snake_case;
  for (char& c : kebab)
    if (c == '_') c = '-';
  return kebab;
}

std::string valueText(const OptionField& field) {
  std::ostringstream text;
  std::visit(
      [&](auto* value) {
        if constexpr (std::is_same_v<decltype(value), bool*>) {
          text << (*value ? "true" : "false");
        } else if constexpr (std::is_same_v<decltype(value), double*>) {
          const double v = *value;
          if (std::isfinite(v) && v == std::floor(v) && std::abs(v) < 1e20)
            text << std::fixed << std::setprecision(0) << v;  // 1000000, not 1e+06
          else
            text << std::setprecision(10) << v;
        } else {
          text << *value;
        }
      },
      field);
  return text.str();
}

bool inRange(const OptionField& field, double min, double max) {
  return std::visit(
      [&](auto* value) {
        if constexpr (std::is_same_v<decltype(value), bool*>) {
          return true;
        } else {
          const double v = static_cast<double>(*value);
          return std::isfinite(v) && v >= min && v <= max;
        }
      },
      field);
}

}  // namespace kneed_walker::core::common
