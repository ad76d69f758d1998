// kneed_walker/TrackerNodelet: image + camera_info in, MAP 3D walker pose out.
//
// A thin wrapper (robot_localization's pattern): parameters are loaded and validated once
// (bad values refuse the nodelet with a message naming them), every ROS <-> core conversion
// is in conversions.cpp, and the tracking is the core's TrackingSession, the same that
// track_offline runs, so the same frames and seed give the same poses online and offline.
//
// Inputs:  image (sensor_msgs/Image) + camera_info (sensor_msgs/CameraInfo), via
//          image_transport (raw or compressed: ~image_transport), in the nodelet's namespace
//          (remap them). The camera's pose: tf's world_frame -> camera_info's frame, or the
//          ~camera_file calibration. ~init_box (sensor_msgs/RegionOfInterest, pixels): where the
//          person is; the track (re)starts from that box at the next frame it can.
// Outputs: per tracked person (up to ~max_people; REP 155 body ids "1".."max_people"):
//          ~body_pose (kneed_walker/BodyPose), ~pose (geometry_msgs/PoseWithCovarianceStamped),
//          ~walker_state (kneed_walker/WalkerState), ~markers (visualization_msgs/MarkerArray),
//          /tf (body_<id> and REP 155 joint frames); per frame: ~body_poses
//          (kneed_walker/BodyPoseArray, every person), ~status (kneed_walker/TrackingStatus,
//          latched), ~particle_cloud (geometry_msgs/PoseArray, every person's, throttled),
//          ~overlay (sensor_msgs/Image), /diagnostics, ~ground_tracks
//          (kneed_walker/GroundTrackArray: where each person stands and goes on the floor, with
//          its covariance; drawn in ~markers). All stamped with the image's time.
//          ~body_poses_smoothed (kneed_walker/BodyPoseArray): the MAP poses of frame t − Δs
//          (paper §4's fixed-lag smoother: the best particle's ancestry, kept to one lineage
//          while it weighs nearly as much, resample_lag_frames behind) as each becomes final,
//          and a track's last Δs frames when it ends; stamped with the frame each describes
//          (track_offline --lagged writes the same poses), and as /tf frames with the suffix
//          _smoothed (body_<id>_smoothed, l_knee_<id>_smoothed, ...).
//
// Threads: the subscriber callback only queues the frame for a worker thread and returns. Up
// to ~image_queue_size frames wait (150: 5 s at 30 fps, through a track's first-frame search);
// a frame arriving at a full queue pushes out the oldest, which is dropped and counted. The
// worker runs the tracker (its per-particle work on all cores), telling it how many frames wait:
// with ~frame_budget_fraction its particle count is fitted to catch them up within about a
// second (Tracker::setBacklogFrames).
#include <cv_bridge/cv_bridge.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <diagnostic_updater/update_functions.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/package.h>
#include <sensor_msgs/RegionOfInterest.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <boost/make_shared.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "kneed_walker/BodyPoseArray.h"
#include "kneed_walker/GroundTrackArray.h"
#include "kneed_walker/TrackerConfig.h"
#include "kneed_walker/TrackingStatus.h"
#include "kneed_walker/core/prior/walker_prior.h"
#include "kneed_walker/core/tracking/tracking_session.h"
#include "kneed_walker/core/vision/overlay.h"
#include "kneed_walker/ros/conversions.h"
#include "kneed_walker/ros/parameters.h"
#include "kneed_walker/ros/rate_diagnostic.h"

namespace kneed_walker::ros_glue {

namespace kw = core;

class TrackerNodelet : public nodelet::Nodelet {
 public:
  ~TrackerNodelet() override;

 private:
  struct Frame {
    sensor_msgs::ImageConstPtr image;
    sensor_msgs::CameraInfoConstPtr info;
  };

  void onInit() override;
  void onFrame(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& info);
  void onInitBox(const sensor_msgs::RegionOfInterestConstPtr& box);
  void onReconfigure(TrackerConfig& config, uint32_t level);
  void workerLoop();
  void process(const Frame& frame);
  // The session for this frame's camera: made on the first frame, made again when the image
  // size changes. Empty string on success, else why the frame cannot be used.
  std::string prepareSession(const Frame& frame);
  // The prior's options with the torque noise scaled by ~prior_noise_scale.
  kw::prior::PriorOptions priorOptions() const;
  void publishAnswer(const kw::tracking::SessionAnswer& answer, const sensor_msgs::ImageConstPtr& image);
  // ~body_poses_smoothed: the answer's MAP frames that became final, a message per frame.
  void publishSmoothed(const kw::tracking::SessionAnswer& answer);
  void skipFrame(const std_msgs::Header& header, const std::string& reason);
  // `people`: tracks running after the frame (-1: the session's count now).
  void publishStatus(const std_msgs::Header& header, uint8_t state, const std::string& message,
                     const kw::tracking::TrackEstimate* estimate, int people = -1);
  void reportDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status);

  TrackerNodeConfig config_;
  kw::gait::GaitTable prior_table_;
  kw::prior::PriorOptions prior_options_;
  std::optional<kw::vision::Camera> file_camera_;
  kw::vision::GroundPlane file_ground_;

  std::unique_ptr<image_transport::ImageTransport> image_transport_;
  image_transport::CameraSubscriber camera_subscriber_;
  ros::Subscriber init_box_subscriber_;
  image_transport::Publisher overlay_publisher_;
  ros::Publisher body_pose_publisher_, body_poses_publisher_, smoothed_poses_publisher_, pose_publisher_, walker_state_publisher_,
      status_publisher_, particle_cloud_publisher_, markers_publisher_, ground_tracks_publisher_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  std::unique_ptr<RateDiagnostic> input_rate_, output_rate_;
  std::unique_ptr<diagnostic_updater::TimeStampStatus> output_latency_;
  ros::WallTimer diagnostics_timer_;  // wall time: sim time stalls before the clock and when a bag loops

  // The frames waiting for the worker (oldest first, at most ~image_queue_size) and the
  // worker's stop flag.
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Frame> waiting_;
  std::optional<cv::Rect2d> waiting_box_;  // from ~init_box, for the worker's session
  // What dynamic_reconfigure may change (cfg/Tracker.cfg), for the worker: set under mutex_,
  // copied by the worker at each frame.
  struct LiveSettings {
    int num_particles = 0;
    double prior_noise_scale = 1;
    bool publish_tf = true, publish_particle_cloud = true, publish_overlay = true;
    double particle_cloud_interval_s = 0.5;
  };
  LiveSettings live_;
  bool restart_requested_ = false;
  LiveSettings publishing_;  // the worker's copy for this frame
  std::unique_ptr<dynamic_reconfigure::Server<TrackerConfig>> reconfigure_server_;
  bool stopping_ = false;
  std::thread worker_;

  // Worker state (touched only by the worker thread, read under stats_mutex_ by diagnostics).
  std::unique_ptr<kw::tracking::TrackingSession> session_;
  std::string session_frame_id_;
  cv::Size session_size_;
  std::map<int, sensor_msgs::ImageConstPtr> unanswered_;  // frames held by the session
  // The stamps of the last kKeptStamps frames fed, by the session's input index: the smoothed
  // poses' stamps (they are at most resample_lag_frames old, or a track's held frames).
  static constexpr size_t kKeptStamps = 1000;
  std::map<int, ros::Time> fed_stamps_;
  ros::Time last_stamp_;
  ros::WallTime last_cloud_;
  std::mutex stats_mutex_;
  uint64_t frames_received_ = 0, frames_dropped_ = 0, frames_processed_ = 0, frames_skipped_ = 0,
           frames_answered_ = 0, resets_ = 0;
  double last_effective_sample_size_ = 0, last_processing_s_ = 0;
  int num_particles_ = 0, people_tracked_ = 0;
  uint64_t tracks_started_ = 0;
  uint64_t tracks_started_again_ = 0;  // of them, a body's second or later track (its pose jumps)
  std::string state_name_ = "waiting for frames", last_problem_;
};

TrackerNodelet::~TrackerNodelet() {
  reconfigure_server_.reset();  // no reconfiguration while the worker stops
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void TrackerNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& private_nh = getPrivateNodeHandle();
  try {
    config_ = loadTrackerNodeConfig(private_nh);
    const std::string package = ros::package::getPath("kneed_walker");
    auto orPackage = [&](const std::string& path, const char* file) {
      return path.empty() ? package + "/config/" + file : path;
    };
    prior_table_ = kw::gait::loadGaitTable(orPackage(config_.ros.gait_table, "prior_gait_table.yaml"),
                                           kw::dynamics::loadBodyProportions(orPackage(config_.ros.walker_model, "walker_model.yaml")));
    prior_options_ = kw::prior::loadPriorOptions(orPackage(config_.ros.prior_config, "prior.yaml"));
    if (!config_.ros.camera_file.empty()) {
      std::string warning;
      file_camera_ = kw::vision::Camera::load(config_.ros.camera_file, config_.ros.camera_file_unit_m, &warning);
      if (!warning.empty()) NODELET_WARN("~camera_file: %s", warning.c_str());
      file_ground_ = kw::vision::loadGroundPlane(config_.ros.camera_file);
      config_.tracker.ground_slope_rad = file_ground_.slope_rad;
    }
  } catch (const std::exception& e) {
    NODELET_FATAL("refusing to start: %s", e.what());
    throw;  // nodelet::Loader reports the failed load and does not keep this nodelet
  }

  // Once the background is learned, the held frames are answered at once: the queues hold them.
  const uint32_t queue = static_cast<uint32_t>(config_.session.background_frames) + 10;
  // A frame's answer publishes a message per person on the per-person topics.
  const uint32_t person_queue = queue * static_cast<uint32_t>(config_.session.max_people);
  body_pose_publisher_ = private_nh.advertise<BodyPose>("body_pose", person_queue);
  body_poses_publisher_ = private_nh.advertise<BodyPoseArray>("body_poses", queue);
  smoothed_poses_publisher_ = private_nh.advertise<BodyPoseArray>("body_poses_smoothed", queue);
  ground_tracks_publisher_ = private_nh.advertise<GroundTrackArray>("ground_tracks", queue);
  pose_publisher_ = private_nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("pose", person_queue);
  walker_state_publisher_ = private_nh.advertise<WalkerState>("walker_state", person_queue);
  status_publisher_ = private_nh.advertise<TrackingStatus>("status", queue, /*latch=*/true);
  // Every output is advertised; the switches (which dynamic_reconfigure may flip) gate publishing.
  particle_cloud_publisher_ = private_nh.advertise<geometry_msgs::PoseArray>("particle_cloud", 2);
  markers_publisher_ = private_nh.advertise<visualization_msgs::MarkerArray>("markers", 2 * config_.session.max_people);
  image_transport_ = std::make_unique<image_transport::ImageTransport>(nh);
  overlay_publisher_ = image_transport::ImageTransport(private_nh).advertise("overlay", 2);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  live_ = {config_.tracker.filter.num_particles, config_.ros.prior_noise_scale, config_.ros.publish_tf,
           config_.ros.publish_particle_cloud, config_.ros.publish_overlay, config_.ros.particle_cloud_interval_s};
  publishing_ = live_;
  if (!file_camera_) {
    tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh);
  }

  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, private_nh, getName());
  diagnostics_->setHardwareID("camera");
  diagnostics_->add("tracker", this, &TrackerNodelet::reportDiagnostics);
  input_rate_ = std::make_unique<RateDiagnostic>("input rate", 1.0, 120.0);
  output_rate_ = std::make_unique<RateDiagnostic>("output rate", 1.0, 120.0);
  output_latency_ = std::make_unique<diagnostic_updater::TimeStampStatus>(
      diagnostic_updater::TimeStampStatusParam(-1.0, 5.0), "output latency");
  diagnostics_->add(*input_rate_);
  diagnostics_->add(*output_rate_);
  diagnostics_->add(*output_latency_);
  diagnostics_timer_ =
      nh.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { diagnostics_->force_update(); });
  num_particles_ = config_.tracker.filter.num_particles;
  // What may change while running starts from the parameters just validated (cfg/Tracker.cfg).
  reconfigure_server_ = std::make_unique<dynamic_reconfigure::Server<TrackerConfig>>(private_nh);
  reconfigure_server_->setCallback(
      [this](TrackerConfig& config, uint32_t level) { onReconfigure(config, level); });

  std_msgs::Header start;
  start.stamp = ros::Time::now();
  publishStatus(start, TrackingStatus::WAITING, "waiting for frames", nullptr);

  // A transport whose plugin is not installed (Debian packages only raw) refuses the nodelet.
  const std::vector<std::string> transports = image_transport_->getLoadableTransports();
  if (std::find(transports.begin(), transports.end(), "image_transport/" + config_.ros.image_transport) ==
      transports.end()) {
    std::string list;
    for (const std::string& t : transports) list += (list.empty() ? "" : ", ") + t.substr(t.find('/') + 1);
    NODELET_FATAL("refusing to start: %s/image_transport = '%s' is not installed (installed: %s)",
                  private_nh.getNamespace().c_str(), config_.ros.image_transport.c_str(), list.c_str());
    throw std::invalid_argument("image_transport '" + config_.ros.image_transport + "' is not installed");
  }
  worker_ = std::thread(&TrackerNodelet::workerLoop, this);
  init_box_subscriber_ = private_nh.subscribe("init_box", 1, &TrackerNodelet::onInitBox, this);
  camera_subscriber_ = image_transport_->subscribeCamera(
      "image", static_cast<uint32_t>(config_.ros.image_queue_size), &TrackerNodelet::onFrame, this,
      image_transport::TransportHints(config_.ros.image_transport, ros::TransportHints(), private_nh));
  NODELET_INFO("tracking up to %d %s with %d particles each (seed %lu), %.2f m tall; input %s; camera %s",
               config_.session.max_people, config_.session.max_people == 1 ? "person" : "people",
               config_.tracker.filter.num_particles, static_cast<unsigned long>(config_.tracker.filter.seed), config_.tracker.person_height_m,
               camera_subscriber_.getTopic().c_str(),
               file_camera_ ? config_.ros.camera_file.c_str() : ("camera_info + tf from " + config_.ros.world_frame).c_str());
}

void TrackerNodelet::onFrame(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& info) {
  input_rate_->tick();
  {
    std::lock_guard<std::mutex> stats(stats_mutex_);
    ++frames_received_;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (waiting_.size() >= static_cast<size_t>(config_.ros.image_queue_size)) {
    waiting_.pop_front();
    std::lock_guard<std::mutex> stats(stats_mutex_);
    ++frames_dropped_;
  }
  waiting_.push_back(Frame{image, info});
  wake_.notify_one();
}

void TrackerNodelet::onInitBox(const sensor_msgs::RegionOfInterestConstPtr& box) {
  if (box->width == 0 || box->height == 0) {
    NODELET_ERROR("~init_box: a box of %ux%u px is empty; ignored", box->width, box->height);
    return;
  }
  NODELET_INFO("~init_box: a box at (%u, %u), %ux%u px; the track starts from it at the next frame if it lies on "
               "the image", box->x_offset, box->y_offset, box->width, box->height);
  std::lock_guard<std::mutex> lock(mutex_);
  waiting_box_ = cv::Rect2d(box->x_offset, box->y_offset, box->width, box->height);
}

void TrackerNodelet::onReconfigure(TrackerConfig& config, uint32_t /*level*/) {
  std::lock_guard<std::mutex> lock(mutex_);
  // dynamic_reconfigure clamps to the ranges but lets NaN through: a NaN keeps the value in force.
  if (!std::isfinite(config.prior_noise_scale)) {
    NODELET_WARN("reconfigure: prior_noise_scale must be a finite number in [0, 100]; kept %g", live_.prior_noise_scale);
    config.prior_noise_scale = live_.prior_noise_scale;
  }
  if (!std::isfinite(config.particle_cloud_interval_s)) {
    NODELET_WARN("reconfigure: particle_cloud_interval_s must be a finite number in [0, 3600]; kept %g",
                 live_.particle_cloud_interval_s);
    config.particle_cloud_interval_s = live_.particle_cloud_interval_s;
  }
  if (config.num_particles != live_.num_particles || config.prior_noise_scale != live_.prior_noise_scale)
    restart_requested_ = true;
  if (config.restart) restart_requested_ = true;
  config.restart = false;  // a button: it reads false again
  live_ = {config.num_particles, config.prior_noise_scale, config.publish_tf, config.publish_particle_cloud,
           config.publish_overlay, config.particle_cloud_interval_s};
}

void TrackerNodelet::workerLoop() {
  for (;;) {
    Frame frame;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !waiting_.empty(); });
      if (stopping_) return;
      frame = std::move(waiting_.front());
      waiting_.pop_front();
    }
    try {
      process(frame);
    } catch (const std::exception& e) {
      // Nothing a message holds may stop the tracker: the frame is skipped and the track
      // starts over.
      if (session_) session_->reset();
      unanswered_.clear();
      fed_stamps_.clear();
      skipFrame(frame.image->header, std::string("tracker error, starting over: ") + e.what());
    }
  }
}

kw::prior::PriorOptions TrackerNodelet::priorOptions() const {
  kw::prior::PriorOptions options = prior_options_;
  for (double& s : options.noise_scale) s *= config_.ros.prior_noise_scale;
  return options;
}

std::string TrackerNodelet::prepareSession(const Frame& frame) {
  const cv::Size size(static_cast<int>(frame.image->width), static_cast<int>(frame.image->height));
  if (session_ && size == session_size_ && frame.image->header.frame_id == session_frame_id_) return "";
  if (session_) {
    NODELET_WARN("the images changed from %dx%d in '%s' to %dx%d in '%s': starting over", session_size_.width,
                 session_size_.height, session_frame_id_.c_str(), size.width, size.height,
                 frame.image->header.frame_id.c_str());
    ++resets_;
  }
  session_.reset();
  unanswered_.clear();
  fed_stamps_.clear();
  std::optional<kw::vision::Camera> camera = file_camera_;
  if (camera) {
    if (camera->width() != size.width || camera->height() != size.height)
      return "the image is " + std::to_string(size.width) + "x" + std::to_string(size.height) + ", ~camera_file " +
             config_.ros.camera_file + " is for " + std::to_string(camera->width()) + "x" +
             std::to_string(camera->height());
  } else {
    geometry_msgs::TransformStamped pose;
    try {
      pose = tf_buffer_->lookupTransform(config_.ros.world_frame, frame.info->header.frame_id, ros::Time(0));
    } catch (const tf2::TransformException& e) {
      return "no camera pose: tf has no transform from " + config_.ros.world_frame + " to " +
             frame.info->header.frame_id + " (" + e.what() + "); publish it (e.g. /tf_static) or set ~camera_file";
    }
    try {
      camera = toCamera(*frame.info, pose);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
  }
  const kw::vision::GroundPlane ground = file_camera_ ? file_ground_ : kw::vision::GroundPlane{};
  session_ = std::make_unique<kw::tracking::TrackingSession>(
      kw::tracking::trackerFactory(*camera, ground, prior_table_, priorOptions(), config_.tracker, config_.likelihood),
      config_.session);
  session_size_ = size;
  session_frame_id_ = frame.image->header.frame_id;
  const auto& b = config_.ros.init_box;
  if (!b.empty()) {
    try {
      session_->startFromBox(cv::Rect2d(cv::Point2d(b[0], b[1]), cv::Point2d(b[2], b[3])));
    } catch (const std::invalid_argument& e) {
      NODELET_ERROR("~init_box [%g, %g, %g, %g] cannot be used (%s): looking for the person instead", b[0], b[1],
                    b[2], b[3], e.what());
    }
  }
  return "";
}

void TrackerNodelet::process(const Frame& frame) {
  const auto started = std::chrono::steady_clock::now();
  const std_msgs::Header& header = frame.image->header;
  bool restart = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    publishing_ = live_;
    std::swap(restart, restart_requested_);
  }
  if (restart) {
    // dynamic_reconfigure: a new particle count, a new prior noise scale, or the restart button.
    // The session is made again at this frame.
    const int particles = publishing_.num_particles;
    config_.tracker.filter.num_particles = particles;
    config_.tracker.min_particles = std::min(config_.ros.min_particles, particles);
    config_.ros.prior_noise_scale = publishing_.prior_noise_scale;
    NODELET_INFO("reconfigured: starting over with %d particles, prior noise x%g", particles,
                 config_.ros.prior_noise_scale);
    session_.reset();
    unanswered_.clear();
    fed_stamps_.clear();
    std::lock_guard<std::mutex> stats(stats_mutex_);
    ++resets_;
    num_particles_ = particles;
  }
  std::string problem = frameProblem(*frame.image, *frame.info);
  if (!problem.empty()) return skipFrame(header, problem);
  // The same stamp again (a driver or relay that repeats a frame): skipped and counted, as
  // track_offline skips it; the track goes on.
  if (!last_stamp_.isZero() && header.stamp == last_stamp_)
    return skipFrame(header, "its stamp is not after the previous frame's");
  if (!last_stamp_.isZero() && header.stamp < last_stamp_) {
    // A bag that loops or was played again: the track starts over from this frame.
    NODELET_WARN("the image stamp went back from %.3f to %.3f s (a bag looped?): starting over", last_stamp_.toSec(),
                 header.stamp.toSec());
    if (session_) session_->reset();
    unanswered_.clear();
    fed_stamps_.clear();
    std::lock_guard<std::mutex> stats(stats_mutex_);
    ++resets_;
  }
  last_stamp_ = header.stamp;
  problem = prepareSession(frame);
  if (!problem.empty()) return skipFrame(header, problem);

  cv_bridge::CvImageConstPtr bgr;
  try {
    bgr = cv_bridge::toCvShare(frame.image, "bgr8");
  } catch (const cv_bridge::Exception& e) {
    return skipFrame(header, std::string("cannot convert the image to bgr8: ") + e.what());
  }
  std::optional<cv::Rect2d> box;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    box.swap(waiting_box_);
  }
  if (box) {
    try {
      session_->startFromBox(*box);
    } catch (const std::invalid_argument& e) {
      NODELET_ERROR("~init_box (%g, %g) %gx%g px cannot be used: %s", box->x, box->y, box->width, box->height, e.what());
    }
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    session_->setBacklogFrames(static_cast<int>(waiting_.size()));
  }
  std::vector<kw::tracking::SessionAnswer> answers;
  try {
    answers = session_->feed(bgr->image, header.stamp.toSec());
  } catch (const std::invalid_argument& e) {
    return skipFrame(header, e.what());
  }
  unanswered_[session_->framesFed() - 1] = frame.image;
  fed_stamps_[session_->framesFed() - 1] = header.stamp;
  while (fed_stamps_.size() > kKeptStamps) fed_stamps_.erase(fed_stamps_.begin());
  {
    std::lock_guard<std::mutex> stats(stats_mutex_);
    ++frames_processed_;
    last_processing_s_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  }
  if (answers.empty()) {
    const bool learning = session_->state() == kw::tracking::SessionState::kLearningBackground;
    publishStatus(header, TrackingStatus::WAITING,
                  std::string(kw::tracking::stateName(session_->state())) + " (" +
                      (learning ? std::to_string(session_->framesFed()) + "/" +
                                      std::to_string(config_.session.background_frames) + " frames)"
                                : std::to_string(session_->framesHeld()) + " frames held)"),
                  nullptr);
    return;
  }
  for (const kw::tracking::SessionAnswer& answer : answers) {
    const auto held = unanswered_.find(answer.input);
    publishAnswer(answer, held != unanswered_.end() ? held->second : frame.image);
    if (held != unanswered_.end()) unanswered_.erase(held);
  }
}

void TrackerNodelet::publishAnswer(const kw::tracking::SessionAnswer& answer, const sensor_msgs::ImageConstPtr& image) {
  std_msgs::Header header;
  header.stamp = image->header.stamp;
  header.frame_id = config_.ros.world_frame;
  // For ~status: the lowest-numbered body still tracked, else the lowest-numbered lost one.
  const kw::tracking::TrackEstimate* first = nullptr;
  for (const kw::tracking::PersonAnswer& person : answer.people)
    if (person.estimate && (!first || (first->lost && !person.estimate->lost))) first = &*person.estimate;
  {
    std::lock_guard<std::mutex> stats(stats_mutex_);
    ++frames_answered_;
    state_name_ = kw::tracking::stateName(answer.state);
    if (first) {
      last_effective_sample_size_ = first->effective_sample_size;
      num_particles_ = first->num_particles;
    }
    people_tracked_ = session_->trackCount();
    for (const kw::tracking::PersonAnswer& person : answer.people) {
      tracks_started_ += person.started;
      tracks_started_again_ += person.started && person.track > 1;
    }
  }
  if (answer.start_failed) NODELET_ERROR("frame at %.3f s: %s", header.stamp.toSec(), answer.message.c_str());
  for (const kw::tracking::PersonAnswer& person : answer.people)
    if (!person.message.empty() && (person.started || person.ended))
      NODELET_INFO("frame at %.3f s: body %d: %s", header.stamp.toSec(), person.body, person.message.c_str());
  auto poses = boost::make_shared<BodyPoseArray>();
  poses->header = header;
  auto ground_tracks = boost::make_shared<GroundTrackArray>();
  ground_tracks->header = header;
  cv_bridge::CvImagePtr picture;
  if (publishing_.publish_overlay && overlay_publisher_.getNumSubscribers() > 0) picture = cv_bridge::toCvCopy(image, "bgr8");
  geometry_msgs::PoseArray cloud;
  const ros::WallTime now = ros::WallTime::now();
  const bool send_cloud = publishing_.publish_particle_cloud && (now - last_cloud_).toSec() >= publishing_.particle_cloud_interval_s;
  for (const kw::tracking::PersonAnswer& person : answer.people) {
    if (!person.estimate) continue;
    const kw::tracking::TrackEstimate& estimate = *person.estimate;
    const kw::tracking::Tracker& tracker = session_->tracker(person.body);
    // The particles walk the prior table's gaits at the slope nearest the ground's that has any
    // (none uphill beyond 4.3°): say so once when that is more than a degree away.
    const double nearest_gait_slope_rad = config_.tracker.ground_slope_rad >= 0 ? tracker.gaitSlopesRad().back()
                                                                                : tracker.gaitSlopesRad().front();
    if (std::abs(nearest_gait_slope_rad - config_.tracker.ground_slope_rad) > M_PI / 180)
      NODELET_WARN_ONCE("the ground slopes %.1f degrees, but the prior's gait table has no gaits there: the walkers "
                        "walk its %.1f-degree gaits", config_.tracker.ground_slope_rad * 180 / M_PI,
                        nearest_gait_slope_rad * 180 / M_PI);
    const std::string id = std::to_string(person.body);
    poses->bodies.push_back(toBodyPose(estimate, header, id, tracker.imageBox(estimate.pose),
                                       cv::Size(tracker.camera().width(), tracker.camera().height())));
    poses->bodies.back().track = static_cast<uint32_t>(person.track);
    body_pose_publisher_.publish(boost::make_shared<BodyPose>(poses->bodies.back()));
    pose_publisher_.publish(boost::make_shared<geometry_msgs::PoseWithCovarianceStamped>(toPose(estimate, header)));
    walker_state_publisher_.publish(boost::make_shared<WalkerState>(toWalkerState(estimate, header)));
    markers_publisher_.publish(
        boost::make_shared<visualization_msgs::MarkerArray>(toMarkers(estimate, header, id, 1.0, tracker.shape())));
    if (publishing_.publish_tf) tf_broadcaster_->sendTransform(toTransforms(estimate, header, id));
    if (person.ground_track) {
      const Eigen::Vector2d position = person.ground_track->position();
      ground_tracks->people.push_back(toGroundTrack(*person.ground_track, header, id, tracker.ground().height(position)));
      markers_publisher_.publish(boost::make_shared<visualization_msgs::MarkerArray>(
          toGroundTrackMarkers(ground_tracks->people.back(), 1.0)));
    }
    if (send_cloud && tracker.started()) {
      const geometry_msgs::PoseArray own = toParticleCloud(tracker.particles(), header);
      cloud.header = own.header;
      cloud.poses.insert(cloud.poses.end(), own.poses.begin(), own.poses.end());
    }
    if (picture) {
      kw::vision::BodyOutlines outlines;
      tracker.project(estimate.pose, outlines);
      kw::vision::drawOverlay(picture->image, tracker.camera(), estimate.pose, outlines);
    }
  }
  body_poses_publisher_.publish(poses);
  ground_tracks_publisher_.publish(ground_tracks);
  publishSmoothed(answer);
  if (!cloud.poses.empty()) {
    last_cloud_ = now;
    particle_cloud_publisher_.publish(boost::make_shared<geometry_msgs::PoseArray>(std::move(cloud)));
  }
  if (picture) overlay_publisher_.publish(picture->toImageMsg());
  // The session's message and what happened to each person at this frame.
  std::string message = answer.message;
  for (const kw::tracking::PersonAnswer& person : answer.people)
    if (!person.message.empty())
      message += (message.empty() ? "" : "; ") + (config_.session.max_people > 1 ? "body " + std::to_string(person.body) + ": " : "") +
                 person.message;
  const uint8_t state = answer.state == kw::tracking::SessionState::kTracking ? TrackingStatus::TRACKING
                        : answer.state == kw::tracking::SessionState::kLost   ? TrackingStatus::LOST
                                                                              : TrackingStatus::WAITING;
  const int people = static_cast<int>(std::count_if(answer.people.begin(), answer.people.end(), [](const auto& p) {
    return p.estimate && !p.ended;
  }));
  publishStatus(header, state, message, first, people);
  if (state != TrackingStatus::TRACKING) return;
  output_rate_->tick();
  output_latency_->tick(header.stamp);
}

void TrackerNodelet::publishSmoothed(const kw::tracking::SessionAnswer& answer) {
  std::map<int, BodyPoseArray::Ptr> by_input;  // in the order of the frames they describe
  for (const kw::tracking::PersonAnswer& person : answer.people) {
    const kw::tracking::Tracker& tracker = session_->tracker(person.body);
    for (const kw::tracking::MapFrame& frame : person.map_frames) {
      const auto stamp = fed_stamps_.find(frame.input);
      if (stamp == fed_stamps_.end()) continue;  // older than the stamps kept (cannot happen within the lag)
      BodyPoseArray::Ptr& poses = by_input[frame.input];
      if (!poses) {
        poses = boost::make_shared<BodyPoseArray>();
        poses->header.stamp = stamp->second;
        poses->header.frame_id = config_.ros.world_frame;
      }
      poses->bodies.push_back(toBodyPose(frame.pose, poses->header, std::to_string(person.body),
                                         tracker.imageBox(frame.pose),
                                         cv::Size(tracker.camera().width(), tracker.camera().height())));
      poses->bodies.back().track = static_cast<uint32_t>(frame.track);
      if (publishing_.publish_tf)
        tf_broadcaster_->sendTransform(toTransforms(frame.pose, std::atan2(frame.pose.forward.y(), frame.pose.forward.x()),
                                                    poses->header, std::to_string(person.body) + "_smoothed"));
    }
  }
  for (const auto& [input, poses] : by_input) smoothed_poses_publisher_.publish(poses);
}

void TrackerNodelet::skipFrame(const std_msgs::Header& header, const std::string& reason) {
  uint64_t skipped;
  {
    std::lock_guard<std::mutex> stats(stats_mutex_);
    skipped = ++frames_skipped_;
    last_problem_ = reason;
  }
  NODELET_WARN_THROTTLE(5.0, "skipped a frame: %s (%lu skipped so far)", reason.c_str(),
                        static_cast<unsigned long>(skipped));
  publishStatus(header, TrackingStatus::WAITING, "skipped: " + reason, nullptr);
}

void TrackerNodelet::publishStatus(const std_msgs::Header& header, uint8_t state, const std::string& message,
                                   const kw::tracking::TrackEstimate* estimate, int people) {
  auto status = boost::make_shared<TrackingStatus>();
  status->header.stamp = header.stamp;
  status->header.frame_id = config_.ros.world_frame;
  status->state = state;
  status->num_particles =
      static_cast<uint32_t>(estimate ? estimate->num_particles : config_.tracker.filter.num_particles);
  status->people_tracked = static_cast<uint32_t>(people >= 0 ? people : session_ ? session_->trackCount() : 0);
  if (estimate) {
    status->effective_sample_size = estimate->effective_sample_size;
    status->resampled = estimate->resampled;
    status->max_log_likelihood = estimate->map_log_likelihood;
  }
  {
    std::lock_guard<std::mutex> stats(stats_mutex_);
    status->processing_time = last_processing_s_;
    status->frames_received = frames_received_;
    status->frames_processed = frames_processed_;
    status->frames_skipped = frames_skipped_;
    status->frames_dropped = frames_dropped_;
    status->frames_answered = frames_answered_;
    status->tracks_started_again = tracks_started_again_;
  }
  status->message = message;
  status_publisher_.publish(status);
}

void TrackerNodelet::reportDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> stats(stats_mutex_);
  const bool troubled = frames_skipped_ > 0 || frames_dropped_ > 0;
  status.summary(troubled ? diagnostic_msgs::DiagnosticStatus::WARN : diagnostic_msgs::DiagnosticStatus::OK,
                 troubled && !last_problem_.empty() ? state_name_ + "; last skipped frame: " + last_problem_ : state_name_);
  status.add("frames received", frames_received_);
  status.add("frames processed", frames_processed_);
  status.add("frames answered", frames_answered_);
  status.add("frames dropped (arrived while busy)", frames_dropped_);
  status.add("frames skipped (unusable)", frames_skipped_);
  status.add("restarts (stamps went back, images changed)", resets_);
  status.add("effective sample size", last_effective_sample_size_);
  status.add("processing time (s)", last_processing_s_);
  status.add("particles per person", num_particles_);
  status.add("people tracked", people_tracked_);
  status.add("tracks started", tracks_started_);
  status.add("tracks started again on a body (lost and started again: its pose jumps)", tracks_started_again_);
  status.add("input", camera_subscriber_.getTopic());
}

}  // namespace kneed_walker::ros_glue

PLUGINLIB_EXPORT_CLASS(kneed_walker::ros_glue::TrackerNodelet, nodelet::Nodelet)
