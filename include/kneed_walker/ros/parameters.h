// Loading the tracker nodelet's private parameters into the core's options, in one place.
//
// Every parameter is read by its name in an option table (the core's TrackerOptions,
// LikelihoodOptions and SessionOptions, and RosInterfaceOptions here), whose default is the
// struct's; config/tracker.yaml documents them all (a test checks that it agrees with the tables).
// A parameter of the wrong type, out of range, or not known at all (a typo) makes
// loadTrackerNodeConfig throw std::invalid_argument naming each offending parameter, so
// the nodelet refuses to start rather than run with a value nobody asked for.
#pragma once

#include <ros/node_handle.h>

#include <string>
#include <vector>

#include "kneed_walker/core/tracking/tracker_options.h"
#include "kneed_walker/core/tracking/tracking_session.h"
#include "kneed_walker/core/vision/likelihood.h"

namespace kneed_walker::ros_glue {

// Options of the ROS wrapper itself (not of the tracking algorithm).
struct RosInterfaceOptions {
  std::string world_frame = "world";  // frame of the published poses (REP 105 style)
  std::string image_transport = "raw";  // raw or compressed (image_transport plugins)
  int image_queue_size = 150;         // frames waiting while one is tracked; a full queue drops its oldest (counted)
  // Each frame's tracking fits into this fraction of the frame interval (from the stamps): the
  // particle count adapts within [min_particles, num_particles] (TrackerOptions, which gets them).
  double frame_budget_fraction = 0.8;
  int min_particles = 500;
  bool publish_particle_cloud = true;  // ~particle_cloud (geometry_msgs/PoseArray)
  double particle_cloud_interval_s = 0.5;  // at most one ~particle_cloud per this interval, s
  bool publish_tf = true;              // body_<id> and joint frames on /tf
  bool publish_overlay = true;         // ~overlay (sensor_msgs/Image): the body drawn on the frame
  // The camera: a calibration file (OpenCV YAML as make_synthetic writes, with the ground
  // plane) or, empty, camera_info's intrinsics and tf's world -> camera_info frame.
  std::string camera_file;
  double camera_file_unit_m = 0.001;   // metres per unit of the file's translation
  std::vector<double> init_box;        // the person's box in the first tracked frame, x1 y1 x2 y2, px (empty: find them)
  // The model's files; empty: the package's config/.
  std::string gait_table, prior_config, walker_model;
  double prior_noise_scale = 1.0;      // factor on the prior's torque noise scales s_j (eq. 11)
};
// Its numbers and flags: name, range, unit, help (core/common/option_table.h).
const core::common::OptionTable<RosInterfaceOptions>& rosInterfaceOptionTable();

struct TrackerNodeConfig {
  core::tracking::TrackerOptions tracker;
  core::vision::LikelihoodOptions likelihood;
  core::tracking::SessionOptions session;
  RosInterfaceOptions ros;
};

// The documentation of every parameter read from an option table, as a Markdown table
// (parameter, default, unit, range, meaning): the README's, checked by a test.
std::string parameterTableMarkdown();

// Reads all parameters under private_nh's namespace. Throws std::invalid_argument listing
// every problem (one per line) when any is found.
TrackerNodeConfig loadTrackerNodeConfig(const ros::NodeHandle& private_nh);

}  // namespace kneed_walker::ros_glue
