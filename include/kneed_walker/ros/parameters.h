// Loading the tracker nodelet's private parameters into the core's options, in one place.
//
// Every parameter is documented in config/tracker.yaml and the README's "ROS API" section.
// A parameter of the wrong type, out of range, or not known at all (a typo) makes
// loadTrackerNodeConfig throw std::invalid_argument naming each offending parameter, so
// the nodelet refuses to start rather than run with a value nobody asked for.
#pragma once

#include <ros/node_handle.h>

#include <string>

#include "kneed_walker/core/tracking/tracker_options.h"

namespace kneed_walker::ros_glue {

// Options of the ROS wrapper itself (not of the tracking algorithm).
struct RosInterfaceOptions {
  std::string world_frame = "world";  // frame of the published poses (REP 105 style)
  std::string body_id = "1";          // REP 155 body id: root frame "body_<body_id>"
  int image_queue_size = 2;           // input queue; older frames are dropped and counted
  bool publish_particle_cloud = true;  // ~particle_cloud (geometry_msgs/PoseArray)
  bool publish_tf = true;              // body_<id> and joint frames on /tf
};

struct TrackerNodeConfig {
  core::tracking::TrackerOptions tracker;
  RosInterfaceOptions ros;
};

// Reads all parameters under private_nh's namespace. Throws std::invalid_argument listing
// every problem (one per line) when any is found.
TrackerNodeConfig loadTrackerNodeConfig(const ros::NodeHandle& private_nh);

}  // namespace kneed_walker::ros_glue
