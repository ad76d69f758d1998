// Spinning until a condition holds, for the rostests' gtest nodes.
#pragma once

#include <ros/ros.h>

namespace kneed_walker::ros_glue::test {

// Spins the global callback queue until pred() holds or timeout_s passes; returns pred().
template <typename Pred>
bool waitFor(Pred pred, double timeout_s) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (!pred() && ros::WallTime::now() < deadline && ros::ok()) {
    ros::spinOnce();
    ros::WallDuration(0.002).sleep();
  }
  return pred();
}

}  // namespace kneed_walker::ros_glue::test
