// Every conversion between ROS messages and the core, in one unit-tested place
// (cartographer_ros' msg_conversion.h): nothing else in the package looks inside a message.
#pragma once

#include <geometry_msgs/TransformStamped.h>
#include <opencv2/core.hpp>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <geometry_msgs/PoseArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <visualization_msgs/MarkerArray.h>

#include <cstdint>
#include <string>
#include <vector>

#include "kneed_walker/BodyPose.h"
#include "kneed_walker/GroundTrack.h"
#include "kneed_walker/WalkerState.h"
#include "kneed_walker/core/person/ground_track.h"
#include "kneed_walker/core/tracking/tracker.h"

#include "kneed_walker/core/vision/camera.h"

namespace kneed_walker::ros_glue {

// The largest image frameProblem accepts, in pixels.
constexpr uint64_t kMaxImagePixels = 64'000'000;
// Why an image + camera_info pair cannot be tracked on, or an empty string when it can:
// empty, oversized or inconsistent image buffers, no stamp (0), unsupported encodings,
// camera_info of another size, non-positive or non-finite focal lengths, unknown distortion
// models, missing frame ids.
// The nodelet and track_offline skip and count such frames instead of failing on them.
// `needs_frame_id`: the camera is placed through tf by the image's frame id (false: the camera
// comes from a calibration file).
std::string frameProblem(const sensor_msgs::Image& image, const sensor_msgs::CameraInfo& info,
                         bool needs_frame_id = true);
// The camera_info part of frameProblem: why the intrinsics cannot be used (focal lengths,
// distortion model and coefficients), or an empty string.
std::string cameraInfoProblem(const sensor_msgs::CameraInfo& info);

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

// --- The tracker's outputs as messages -----------------------------------------------------
// `header`: the image's stamp and the world frame. REP 155 names: body_<id> at the mid-hip
// (x along the walking direction, z up), joint frames <joint>_<id> beneath it.

// `image_box_px`: the body's projected parts' bounding box (Tracker::imageBox), clipped to
// the image of `image_size`.
BodyPose toBodyPose(const core::tracking::TrackEstimate& estimate, const std_msgs::Header& header,
                    const std::string& body_id, const cv::Rect2d& image_box_px, const cv::Size& image_size);
// A pose without the particles' spread (the smoothed MAP pose): root covariance and joint
// standard deviations zero, the root turned to the walking direction.
BodyPose toBodyPose(const core::body::BodyPose& pose, const std_msgs::Header& header, const std::string& body_id,
                    const cv::Rect2d& image_box_px, const cv::Size& image_size);
// The mid-hip and walking direction with the particles' spread (as amcl's ~amcl_pose).
geometry_msgs::PoseWithCovarianceStamped toPose(const core::tracking::TrackEstimate& estimate,
                                                const std_msgs::Header& header);
WalkerState toWalkerState(const core::tracking::TrackEstimate& estimate, const std_msgs::Header& header);
// world -> body_<id>, and body_<id> -> each joint's frame.
std::vector<geometry_msgs::TransformStamped> toTransforms(const core::tracking::TrackEstimate& estimate,
                                                          const std_msgs::Header& header, const std::string& body_id);
// The same for a pose walking along `heading_rad` (the smoothed MAP pose: body_id "1_smoothed"
// names its frames body_1_smoothed, l_knee_1_smoothed, ...).
std::vector<geometry_msgs::TransformStamped> toTransforms(const core::body::BodyPose& pose, double heading_rad,
                                                          const std_msgs::Header& header, const std::string& body_id);
// The skeleton (bones as lines, joints as spheres) and the body's parts as the likelihood sees
// them (the tapered elliptical cylinders of `shape`, a triangle mesh of kPartMeshSides sides
// each, half transparent), coloured left, right and trunk; they expire after `lifetime_s` so a
// lost track's body does not linger.
constexpr int kPartMeshSides = 12;
visualization_msgs::MarkerArray toMarkers(const core::tracking::TrackEstimate& estimate, const std_msgs::Header& header,
                                          const std::string& body_id, double lifetime_s,
                                          const core::body::BodyShape& shape);
// A person's ground track at one frame (person/ground_track.h): position on the ground (z the
// ground's height there), velocity, stature and their 5x5 covariance.
GroundTrack toGroundTrack(const core::person::GroundTrackEstimate& track, const std_msgs::Header& header,
                          const std::string& body_id, double ground_height_m);
// The ground track in rviz: the position's 2-sd ellipse on the ground (a flat cylinder, its axes
// the covariance's), an arrow of the velocity (one second ahead) and a line of the stature;
// namespace "ground_track_<id>", expiring after `lifetime_s`.
visualization_msgs::MarkerArray toGroundTrackMarkers(const GroundTrack& track, double lifetime_s);
// Each particle's mid-hip, facing its walking direction.
geometry_msgs::PoseArray toParticleCloud(const std::vector<core::tracking::TrackerParticle>& particles,
                                         const std_msgs::Header& header);

}  // namespace kneed_walker::ros_glue
