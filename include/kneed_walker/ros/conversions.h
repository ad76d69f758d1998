// Every conversion between ROS messages and the core, in one unit-tested place
// (cartographer_ros' msg_conversion.h): nothing else in the package looks inside a message.
#pragma once

#include <geometry_msgs/TransformStamped.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <string>

#include "kneed_walker/core/vision/camera.h"

namespace kneed_walker::ros_glue {

// Why an image + camera_info pair cannot be tracked on, or an empty string when it can:
// empty or inconsistent image buffers, unsupported encodings, camera_info of another size,
// non-positive or non-finite focal lengths, unknown distortion models, missing frame ids.
// The nodelet skips and counts such frames instead of failing on them.
std::string frameProblem(const sensor_msgs::Image& image, const sensor_msgs::CameraInfo& info);

// The intrinsics of a core camera as a CameraInfo (plumb_bob for up to 5 distortion
// coefficients, rational_polynomial for 8; R identity; P = [K | 0], a monocular camera).
sensor_msgs::CameraInfo toCameraInfo(const core::vision::Camera& camera, const std::string& frame_id);

// The camera's pose in the world: the transform from `world_frame` to the camera's optical
// frame (REP 103 `_optical`: z forward, x right, y down), as tf2 publishes it.
geometry_msgs::TransformStamped cameraPose(const core::vision::Camera& camera, const std::string& world_frame,
                                           const std::string& camera_frame);

// A core camera from CameraInfo intrinsics and the camera's pose in the world (the inverse of
// the two above). Throws std::invalid_argument naming what is wrong.
core::vision::Camera toCamera(const sensor_msgs::CameraInfo& info, const geometry_msgs::TransformStamped& pose);

}  // namespace kneed_walker::ros_glue
