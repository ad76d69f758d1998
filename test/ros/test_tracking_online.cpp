// Runs inside tracking_online.test: track.launch with a synthetic sequence's camera file. The
// test publishes the sequence's frames one at a time, waiting for each frame's ~status, and
// checks (1) every frame was answered and none dropped, (2) the joints stay within the
// offline tracker's loose bound of the ground truth, (3) track_offline on the same frames
// and seed gives the same joints (to 1e-9 m), and its --lagged the same smoothed joints as
// ~body_poses_smoothed.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/RegionOfInterest.h>
#include <sensor_msgs/Image.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "kneed_walker/BodyPose.h"
#include "kneed_walker/BodyPoseArray.h"
#include "kneed_walker/GroundTrackArray.h"
#include "kneed_walker/core/vision/camera.h"
#include "kneed_walker/TrackingStatus.h"
#include "joints_csv.h"
#include "wait_for.h"

namespace kneed_walker::ros_glue {
namespace {

using test::JointRow;
using test::readJoints;
using test::waitFor;

TEST(TrackingOnline, AnswersEveryFrameMatchesTrackOfflineStaysNearTheTruthAndTracksALoopAgain) {
  ros::NodeHandle nh, private_nh("~");
  std::string sequence;
  int particles = 0;
  ASSERT_TRUE(private_nh.getParam("sequence", sequence));
  ASSERT_TRUE(private_nh.getParam("particles", particles));

  std::vector<sensor_msgs::Image::ConstPtr> images;
  std::vector<sensor_msgs::CameraInfo::ConstPtr> infos;
  rosbag::Bag bag(sequence + ".bag");
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (auto image = m.instantiate<sensor_msgs::Image>()) images.push_back(image);
    if (auto info = m.instantiate<sensor_msgs::CameraInfo>()) infos.push_back(info);
  }
  ASSERT_EQ(images.size(), infos.size());
  ASSERT_GT(images.size(), 20u);

  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("/camera/image_raw", 50);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("/camera/camera_info", 50);
  std::map<ros::Time, BodyPose> poses;
  std::map<ros::Time, TrackingStatus> statuses;
  TrackingStatus last;
  ros::Subscriber pose_sub = nh.subscribe<BodyPose>("/kneed_walker/body_pose", 100,
                                                    [&](const BodyPoseConstPtr& p) { poses[p->header.stamp] = *p; });
  std::map<ros::Time, BodyPoseArray> arrays;
  ros::Subscriber array_sub = nh.subscribe<BodyPoseArray>("/kneed_walker/body_poses", 100,
                                                          [&](const BodyPoseArrayConstPtr& a) { arrays[a->header.stamp] = *a; });
  std::map<ros::Time, BodyPoseArray> smoothed;
  ros::Subscriber smoothed_sub = nh.subscribe<BodyPoseArray>(
      "/kneed_walker/body_poses_smoothed", 100, [&](const BodyPoseArrayConstPtr& a) { smoothed[a->header.stamp] = *a; });
  std::map<ros::Time, GroundTrackArray> ground_tracks;
  ros::Subscriber ground_sub = nh.subscribe<GroundTrackArray>(
      "/kneed_walker/ground_tracks", 100, [&](const GroundTrackArrayConstPtr& a) { ground_tracks[a->header.stamp] = *a; });
  ros::Subscriber status_sub = nh.subscribe<TrackingStatus>("/kneed_walker/status", 100, [&](const TrackingStatusConstPtr& s) {
    statuses[s->header.stamp] = *s;
    last = *s;
  });
  ASSERT_TRUE(waitFor([&] {
    return image_pub.getNumSubscribers() > 0 && info_pub.getNumSubscribers() > 0 && pose_sub.getNumPublishers() > 0 &&
           status_sub.getNumPublishers() > 0;
  }, 60.0)) << "track.launch's nodelet did not connect";

  // Mid-track, bad frames between good ones (stamped between them): each is skipped and named,
  // the track goes on, and the good frames are tracked as if the bad ones had not come.
  struct Spoiled {
    const char* what;
    std::function<void(sensor_msgs::Image&, sensor_msgs::CameraInfo&)> spoil;
    const char* expected;  // in ~status's message
  };
  const std::vector<Spoiled> spoiled = {
      {"NaN focal length", [](auto&, auto& info) { info.K[4] = std::nan(""); }, "no valid focal length"},
      {"NaN distortion", [](auto&, auto& info) { info.D[0] = std::nan(""); }, "not finite"},
      {"3 distortion coefficients", [](auto&, auto& info) { info.D.resize(3); }, "3 coefficients"},
      {"unknown encoding", [](auto& image, auto&) { image.encoding = "32FC1"; }, "encoding '32FC1'"},
      {"short data", [](auto& image, auto&) { image.data.resize(10); }, "bytes"},
      {"camera_info of another size", [](auto&, auto& info) { info.width = 80; }, "camera_info is for 80x"},
  };
  ros::Subscriber diagnostics_sub;
  std::map<std::string, std::string> diagnostics;  // the tracker's key-values, last seen
  diagnostic_msgs::DiagnosticStatus tracker_status;  // the tracker's status, last seen
  std::set<std::string> status_names;  // every status the nodelet's updater publishes
  diagnostics_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>("/diagnostics", 20, [&](const diagnostic_msgs::DiagnosticArrayConstPtr& d) {
    for (const diagnostic_msgs::DiagnosticStatus& status : d->status) {
      status_names.insert(status.name);
      if (status.name.find(": tracker") != std::string::npos) {
        tracker_status = status;
        for (const diagnostic_msgs::KeyValue& kv : status.values) diagnostics[kv.key] = kv.value;
      }
    }
  });
  const size_t spoil_after = images.size() - 8;  // tracking by then
  for (size_t f = 0; f < images.size(); ++f) {
    info_pub.publish(infos[f]);
    image_pub.publish(images[f]);
    ASSERT_TRUE(waitFor([&] { return statuses.count(images[f]->header.stamp) > 0; }, 60.0)) << "no answer to frame " << f;
    if (f != spoil_after) continue;
    ASSERT_EQ(statuses.at(images[f]->header.stamp).state, TrackingStatus::TRACKING) << "not tracking before the bad frames";
    for (size_t k = 0; k < spoiled.size(); ++k) {
      sensor_msgs::Image image = *images[f];
      sensor_msgs::CameraInfo info = *infos[f];
      image.header.stamp = info.header.stamp = images[f]->header.stamp + ros::Duration(0.01 * (k + 1));
      spoiled[k].spoil(image, info);
      info_pub.publish(info);
      image_pub.publish(image);
      ASSERT_TRUE(waitFor([&] { return statuses.count(image.header.stamp) > 0; }, 10.0)) << "no answer to " << spoiled[k].what;
      EXPECT_NE(statuses.at(image.header.stamp).message.find(spoiled[k].expected), std::string::npos)
          << spoiled[k].what << ": " << statuses.at(image.header.stamp).message;
    }
  }
  ASSERT_TRUE(waitFor([&] { return last.header.stamp == images.back()->header.stamp; }, 10.0));
  const TrackingStatus& after_bad = statuses.at(images[spoil_after + 1]->header.stamp);
  EXPECT_EQ(after_bad.state, TrackingStatus::TRACKING) << "the track did not go on after the bad frames: " << after_bad.message;
  EXPECT_EQ(last.frames_processed, images.size());
  EXPECT_EQ(last.frames_skipped, spoiled.size()) << "frames were skipped: " << last.message;
  EXPECT_EQ(last.frames_dropped, 0u);
  EXPECT_EQ(last.frames_received, images.size() + spoiled.size());
  // diagnostic_updater publishes once a second: wait for a report made after the last answer.
  const size_t sent = images.size() + spoiled.size();
  ASSERT_TRUE(waitFor([&] {
    return diagnostics["frames skipped (unusable)"] == std::to_string(spoiled.size()) &&
           diagnostics["frames answered"] == std::to_string(images.size());
  }, 5.0)) << "/diagnostics says " << diagnostics["frames skipped (unusable)"] << " frames skipped, "
           << diagnostics["frames answered"] << " answered";
  EXPECT_EQ(diagnostics["frames dropped (arrived while busy)"], "0");
  // The rest of /diagnostics, as an operator reads it: every frame counted once where it went,
  // the filter's figures, the input topic, a warning that names the last bad frame, and the
  // rate and latency checks of diagnostic_updater beside the tracker's own status.
  EXPECT_EQ(diagnostics["frames received"], std::to_string(sent));
  EXPECT_EQ(diagnostics["frames processed"], std::to_string(images.size()));
  EXPECT_EQ(diagnostics["restarts (stamps went back, images changed)"], "0");
  EXPECT_EQ(diagnostics["particles per person"], std::to_string(particles));
  // The walker is found, lost near the end of the walk and found again (the log says when).
  EXPECT_GE(std::atoi(diagnostics["tracks started"].c_str()), 1) << diagnostics["tracks started"];
  EXPECT_FALSE(diagnostics["people tracked"].empty());
  const double ess = std::stod(diagnostics["effective sample size"]);
  EXPECT_GT(ess, 0.0);
  EXPECT_LE(ess, particles);
  EXPECT_GT(std::stod(diagnostics["processing time (s)"]), 0.0);
  EXPECT_NE(diagnostics["input"].find("image"), std::string::npos) << diagnostics["input"];
  EXPECT_EQ(tracker_status.level, diagnostic_msgs::DiagnosticStatus::WARN) << "frames were skipped: a warning";
  // The state of the last answer, then the last bad frame's problem (by this sequence's last
  // frames the session reports "waiting for a person" again).
  EXPECT_NE(tracker_status.message.find("; last skipped frame: "), std::string::npos) << tracker_status.message;
  EXPECT_NE(tracker_status.message.find(spoiled.back().expected), std::string::npos)
      << "the warning names the last bad frame's problem: " << tracker_status.message;
  for (const char* check : {"input rate", "output rate", "output latency"}) {
    bool found = false;
    for (const std::string& name : status_names) found = found || name.find(check) != std::string::npos;
    EXPECT_TRUE(found) << "no '" << check << "' status on /diagnostics";
  }

  // The same frames and seed through track_offline (as the nodelet: the background from the
  // first frames, the person found in the image, each frame's filtered estimate).
  const std::string csv = "/tmp/kneed_walker_tracking_online_" + std::to_string(getpid()) + ".csv";
  const std::string command = std::string(KNEED_WALKER_TRACK_OFFLINE) + " --bag " + sequence + ".bag --camera " +
                              sequence + "_camera.yml --background-from-start --background-frames 20 --filtered" +
                              " --num-particles " + std::to_string(particles) + " --seed 1 --out-csv " + csv + " 2>&1";
  ASSERT_EQ(std::system((command + " > /dev/null").c_str()), 0) << command;
  const std::vector<JointRow> offline = readJoints(csv);
  std::remove(csv.c_str());
  ASSERT_FALSE(offline.empty());

  // Compare frame by frame (frames are the bag's order).
  std::map<int, std::map<std::string, const JointRow*>> offline_by_frame;
  for (const JointRow& row : offline) offline_by_frame[row.frame][row.joint] = &row;
  const std::vector<JointRow> truth = readJoints(sequence + "_ground_truth.csv");
  std::map<int, std::map<std::string, const JointRow*>> truth_by_frame;
  for (const JointRow& row : truth) truth_by_frame[row.frame][row.joint] = &row;
  double worst_difference_m = 0, error_sum_m = 0, ground_error_sum_m = 0;
  int compared = 0, error_count = 0, ground_count = 0;
  for (size_t f = 0; f < images.size(); ++f) {
    const auto pose = poses.find(images[f]->header.stamp);
    ASSERT_EQ(pose != poses.end(), offline_by_frame.count(static_cast<int>(f)) > 0)
        << "frame " << f << ": the nodelet and track_offline disagree on whether it was tracked; the nodelet's status: "
        << statuses[images[f]->header.stamp].message << " (" << poses.size() << " poses)";
    if (pose == poses.end()) continue;
    // ~body_poses holds every person's pose: here the one body's, as ~body_pose.
    const auto array = arrays.find(images[f]->header.stamp);
    ASSERT_NE(array, arrays.end()) << "frame " << f << ": a ~body_pose without a ~body_poses";
    ASSERT_EQ(array->second.bodies.size(), 1u) << "frame " << f;
    EXPECT_EQ(array->second.bodies[0].body_id, "1");
    EXPECT_EQ(array->second.bodies[0].joint_positions, pose->second.joint_positions) << "frame " << f;
    // Its track: the same as track_offline's at the frame (a new one where a lost person started again).
    EXPECT_GE(pose->second.track, 1u) << "frame " << f;
    EXPECT_EQ(pose->second.track, static_cast<uint32_t>(offline_by_frame[f].at("waist")->track)) << "frame " << f;
    // ~ground_tracks: the same body's ground track, in the world frame, near the true waist's
    // ground point, with a positive covariance.
    const auto ground = ground_tracks.find(images[f]->header.stamp);
    ASSERT_NE(ground, ground_tracks.end()) << "frame " << f << ": a ~body_pose without a ~ground_tracks";
    ASSERT_EQ(ground->second.people.size(), 1u) << "frame " << f;
    const GroundTrack& track = ground->second.people[0];
    EXPECT_EQ(track.body_id, "1");
    EXPECT_EQ(track.header.frame_id, pose->second.header.frame_id);
    for (int d = 0; d < 5; ++d) EXPECT_GT(track.covariance[6 * d], 0.0) << "frame " << f;
    if (truth_by_frame[f].count("waist")) {
      const JointRow* waist = truth_by_frame[f].at("waist");
      ground_error_sum_m += std::hypot(track.position.x - waist->x, track.position.y - waist->y);
      ++ground_count;
    }
    // Tracks running after the frame: none at the frame where the track is lost.
    const TrackingStatus& status = statuses[images[f]->header.stamp];
    EXPECT_EQ(status.people_tracked, status.state == TrackingStatus::TRACKING ? 1u : 0u) << "frame " << f;
    for (size_t j = 0; j < pose->second.joint_names.size(); ++j) {
      const std::string& name = pose->second.joint_names[j];
      const geometry_msgs::Point& p = pose->second.joint_positions[j];
      const JointRow* o = offline_by_frame[f].at(name);
      worst_difference_m = std::max({worst_difference_m, std::abs(p.x - o->x), std::abs(p.y - o->y), std::abs(p.z - o->z)});
      ++compared;
      if (truth_by_frame[f].count(name)) {
        const JointRow* t = truth_by_frame[f].at(name);
        error_sum_m += std::sqrt((p.x - t->x) * (p.x - t->x) + (p.y - t->y) * (p.y - t->y) + (p.z - t->z) * (p.z - t->z));
        ++error_count;
      }
    }
  }
  ASSERT_GT(compared, 0) << "nothing was tracked";
  const double mean_error_mm = 1000 * error_sum_m / error_count;
  std::printf("frames %zu, tracked %zu; nodelet vs track_offline: largest difference %.3g m over %d joints; "
              "mean joint error %.1f mm\n", images.size(), poses.size(), worst_difference_m, compared, mean_error_mm);
  EXPECT_LE(worst_difference_m, 1e-9);
  EXPECT_LT(mean_error_mm, 350.0);  // test/ros/check_tracking's loose bound
  ASSERT_GT(ground_count, 0);
  const double ground_error_mm = 1000 * ground_error_sum_m / ground_count;
  std::printf("ground track: mean distance from the true waist's ground point %.1f mm over %d frames\n", ground_error_mm,
              ground_count);
  EXPECT_LT(ground_error_mm, 300.0);

  // The smoothed poses (the MAP at t − Δs as each becomes final): each frame
  // ~body_poses_smoothed gave is track_offline --lagged's for the same frames and seed; it gave
  // all of them but the last Δs + 1 of a track still running when the frames stopped (track_offline
  // writes those at the end of its input).
  const std::string lagged_csv = "/tmp/kneed_walker_tracking_online_lagged_" + std::to_string(getpid()) + ".csv";
  std::string lagged_command = command;
  lagged_command.replace(lagged_command.find("--filtered"), 10, "--lagged");
  lagged_command.replace(lagged_command.find(csv), csv.size(), lagged_csv);
  ASSERT_EQ(std::system((lagged_command + " > /dev/null").c_str()), 0) << lagged_command;
  std::map<int, std::map<std::string, JointRow>> lagged_by_frame;
  for (const JointRow& row : readJoints(lagged_csv)) lagged_by_frame[row.frame][row.joint] = row;
  std::remove(lagged_csv.c_str());
  ASSERT_FALSE(lagged_by_frame.empty());
  double worst_smoothed_m = 0;
  int smoothed_frames = 0;
  for (size_t f = 0; f < images.size(); ++f) {
    const auto online = smoothed.find(images[f]->header.stamp);
    if (online == smoothed.end()) continue;
    ++smoothed_frames;
    ASSERT_TRUE(lagged_by_frame.count(static_cast<int>(f))) << "frame " << f << " smoothed online, not by --lagged";
    ASSERT_EQ(online->second.bodies.size(), 1u) << "frame " << f;
    const BodyPose& body = online->second.bodies[0];
    for (size_t j = 0; j < body.joint_names.size(); ++j) {
      const JointRow& o = lagged_by_frame[static_cast<int>(f)].at(body.joint_names[j]);
      const geometry_msgs::Point& p = body.joint_positions[j];
      worst_smoothed_m = std::max({worst_smoothed_m, std::abs(p.x - o.x), std::abs(p.y - o.y), std::abs(p.z - o.z)});
    }
  }
  const int lag = 3;  // config/tracker.yaml's resample_lag_frames
  std::printf("smoothed: %d frames online, %zu by track_offline --lagged; largest difference %.3g m\n", smoothed_frames,
              lagged_by_frame.size(), worst_smoothed_m);
  EXPECT_GE(smoothed_frames + lag + 1, static_cast<int>(lagged_by_frame.size()));
  EXPECT_GT(smoothed_frames, 0);
  EXPECT_LE(worst_smoothed_m, 1e-9);

  // The bag again, as `rosbag play -l` sends it: the stamps go back, the nodelet starts over
  // (learns the background again, finds the person again) and, with the same seed, tracks
  // exactly as the first time.
  const std::map<ros::Time, BodyPose> first_pass = poses;
  poses.clear();
  statuses.clear();
  for (size_t f = 0; f < images.size(); ++f) {
    info_pub.publish(infos[f]);
    image_pub.publish(images[f]);
    ASSERT_TRUE(waitFor([&] { return statuses.count(images[f]->header.stamp) > 0; }, 60.0)) << "loop: no answer to frame " << f;
  }
  ASSERT_TRUE(waitFor([&] { return poses.size() >= first_pass.size(); }, 10.0))
      << "the looped bag was tracked in " << poses.size() << " frames, the first pass in " << first_pass.size();
  double loop_difference_m = 0;
  for (const auto& [stamp, pose] : first_pass) {
    ASSERT_TRUE(poses.count(stamp)) << "the loop did not track the frame at " << stamp;
    for (size_t j = 0; j < pose.joint_positions.size(); ++j) {
      const geometry_msgs::Point &a = pose.joint_positions[j], &b = poses.at(stamp).joint_positions[j];
      loop_difference_m = std::max({loop_difference_m, std::abs(a.x - b.x), std::abs(a.y - b.y), std::abs(a.z - b.z)});
    }
  }
  std::printf("looped: %zu frames tracked again, largest difference from the first pass %.3g m\n", poses.size(),
              loop_difference_m);
  EXPECT_EQ(loop_difference_m, 0.0);

  // Once more with the person's box on ~init_box (around the truth's first pose): the track
  // starts from it at the first frame, where on its own the nodelet found the person later.
  const auto first_tracked = std::find_if(statuses.begin(), statuses.end(), [](const auto& s) {
    return s.second.state == TrackingStatus::TRACKING;
  });
  ASSERT_NE(first_tracked, statuses.begin()) << "the person was found at the first frame already";
  const core::vision::Camera camera = core::vision::Camera::load(sequence + "_camera.yml", 0.001);
  cv::Rect2d box;
  for (const JointRow& row : truth)
    if (row.frame == 0)
      if (const auto px = camera.project(Eigen::Vector3d(row.x, row.y, row.z))) box |= cv::Rect2d(px->x(), px->y(), 1, 1);
  box.y -= 0.12 * box.height;  // the head's top above its centre
  box.height *= 1.16;
  sensor_msgs::RegionOfInterest roi;
  roi.x_offset = static_cast<uint32_t>(box.x);
  roi.y_offset = static_cast<uint32_t>(box.y);
  roi.width = static_cast<uint32_t>(box.width);
  roi.height = static_cast<uint32_t>(box.height);
  ros::Publisher box_pub = nh.advertise<sensor_msgs::RegionOfInterest>("/kneed_walker/init_box", 1, true);
  ASSERT_TRUE(waitFor([&] { return box_pub.getNumSubscribers() > 0; }, 10.0));
  box_pub.publish(roi);
  ros::WallDuration(0.3).sleep();
  statuses.clear();
  for (size_t f = 0; f < images.size(); ++f) {
    info_pub.publish(infos[f]);
    image_pub.publish(images[f]);
    ASSERT_TRUE(waitFor([&] { return statuses.count(images[f]->header.stamp) > 0; }, 60.0)) << "box: no answer to frame " << f;
  }
  const TrackingStatus& first = statuses.at(images.front()->header.stamp);
  std::printf("from ~init_box (%u, %u) %ux%u: frame 0 %s (%s)\n", roi.x_offset, roi.y_offset, roi.width, roi.height,
              first.state == TrackingStatus::TRACKING ? "tracked" : "not tracked", first.message.c_str());
  EXPECT_EQ(first.state, TrackingStatus::TRACKING) << first.message;
}

}  // namespace
}  // namespace kneed_walker::ros_glue

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracking_online");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
