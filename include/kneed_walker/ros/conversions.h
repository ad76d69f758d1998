// Every conversion between ROS messages and the core, in one unit-tested place
// (cartographer_ros' msg_conversion.h): nothing else in the package looks inside a message.
#pragma once

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <string>

namespace kneed_walker {

// Why an image + camera_info pair cannot be tracked on, or an empty string when it can:
// empty or inconsistent image buffers, unsupported encodings, camera_info of another size,
// non-positive or non-finite focal lengths, unknown distortion models, missing frame ids.
// The nodelet skips and counts such frames instead of failing on them.
std::string frameProblem(const sensor_msgs::Image& image, const sensor_msgs::CameraInfo& info);

}  // namespace kneed_walker
