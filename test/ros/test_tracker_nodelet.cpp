// Runs inside tracker_nodelet.test: a manager with kneed_walker/TrackerNodelet loaded as
// /kneed_walker, its input remapped to /camera/image_raw.
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <image_transport/image_transport.h>
#include <nodelet/NodeletLoad.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/RegionOfInterest.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_msgs/TFMessage.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>

#include "kneed_walker/TrackingStatus.h"
#include "wait_for.h"
#include "kneed_walker/ros/parameters.h"

namespace kneed_walker::ros_glue {
namespace {

using test::waitFor;

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
      {"/kneed_walker/ground_tracks", "kneed_walker/GroundTrackArray"},
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

// The camera 3 m up, looking along +X (optical z forward, x right = -Y, y down = -Z), on a
// latched /tf_static publisher.
void publishCameraPose(ros::Publisher& tf_pub) {
  geometry_msgs::TransformStamped camera_pose;
  camera_pose.header.frame_id = "world";
  camera_pose.child_frame_id = "camera_optical";
  camera_pose.transform.translation.z = 3;
  camera_pose.transform.rotation.x = -0.5, camera_pose.transform.rotation.y = 0.5;
  camera_pose.transform.rotation.z = -0.5, camera_pose.transform.rotation.w = 0.5;
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(camera_pose);
  tf_pub.publish(tf);
  ros::WallDuration(0.5).sleep();
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

// Bad input of every kind is skipped, counted and named in ~status; the nodelet survives it
// and takes good frames again after it; a stamp that goes back (a looping bag) starts over.
TEST(TrackerNodelet, SkipsAndNamesBadFramesStartsOverAndTakesReconfiguration) {
  ros::NodeHandle nh;
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("/camera/image_raw", 10);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("/camera/camera_info", 10);
  ros::Publisher tf_pub = nh.advertise<tf2_msgs::TFMessage>("/tf_static", 1, /*latch=*/true);
  TrackingStatus last;
  int received = 0;
  ros::Subscriber status_sub = nh.subscribe<TrackingStatus>(
      "/kneed_walker/status", 10, [&](const TrackingStatusConstPtr& s) {
        last = *s;
        ++received;
      });
  // ~status is latched: the nodelet's first word arrives before any frame.
  ASSERT_TRUE(waitFor([&] { return received >= 1; }, 30.0)) << "no latched ~status";
  EXPECT_EQ(last.state, TrackingStatus::WAITING);
  EXPECT_EQ(last.frames_processed, 0u);
  ASSERT_TRUE(waitFor([&] {
    return image_pub.getNumSubscribers() > 0 && info_pub.getNumSubscribers() > 0;
  }, 30.0)) << "the nodelet did not subscribe to /camera/image_raw + /camera/camera_info";
  publishCameraPose(tf_pub);

  struct Case {
    const char* what;
    std::function<void(sensor_msgs::Image&, sensor_msgs::CameraInfo&)> spoil;
    const char* expected;  // in ~status's message; empty: a good frame
  };
  // An image of the same grey in another accepted encoding (frameProblem's list).
  auto recode = [](sensor_msgs::Image& image, const std::string& encoding) {
    image.encoding = encoding;
    image.step = image.width * static_cast<uint32_t>(sensor_msgs::image_encodings::numChannels(encoding));
    image.data.assign(static_cast<size_t>(image.step) * image.height, 128);
  };
  const std::vector<Case> cases = {
      {"good", [](auto&, auto&) {}, ""},
      {"rgb8", [&](auto& image, auto&) { recode(image, sensor_msgs::image_encodings::RGB8); }, ""},
      {"mono8", [&](auto& image, auto&) { recode(image, sensor_msgs::image_encodings::MONO8); }, ""},
      {"bgra8", [&](auto& image, auto&) { recode(image, sensor_msgs::image_encodings::BGRA8); }, ""},
      {"rgba8", [&](auto& image, auto&) { recode(image, sensor_msgs::image_encodings::RGBA8); }, ""},
      {"an unsupported distortion model", [](auto&, auto& info) { info.distortion_model = "equidistant"; },
       "'equidistant' is not supported"},
      {"plumb_bob with 8 coefficients", [](auto&, auto& info) { info.D.resize(8); }, "8 coefficients for model 'plumb_bob'"},
      {"no focal length", [](auto&, auto& info) { info.K[0] = 0; }, "no valid focal length"},
      {"NaN focal length", [](auto&, auto& info) { info.K[4] = std::nan(""); }, "no valid focal length"},
      {"NaN distortion", [](auto&, auto& info) { info.D[1] = std::nan(""); }, "not finite"},
      {"3 distortion coefficients", [](auto&, auto& info) { info.D.resize(3); }, "3 coefficients"},
      {"unknown encoding", [](auto& image, auto&) { image.encoding = "32FC1"; }, "encoding '32FC1'"},
      {"short data", [](auto& image, auto&) { image.data.resize(10); }, "bytes"},
      {"camera_info of another size", [](auto&, auto& info) { info.width = 80; }, "camera_info is for 80x48"},
      {"no frame id", [](auto& image, auto& info) { image.header.frame_id = info.header.frame_id = ""; }, "frame_id"},
      {"no stamp", [](auto& image, auto& info) { image.header.stamp = info.header.stamp = ros::Time(); },
       "the image has no stamp (0)"},
      {"good again", [](auto&, auto&) {}, ""},
  };
  double stamp = 10;
  uint64_t processed = 0, skipped = 0;
  for (const Case& c : cases) {
    sensor_msgs::Image image = makeImage(64, 48);
    sensor_msgs::CameraInfo info = makeInfo(64, 48);
    image.header.stamp = info.header.stamp = ros::Time(stamp += 0.1);
    image.header.frame_id = info.header.frame_id = "camera_optical";
    c.spoil(image, info);
    const int before = received;
    info_pub.publish(info);
    image_pub.publish(image);
    ASSERT_TRUE(waitFor([&] { return received > before; }, 10.0)) << "no status for the frame: " << c.what;
    if (*c.expected) {
      ++skipped;
      EXPECT_NE(last.message.find(c.expected), std::string::npos) << c.what << ": " << last.message;
    } else {
      ++processed;
      EXPECT_NE(last.message.find("learning the background"), std::string::npos) << c.what << ": " << last.message;
    }
    EXPECT_EQ(last.frames_processed, processed) << c.what;
    EXPECT_EQ(last.frames_skipped, skipped) << c.what;
    EXPECT_EQ(last.frames_received, last.frames_processed + last.frames_skipped + last.frames_dropped) << c.what;
    EXPECT_EQ(last.frames_answered, 0u) << "learning the background: nothing answered yet";
  }
  // A good frame stamped `at`; true once its status came.
  auto send = [&](double at) {
    sensor_msgs::Image image = makeImage(64, 48);
    sensor_msgs::CameraInfo info = makeInfo(64, 48);
    image.header.stamp = info.header.stamp = ros::Time(at);
    image.header.frame_id = info.header.frame_id = "camera_optical";
    const int before = received;
    info_pub.publish(info);
    image_pub.publish(image);
    return waitFor([&] { return received > before; }, 10.0);
  };
  // The last frame's stamp again: skipped and counted, nothing starts over.
  ASSERT_TRUE(send(stamp)) << "no status for a repeated stamp";
  EXPECT_EQ(last.frames_processed, processed);
  EXPECT_EQ(last.frames_skipped, ++skipped);
  EXPECT_NE(last.message.find("its stamp is not after the previous frame's"), std::string::npos) << last.message;
  // A stamp older than the last: the nodelet starts over (the held frames are forgotten) and
  // takes the frame.
  ASSERT_TRUE(send(10.05)) << "no status after the stamp went back";
  EXPECT_EQ(last.frames_processed, processed + 1);
  EXPECT_NE(last.message.find("(1/"), std::string::npos) << "did not start over: " << last.message;
  EXPECT_EQ(last.num_particles, 5000u);
  EXPECT_EQ(last.header.frame_id, "world");

  // dynamic_reconfigure: a new particle count starts over with it at the next frame; the
  // restart button starts over and reads false again.
  ASSERT_TRUE(send(10.15));
  EXPECT_NE(last.message.find("(2/"), std::string::npos) << last.message;
  // One parameter through the reconfigure service; returns the configuration it answers with.
  auto reconfigure = [](auto parameter, auto dynamic_reconfigure::Config::*list, const std::string& name, auto value) {
    dynamic_reconfigure::Reconfigure call;
    parameter.name = name;
    parameter.value = value;
    (call.request.config.*list).push_back(parameter);
    EXPECT_TRUE(ros::service::call("/kneed_walker/set_parameters", call)) << name;
    return call.response.config;
  };
  reconfigure(dynamic_reconfigure::IntParameter(), &dynamic_reconfigure::Config::ints, "num_particles", 123);
  ASSERT_TRUE(send(10.25));
  EXPECT_EQ(last.num_particles, 123u);
  EXPECT_NE(last.message.find("(1/"), std::string::npos) << "a new particle count did not start over: " << last.message;
  ASSERT_TRUE(send(10.35));
  EXPECT_NE(last.message.find("(2/"), std::string::npos) << last.message;
  const dynamic_reconfigure::Config pressed =
      reconfigure(dynamic_reconfigure::BoolParameter(), &dynamic_reconfigure::Config::bools, "restart", true);
  for (const dynamic_reconfigure::BoolParameter& b : pressed.bools)
    if (b.name == "restart") EXPECT_FALSE(b.value) << "the restart button stayed pressed";
  ASSERT_TRUE(send(10.45));
  EXPECT_NE(last.message.find("(1/"), std::string::npos) << "restart did not start over: " << last.message;
  EXPECT_EQ(last.num_particles, 123u);
  ASSERT_TRUE(send(10.55));
  reconfigure(dynamic_reconfigure::DoubleParameter(), &dynamic_reconfigure::Config::doubles, "prior_noise_scale", 0.5);
  ASSERT_TRUE(send(10.65));
  EXPECT_NE(last.message.find("(1/"), std::string::npos) << "a new noise scale did not start over: " << last.message;
  // NaN is no noise scale: the one in force stays (and nothing starts over).
  const dynamic_reconfigure::Config kept = reconfigure(dynamic_reconfigure::DoubleParameter(),
                                                       &dynamic_reconfigure::Config::doubles, "prior_noise_scale", std::nan(""));
  for (const dynamic_reconfigure::DoubleParameter& d : kept.doubles)
    if (d.name == "prior_noise_scale") EXPECT_EQ(d.value, 0.5) << "NaN was taken";
  ASSERT_TRUE(send(10.75));
  EXPECT_NE(last.message.find("(2/"), std::string::npos) << "NaN started over: " << last.message;

  // ~init_box that cannot be a person in this 64x48 image: empty, off the image, or an offset
  // wrapped around uint32. Each is refused with an error naming it, and the session goes on
  // (nothing starts over, no frame is lost).
  std::vector<std::string> errors;
  ros::Subscriber log_sub = nh.subscribe<rosgraph_msgs::Log>("/rosout", 50, [&](const rosgraph_msgs::LogConstPtr& log) {
    if (log->level >= rosgraph_msgs::Log::ERROR) errors.push_back(log->msg);
  });
  ros::Publisher box_pub = nh.advertise<sensor_msgs::RegionOfInterest>("/kneed_walker/init_box", 1);
  ASSERT_TRUE(waitFor([&] { return box_pub.getNumSubscribers() > 0; }, 10.0));
  auto named = [&](const char* expected) {
    for (const std::string& e : errors)
      if (e.find("init_box") != std::string::npos && e.find(expected) != std::string::npos) return true;
    return false;
  };
  // /rosout reaches this node some time after it subscribes: an empty box (refused on arrival,
  // it changes nothing) until its error comes through.
  sensor_msgs::RegionOfInterest empty;
  empty.width = 10;
  ASSERT_TRUE(waitFor([&] {
    box_pub.publish(empty);
    return waitFor([&] { return named("is empty"); }, 0.5);
  }, 20.0)) << "no error naming an empty ~init_box";
  struct BadBox {
    uint32_t x, y, width, height;
    const char* expected;
  };
  double at = 10.75;
  uint64_t frames = last.frames_processed;
  for (const BadBox& b : {BadBox{200, 10, 10, 20, "lies mostly outside"},
                          BadBox{4294967000u, 10, 500, 20, "lies mostly outside"},
                          BadBox{50, 40, 30, 30, "lies mostly outside"}}) {
    sensor_msgs::RegionOfInterest box;
    box.x_offset = b.x;
    box.y_offset = b.y;
    box.width = b.width;
    box.height = b.height;
    errors.clear();
    box_pub.publish(box);
    ros::Duration(0.3).sleep();  // the box before the frame it applies to
    ASSERT_TRUE(send(at += 0.1));
    ++frames;
    EXPECT_EQ(last.frames_processed, frames) << b.expected;
    EXPECT_EQ(last.message.find("(1/"), std::string::npos) << "a bad box started over: " << last.message;
    EXPECT_TRUE(waitFor([&] { return named(b.expected); }, 5.0)) << "no error naming the box (" << b.x << ", " << b.y << ") " << b.width << "x" << b.height;
  }
}

TEST(TrackerNodelet, ParameterProblemsAreAllNamed) {
  ros::NodeHandle bad("/bad_parameters");
  bad.setParam("num_particles", -5);
  bad.setParam("person_mass_kg", "heavy");
  bad.setParam("num_partcles", 100);
  bad.setParam("image_transport", "carrier_pigeon");
  bad.setParam("camera_file", "/nonexistent/camera.yml");
  bad.setParam("ground_slope_rad", 0.1);
  try {
    loadTrackerNodeConfig(bad);
    FAIL() << "bad parameters were accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("/bad_parameters/num_particles = -5 is outside"), std::string::npos) << what;
    EXPECT_EQ(what.find("min_particles ="), std::string::npos) << "only the parameter typed is named: " << what;
    EXPECT_NE(what.find("/bad_parameters/person_mass_kg must be a number"), std::string::npos) << what;
    EXPECT_NE(what.find("/bad_parameters/num_partcles is not a parameter"), std::string::npos) << what;
    EXPECT_NE(what.find("/bad_parameters/image_transport = 'carrier_pigeon'"), std::string::npos) << what;
    EXPECT_NE(what.find("/bad_parameters/ground_slope_rad = 0.100000 with camera_file"), std::string::npos) << what;
  }
}

// The frame budget's parameters reach the tracker's options; num_particles below the default
// min_particles is taken as the count (nothing to fit), and a bad fraction is refused by name.
TEST(TrackerNodelet, FrameBudgetParametersReachTheTracker) {
  ros::NodeHandle few("/few_particles");
  few.setParam("num_particles", 300);
  const TrackerNodeConfig config = loadTrackerNodeConfig(few);
  EXPECT_EQ(config.tracker.filter.num_particles, 300);
  EXPECT_EQ(config.tracker.min_particles, 300);
  EXPECT_DOUBLE_EQ(config.tracker.frame_budget_fraction, 0.8);
  EXPECT_EQ(config.ros.image_queue_size, 150);
  ros::NodeHandle bad("/bad_budget");
  bad.setParam("frame_budget_fraction", std::numeric_limits<double>::quiet_NaN());
  try {
    loadTrackerNodeConfig(bad);
    FAIL() << "a NaN frame_budget_fraction was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("/bad_budget/frame_budget_fraction"), std::string::npos) << e.what();
  }
}

// The demo's parameters for several people (config/pets_people.yaml) load as written; a bad
// max_people or use_optical_flow is refused by name, and body_id is no longer a parameter (the
// bodies' ids are their slots).
TEST(TrackerNodelet, SeveralPeopleParametersLoadAndBadOnesAreNamed) {
  ros::NodeHandle people("/people_parameters");
  people.setParam("max_people", 10);
  people.setParam("use_optical_flow", false);
  people.setParam("merge_distance_m", 0.5);
  people.setParam("reacquire_distance_m", 0.0);
  const TrackerNodeConfig config = loadTrackerNodeConfig(people);
  EXPECT_EQ(config.session.max_people, 10);
  EXPECT_FALSE(config.likelihood.use_flow);
  EXPECT_DOUBLE_EQ(config.session.merge_distance_m, 0.5);
  EXPECT_DOUBLE_EQ(config.session.reacquire_distance_m, 0.0);
  ros::NodeHandle bad("/bad_people_parameters");
  bad.setParam("max_people", 0);
  bad.setParam("use_optical_flow", "no");
  bad.setParam("body_id", "1");
  try {
    loadTrackerNodeConfig(bad);
    FAIL() << "bad parameters were accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("max_people = 0 is outside [1, 16]"), std::string::npos) << what;
    EXPECT_NE(what.find("/bad_people_parameters/use_optical_flow must be"), std::string::npos) << what;
    EXPECT_NE(what.find("/bad_people_parameters/body_id is not a parameter"), std::string::npos) << what;
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

// ~image_transport: compressed: a second tracker reads JPEG images (the package's compressed
// transport, image_transport_plugins.xml; Debian packages only raw) from a camera publisher that
// offers every installed transport, and takes them as frames.
TEST(TrackerNodelet, TakesCompressedImages) {
  ros::NodeHandle nh;
  nh.setParam("/compressed_tracker/image_transport", "compressed");
  ros::ServiceClient load = nh.serviceClient<nodelet::NodeletLoad>("/manager/load_nodelet");
  ASSERT_TRUE(load.waitForExistence(ros::Duration(30.0)));
  nodelet::NodeletLoad request;
  request.request.name = "/compressed_tracker";
  request.request.type = "kneed_walker/TrackerNodelet";
  request.request.remap_source_args = {"/image"};  // the nodelet subscribes "image" in its parent namespace
  request.request.remap_target_args = {"/jpeg_camera/image_raw"};
  ASSERT_TRUE(load.call(request) && request.response.success) << "the tracker with the compressed transport was refused";
  ros::Publisher tf_pub = nh.advertise<tf2_msgs::TFMessage>("/tf_static", 1, /*latch=*/true);
  publishCameraPose(tf_pub);
  image_transport::ImageTransport transport(nh);
  image_transport::CameraPublisher camera = transport.advertiseCamera("/jpeg_camera/image_raw", 5);
  TrackingStatus last;
  ros::Subscriber status_sub = nh.subscribe<TrackingStatus>("/compressed_tracker/status", 10,
                                                            [&](const TrackingStatusConstPtr& m) { last = *m; });
  ASSERT_TRUE(waitFor([&] { return camera.getNumSubscribers() > 0; }, 30.0)) << "nobody subscribed to the camera";
  EXPECT_TRUE(advertisedTopics().count("/jpeg_camera/image_raw/compressed")) << "no compressed sub-topic";
  ros::WallDuration(1.0).sleep();  // the camera's count may be camera_info's: let the image subscription connect too
  for (int f = 0; f < 3; ++f) {
    sensor_msgs::Image image = makeImage(64, 48);
    sensor_msgs::CameraInfo info = makeInfo(64, 48);
    image.header.stamp = info.header.stamp = ros::Time(20.0 + 0.1 * f);
    image.header.frame_id = info.header.frame_id = "camera_optical";
    camera.publish(image, info);
    ASSERT_TRUE(waitFor([&] { return last.frames_processed == static_cast<uint64_t>(f + 1); }, 10.0))
        << "frame " << f << " not taken: " << last.message;
  }
  EXPECT_EQ(last.frames_skipped, 0u) << last.message;
}

}  // namespace
}  // namespace kneed_walker::ros_glue

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_nodelet");
  ros::NodeHandle keep_alive;
  return RUN_ALL_TESTS();
}
