// A recording replayed through view.launch (viewing_a_recording.test): the body's tf frames,
// markers and poses come out, and no tracker is running.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include <string>
#include <vector>

#include "kneed_walker/BodyPose.h"
#include "wait_for.h"

namespace kneed_walker::ros_glue {
namespace {

using test::waitFor;

TEST(ViewingARecording, TfFramesMarkersAndPosesComeOutWithNoTracker) {
  ros::NodeHandle nh;
  tf2_ros::Buffer tf_buffer(ros::Duration(120.0));
  tf2_ros::TransformListener tf_listener(tf_buffer);
  int marker_messages = 0;
  std::vector<BodyPose> poses;
  ros::Subscriber markers_sub = nh.subscribe<visualization_msgs::MarkerArray>(
      "/kneed_walker/markers", 100, [&](const visualization_msgs::MarkerArrayConstPtr& m) { marker_messages += !m->markers.empty(); });
  ros::Subscriber pose_sub =
      nh.subscribe<BodyPose>("/kneed_walker/body_pose", 100, [&](const BodyPoseConstPtr& p) { poses.push_back(*p); });
  ASSERT_TRUE(waitFor([&] { return marker_messages >= 5 && poses.size() >= 5; }, 90.0))
      << marker_messages << " marker messages and " << poses.size() << " poses came out of the recording";
  // The body's joint frames at a recorded pose's time, from the recorded /tf.
  const BodyPose& pose = poses.back();
  ASSERT_TRUE(waitFor([&] { return tf_buffer.canTransform(pose.header.frame_id, "l_ankle_" + pose.body_id, pose.header.stamp); }, 10.0))
      << "no tf from " << pose.header.frame_id << " to l_ankle_" << pose.body_id << " at " << pose.header.stamp;
  const geometry_msgs::TransformStamped ankle =
      tf_buffer.lookupTransform(pose.header.frame_id, "l_ankle_" + pose.body_id, pose.header.stamp);
  for (size_t j = 0; j < pose.joint_names.size(); ++j)
    if (pose.joint_names[j] == "l_ankle") {
      EXPECT_NEAR(ankle.transform.translation.x, pose.joint_positions[j].x, 1e-9);
      EXPECT_NEAR(ankle.transform.translation.z, pose.joint_positions[j].z, 1e-9);
    }
  ros::V_string nodes;
  ASSERT_TRUE(ros::master::getNodes(nodes));
  for (const std::string& node : nodes) EXPECT_EQ(node.find("kneed_walker"), std::string::npos) << "a tracker is running: " << node;
  std::printf("from the recording: %d marker messages, %zu poses, tf of l_ankle_%s; nodes: %zu\n", marker_messages,
              poses.size(), pose.body_id.c_str(), nodes.size());
}

}  // namespace
}  // namespace kneed_walker::ros_glue

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_viewing_a_recording");
  ros::NodeHandle keep_alive;
  return RUN_ALL_TESTS();
}
