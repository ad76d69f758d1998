// Runs inside tracker_nodelet.test: a manager with kneed_walker/TrackerNodelet loaded as
// /kneed_walker, its input remapped to /camera/image_raw.
#include <gtest/gtest.h>
#include <nodelet/NodeletLoad.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>

#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>

#include "kneed_walker/TrackingStatus.h"
#include "kneed_walker/ros/parameters.h"

namespace kneed_walker::ros_glue {
namespace {

// Spins until pred() holds or timeout_s passes; returns pred().
template <typename Pred>
bool waitFor(Pred pred, double timeout_s) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (!pred() && ros::WallTime::now() < deadline && ros::ok()) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  return pred();
}

std::map<std::string, std::string> advertisedTopics() {
  ros::master::V_TopicInfo topics;
  ros::master::getTopics(topics);
  std::map<std::string, std::string> types;
  for (const auto& t : topics) types[t.name] = t.datatype;
  return types;
}

TEST(TrackerNodelet, PluginIsRegistered) {
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(
      popen("rospack plugins --attrib=plugin nodelet 2>&1", "r"), pclose);
  ASSERT_TRUE(pipe);
  std::string output;
  char buffer[512];
  while (fgets(buffer, sizeof buffer, pipe.get())) output += buffer;
  EXPECT_NE(output.find("kneed_walker "), std::string::npos) << output;
  EXPECT_NE(output.find("nodelet_plugins.xml"), std::string::npos) << output;
}

TEST(TrackerNodelet, AdvertisesItsOutputs) {
  const std::map<std::string, std::string> expected = {
      {"/kneed_walker/body_pose", "kneed_walker/BodyPose"},
      {"/kneed_walker/pose", "geometry_msgs/PoseWithCovarianceStamped"},
      {"/kneed_walker/walker_state", "kneed_walker/WalkerState"},
      {"/kneed_walker/status", "kneed_walker/TrackingStatus"},
      {"/kneed_walker/particle_cloud", "geometry_msgs/PoseArray"},
      {"/kneed_walker/markers", "visualization_msgs/MarkerArray"},
      {"/tf", "tf2_msgs/TFMessage"},
      {"/diagnostics", "diagnostic_msgs/DiagnosticArray"},
  };
  std::map<std::string, std::string> topics;
  waitFor([&] {
    topics = advertisedTopics();
    for (const auto& e : expected)
      if (topics.count(e.first) == 0) return false;
    return true;
  }, 30.0);
  for (const auto& e : expected) {
    ASSERT_EQ(topics.count(e.first), 1u) << e.first << " is not advertised";
    EXPECT_EQ(topics[e.first], e.second) << e.first;
  }
}

sensor_msgs::CameraInfo makeInfo(uint32_t width, uint32_t height) {
  sensor_msgs::CameraInfo info;
  info.width = width;
  info.height = height;
  info.K = {500, 0, width / 2.0, 0, 500, height / 2.0, 0, 0, 1};
  info.distortion_model = "plumb_bob";
  info.D = {0, 0, 0, 0, 0};
  return info;
}

sensor_msgs::Image makeImage(uint32_t width, uint32_t height) {
  sensor_msgs::Image image;
  image.width = width;
  image.height = height;
  image.encoding = sensor_msgs::image_encodings::BGR8;
  image.step = 3 * width;
  image.data.assign(static_cast<size_t>(image.step) * height, 128);
  return image;
}

TEST(TrackerNodelet, CountsGoodFramesAndSkipsBadOnes) {
  ros::NodeHandle nh;
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("/camera/image_raw", 10);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("/camera/camera_info", 10);
  TrackingStatus last;
  int received = 0;
  ros::Subscriber status_sub = nh.subscribe<TrackingStatus>(
      "/kneed_walker/status", 10, [&](const TrackingStatusConstPtr& s) {
        last = *s;
        ++received;
      });
  ASSERT_TRUE(waitFor([&] {
    return image_pub.getNumSubscribers() > 0 && info_pub.getNumSubscribers() > 0 &&
           status_sub.getNumPublishers() > 0;
  }, 30.0)) << "the nodelet did not subscribe to /camera/image_raw + /camera/camera_info";

  // One good frame, then one whose camera_info has no focal length, then one older than the
  // last accepted frame. Each pair shares its stamp so image_transport's synchroniser
  // matches them.
  const double stamps[] = {10.0, 10.1, 9.95};
  for (int i = 0; i < 3; ++i) {
    sensor_msgs::Image image = makeImage(64, 48);
    sensor_msgs::CameraInfo info = makeInfo(64, 48);
    if (i == 1) info.K[0] = 0;
    image.header.stamp = info.header.stamp = ros::Time(stamps[i]);
    image.header.frame_id = info.header.frame_id = "camera_optical";
    info_pub.publish(info);
    image_pub.publish(image);
    ASSERT_TRUE(waitFor([&] { return received == i + 1; }, 10.0)) << "no status for frame " << i;
    if (i == 0) {
      EXPECT_EQ(last.frames_processed, 1u);
      EXPECT_EQ(last.frames_skipped, 0u);
    }
    if (i == 1) EXPECT_NE(last.message.find("no valid focal length"), std::string::npos) << last.message;
  }
  EXPECT_EQ(last.frames_processed, 1u);
  EXPECT_EQ(last.frames_skipped, 2u);
  EXPECT_NE(last.message.find("stamp does not advance"), std::string::npos) << last.message;
  EXPECT_EQ(last.num_particles, 5000u);
  EXPECT_EQ(last.header.frame_id, "world");
}

TEST(TrackerNodelet, ParameterProblemsAreAllNamed) {
  ros::NodeHandle bad("/bad_parameters");
  bad.setParam("num_particles", -5);
  bad.setParam("person_mass_kg", "heavy");
  bad.setParam("num_partcles", 100);
  try {
    loadTrackerNodeConfig(bad);
    FAIL() << "bad parameters were accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("/bad_parameters/num_particles = -5 is outside"), std::string::npos) << what;
    EXPECT_NE(what.find("/bad_parameters/person_mass_kg must be a number"), std::string::npos) << what;
    EXPECT_NE(what.find("/bad_parameters/num_partcles is not a parameter"), std::string::npos) << what;
  }
}

TEST(TrackerNodelet, ManagerRefusesNodeletWithBadParameters) {
  ros::NodeHandle nh;
  nh.setParam("/refused_tracker/resample_mixing", 2.0);
  ros::ServiceClient load = nh.serviceClient<nodelet::NodeletLoad>("/manager/load_nodelet");
  ASSERT_TRUE(load.waitForExistence(ros::Duration(30.0)));
  nodelet::NodeletLoad request;
  request.request.name = "/refused_tracker";
  request.request.type = "kneed_walker/TrackerNodelet";
  // The manager answers a failed load by failing the service call.
  const bool loaded = load.call(request) && request.response.success;
  EXPECT_FALSE(loaded) << "a nodelet with resample_mixing = 2 was loaded";
  EXPECT_EQ(advertisedTopics().count("/refused_tracker/status"), 0u);
}

}  // namespace
}  // namespace kneed_walker::ros_glue

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_nodelet");
  ros::NodeHandle keep_alive;
  return RUN_ALL_TESTS();
}
