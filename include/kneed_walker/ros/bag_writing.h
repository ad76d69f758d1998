// Writing camera streams into rosbags as a camera driver would publish them (make_synthetic,
// video_to_bag): the images with their camera_info, and the camera's pose on /tf_static.
#pragma once

#include <rosbag/bag.h>
#include <ros/time.h>

#include <string>

#include "kneed_walker/core/vision/camera.h"

namespace kneed_walker::ros_glue {

// The camera's pose (world_frame -> camera_frame) on /tf_static at `stamp`, on a latched
// connection as tf2's static broadcaster makes it, so that a player and tf see it as static.
void writeStaticCameraPose(rosbag::Bag& bag, const core::vision::Camera& camera, const std::string& world_frame,
                           const std::string& camera_frame, const ros::Time& stamp, const std::string& caller_id);

}  // namespace kneed_walker::ros_glue
