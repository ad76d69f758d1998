#include "kneed_walker/ros/bag_writing.h"

#include <boost/make_shared.hpp>
#include <tf2_msgs/TFMessage.h>

#include "kneed_walker/ros/conversions.h"

namespace kneed_walker::ros_glue {

void writeStaticCameraPose(rosbag::Bag& bag, const core::vision::Camera& camera, const std::string& world_frame,
                           const std::string& camera_frame, const ros::Time& stamp, const std::string& caller_id) {
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(cameraPose(camera, world_frame, camera_frame));
  tf.transforms.back().header.stamp = stamp;
  // A header given to rosbag replaces its own, so it carries the message's type too.
  auto latched = boost::make_shared<ros::M_string>();
  (*latched)["type"] = ros::message_traits::datatype(tf);
  (*latched)["md5sum"] = ros::message_traits::md5sum(tf);
  (*latched)["message_definition"] = ros::message_traits::definition(tf);
  (*latched)["latching"] = "1";
  (*latched)["callerid"] = caller_id;
  bag.write("/tf_static", stamp, tf, latched);
}

}  // namespace kneed_walker::ros_glue
