// A synthetic bag through track.launch bag:= record:= (playing_a_bag.test): the joints from tf
// and from ~body_pose agree, stay within check_tracking's loose bound of the truth, and every
// frame of the bag is answered or counted as dropped.
#include <Eigen/Core>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "joints_csv.h"
#include "kneed_walker/BodyPose.h"
#include "kneed_walker/TrackingStatus.h"
#include "wait_for.h"

namespace kneed_walker::ros_glue {
namespace {

using test::waitFor;

TEST(PlayingABag, JointsFromTfAndBodyPoseAgreeAndFollowTheTruthAndEveryFrameIsAccountedFor) {
  ros::NodeHandle nh, private_nh("~");
  std::string sequence;
  ASSERT_TRUE(private_nh.getParam("sequence", sequence));
  std::vector<ros::Time> image_stamps;
  {
    rosbag::Bag bag(sequence + ".bag");
    for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery("/camera/image_raw")))
      image_stamps.push_back(m.instantiate<sensor_msgs::Image>()->header.stamp);
  }
  ASSERT_GT(image_stamps.size(), 20u);
  // Truth by frame; frames found by stamp (the CSV's are to the microsecond).
  std::map<int, std::map<std::string, Eigen::Vector3d>> truth;
  std::map<int, double> truth_stamps;
  for (const test::JointRow& row : test::readJoints(sequence + "_ground_truth.csv")) {
    truth[row.frame][row.joint] = Eigen::Vector3d(row.x, row.y, row.z);
    truth_stamps[row.frame] = row.stamp;
  }
  auto frameAt = [&](const ros::Time& stamp) {
    for (const auto& [frame, s] : truth_stamps)
      if (std::abs(s - stamp.toSec()) < 1e-3) return frame;
    return -1;
  };

  tf2_ros::Buffer tf_buffer(ros::Duration(120.0));
  tf2_ros::TransformListener tf_listener(tf_buffer);
  std::map<ros::Time, BodyPose> poses;
  TrackingStatus last;
  ros::Subscriber pose_sub =
      nh.subscribe<BodyPose>("/kneed_walker/body_pose", 100, [&](const BodyPoseConstPtr& p) { poses[p->header.stamp] = *p; });
  ros::Subscriber status_sub =
      nh.subscribe<TrackingStatus>("/kneed_walker/status", 100, [&](const TrackingStatusConstPtr& s) { last = *s; });
  std::string dropped;  // /diagnostics' count of frames dropped from the full queue, last seen
  ros::Subscriber diagnostics_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 20, [&](const diagnostic_msgs::DiagnosticArrayConstPtr& d) {
        for (const diagnostic_msgs::DiagnosticStatus& status : d->status)
          for (const diagnostic_msgs::KeyValue& kv : status.values)
            if (kv.key == "frames dropped (arrived while busy)") dropped = kv.value;
      });
  // The bag plays at a quarter speed after a 2 s delay: 31 frames in about 14 s.
  ASSERT_TRUE(waitFor([&] { return last.header.stamp == image_stamps.back(); }, 180.0))
      << "the last frame was not answered; last status: " << last.message;
  ros::WallDuration(0.5).sleep();  // the last frame's tf and pose
  ros::spinOnce();

  EXPECT_EQ(last.frames_received, image_stamps.size());
  EXPECT_EQ(last.frames_processed + last.frames_skipped + last.frames_dropped, last.frames_received)
      << "frames neither processed nor counted as skipped or dropped";
  // ~image_queue_size (20 here) holds the frames that arrive while the held ones are answered:
  // none is dropped. (A frame may still be skipped: the first image can come before the bag's
  // /tf_static, and then the camera's pose is unknown.)
  ASSERT_TRUE(waitFor([&] { return !dropped.empty(); }, 10.0)) << "no /diagnostics from the tracker";
  EXPECT_EQ(dropped, "0") << "frames were dropped from the queue";
  ASSERT_GE(poses.size(), 10u) << "too few frames tracked: " << last.message;
  double tf_difference_m = 0, error_sum_m = 0;
  int joints = 0, looked_up = 0;
  for (const auto& [stamp, pose] : poses) {
    const int frame = frameAt(stamp);
    ASSERT_GE(frame, 0) << "a pose stamped " << stamp << " is no frame of the bag";
    for (size_t j = 0; j < pose.joint_names.size(); ++j) {
      const std::string& name = pose.joint_names[j];
      const Eigen::Vector3d p(pose.joint_positions[j].x, pose.joint_positions[j].y, pose.joint_positions[j].z);
      error_sum_m += (p - truth.at(frame).at(name)).norm();
      ++joints;
      const std::string tf_frame = name == "waist" ? "body_" + pose.body_id : name + "_" + pose.body_id;
      try {
        const geometry_msgs::TransformStamped t = tf_buffer.lookupTransform(pose.header.frame_id, tf_frame, stamp);
        const Eigen::Vector3d q(t.transform.translation.x, t.transform.translation.y, t.transform.translation.z);
        tf_difference_m = std::max(tf_difference_m, (q - p).norm());
        ++looked_up;
      } catch (const tf2::TransformException& e) {
        ADD_FAILURE() << "no tf for " << tf_frame << " at " << stamp << ": " << e.what();
      }
    }
  }
  const double mean_error_mm = 1000 * error_sum_m / joints;
  std::printf("bag frames %zu: answered %lu, dropped or skipped %lu; tracked %zu; tf vs body_pose: largest "
              "difference %.3g m over %d joints; mean joint error %.1f mm\n",
              image_stamps.size(), static_cast<unsigned long>(last.frames_processed),
              static_cast<unsigned long>(last.frames_skipped), poses.size(), tf_difference_m, looked_up, mean_error_mm);
  EXPECT_EQ(looked_up, joints);
  EXPECT_LT(tf_difference_m, 1e-9);
  EXPECT_LT(mean_error_mm, 350.0);  // test/ros/check_tracking's loose bound
}

}  // namespace
}  // namespace kneed_walker::ros_glue

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_playing_a_bag");
  ros::NodeHandle keep_alive;
  return RUN_ALL_TESTS();
}
