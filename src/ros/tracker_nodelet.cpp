// kneed_walker/TrackerNodelet: image + camera_info in, MAP 3D walker pose out.
//
// A thin wrapper (robot_localization's pattern): parameters are loaded and validated once
// (bad values refuse the nodelet with a message naming them), every ROS <-> core conversion
// is in conversions.cpp, and the algorithm lives in the ROS-free core.
//
// Inputs:  image (sensor_msgs/Image) + camera_info (sensor_msgs/CameraInfo), via
//          image_transport, in the nodelet's namespace (remap them).
// Outputs: ~body_pose (kneed_walker/BodyPose), ~pose (geometry_msgs/PoseWithCovarianceStamped),
//          ~walker_state (kneed_walker/WalkerState), ~status (kneed_walker/TrackingStatus),
//          ~particle_cloud (geometry_msgs/PoseArray), ~markers (visualization_msgs/MarkerArray),
//          /tf (body_<id> and REP 155 joint frames), /diagnostics.
//
// Callbacks run on this nodelet's single-threaded queue; the per-particle work will use its
// own worker threads (core::tracking::TrackerOptions::num_threads).
#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/PoseArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <tf2_ros/transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <boost/make_shared.hpp>
#include <chrono>
#include <memory>
#include <stdexcept>

#include "kneed_walker/BodyPose.h"
#include "kneed_walker/TrackingStatus.h"
#include "kneed_walker/WalkerState.h"
#include "kneed_walker/ros/conversions.h"
#include "kneed_walker/ros/parameters.h"

namespace kneed_walker::ros_glue {

class TrackerNodelet : public nodelet::Nodelet {
 private:
  void onInit() override;
  void onFrame(const sensor_msgs::ImageConstPtr& image,
               const sensor_msgs::CameraInfoConstPtr& info);
  void skipFrame(const std_msgs::Header& header, const std::string& reason);
  void publishStatus(const std_msgs::Header& header, uint8_t state, double processing_time_s);
  void reportDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status);

  TrackerNodeConfig config_;

  std::unique_ptr<image_transport::ImageTransport> image_transport_;
  image_transport::CameraSubscriber camera_subscriber_;
  ros::Publisher body_pose_publisher_;
  ros::Publisher pose_publisher_;
  ros::Publisher walker_state_publisher_;
  ros::Publisher status_publisher_;
  ros::Publisher particle_cloud_publisher_;
  ros::Publisher markers_publisher_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::Timer diagnostics_timer_;

  // Frame bookkeeping (touched only on this nodelet's single-threaded callback queue).
  uint64_t frames_processed_ = 0;
  uint64_t frames_skipped_ = 0;
  ros::Time last_stamp_;
  std::string status_message_;
};

void TrackerNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& private_nh = getPrivateNodeHandle();
  try {
    config_ = loadTrackerNodeConfig(private_nh);
  } catch (const std::invalid_argument& e) {
    NODELET_FATAL("refusing to start: %s", e.what());
    throw;  // nodelet::Loader reports the failed load and does not keep this nodelet
  }

  body_pose_publisher_ = private_nh.advertise<BodyPose>("body_pose", 10);
  pose_publisher_ = private_nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("pose", 10);
  walker_state_publisher_ = private_nh.advertise<WalkerState>("walker_state", 10);
  status_publisher_ = private_nh.advertise<TrackingStatus>("status", 10);
  if (config_.ros.publish_particle_cloud)
    particle_cloud_publisher_ = private_nh.advertise<geometry_msgs::PoseArray>("particle_cloud", 2);
  markers_publisher_ = private_nh.advertise<visualization_msgs::MarkerArray>("markers", 2);
  if (config_.ros.publish_tf) tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();

  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, private_nh, getName());
  diagnostics_->setHardwareID("camera");
  diagnostics_->add("tracker", this, &TrackerNodelet::reportDiagnostics);
  diagnostics_timer_ = nh.createTimer(ros::Duration(1.0),
                                      [this](const ros::TimerEvent&) { diagnostics_->update(); });

  image_transport_ = std::make_unique<image_transport::ImageTransport>(nh);
  camera_subscriber_ = image_transport_->subscribeCamera(
      "image", static_cast<uint32_t>(config_.ros.image_queue_size), &TrackerNodelet::onFrame,
      this);
  status_message_ = "waiting for image + camera_info on " + camera_subscriber_.getTopic();
  NODELET_INFO("tracking %d particles (seed %lu), person %.2f m %.1f kg; input %s",
               config_.tracker.num_particles, static_cast<unsigned long>(config_.tracker.seed),
               config_.tracker.person_height_m, config_.tracker.person_mass_kg,
               camera_subscriber_.getTopic().c_str());
}

void TrackerNodelet::onFrame(const sensor_msgs::ImageConstPtr& image,
                             const sensor_msgs::CameraInfoConstPtr& info) {
  const auto start = std::chrono::steady_clock::now();
  const std::string problem = frameProblem(*image, *info);
  if (!problem.empty()) return skipFrame(image->header, problem);
  if (!last_stamp_.isZero() && image->header.stamp <= last_stamp_)
    return skipFrame(image->header, "stamp does not advance (a bag looped or was played twice?)");
  last_stamp_ = image->header.stamp;
  ++frames_processed_;

  // The tracker itself (likelihood + particle filter) is the next milestone of the core; until
  // it exists, frames are validated and counted and no pose is published.
  status_message_ = "frames are validated, but the tracker (likelihood + particle filter) is "
                    "not implemented yet: no pose is published";
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  publishStatus(image->header, TrackingStatus::WAITING, elapsed_s);
}

void TrackerNodelet::skipFrame(const std_msgs::Header& header, const std::string& reason) {
  ++frames_skipped_;
  status_message_ = "skipped frame " + std::to_string(header.seq) + ": " + reason;
  NODELET_WARN_THROTTLE(5.0, "%s (%lu skipped so far)", status_message_.c_str(),
                        static_cast<unsigned long>(frames_skipped_));
  publishStatus(header, TrackingStatus::WAITING, 0.0);
}

void TrackerNodelet::publishStatus(const std_msgs::Header& header, uint8_t state,
                                   double processing_time_s) {
  auto status = boost::make_shared<TrackingStatus>();
  status->header.stamp = header.stamp;
  status->header.frame_id = config_.ros.world_frame;
  status->state = state;
  status->num_particles = static_cast<uint32_t>(config_.tracker.num_particles);
  status->processing_time = processing_time_s;
  status->frames_processed = frames_processed_;
  status->frames_skipped = frames_skipped_;
  status->message = status_message_;
  status_publisher_.publish(status);
}

void TrackerNodelet::reportDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const bool skipping = frames_skipped_ > 0;
  status.summary(skipping ? diagnostic_msgs::DiagnosticStatus::WARN
                          : diagnostic_msgs::DiagnosticStatus::OK,
                 status_message_);
  status.add("frames processed", frames_processed_);
  status.add("frames skipped", frames_skipped_);
  status.add("particles", config_.tracker.num_particles);
  status.add("input", camera_subscriber_.getTopic());
}

}  // namespace kneed_walker::ros_glue

PLUGINLIB_EXPORT_CLASS(kneed_walker::ros_glue::TrackerNodelet, nodelet::Nodelet)
