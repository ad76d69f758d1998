// The package's shipped configuration, for the core's tests.
#pragma once

#include <string>

#include "kneed_walker/core/dynamics/walker_model.h"

namespace kneed_walker::core::test {

inline std::string configFile(const std::string& name) {
  return std::string(KNEED_WALKER_SOURCE_DIR) + "/config/" + name;
}

// The walker model that the shipped gait tables were optimised for.
inline const dynamics::BodyProportions& shippedWalkerModel() {
  static const dynamics::BodyProportions model = dynamics::loadBodyProportions(configFile("walker_model.yaml"));
  return model;
}

}  // namespace kneed_walker::core::test
