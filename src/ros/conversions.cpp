#include "kneed_walker/ros/conversions.h"

#include <sensor_msgs/distortion_models.h>
#include <sensor_msgs/image_encodings.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "kneed_walker/core/vision/body_projection.h"

namespace kneed_walker::ros_glue {
namespace {

namespace enc = sensor_msgs::image_encodings;

bool supportedEncoding(const std::string& encoding) {
  return encoding == enc::MONO8 || encoding == enc::BGR8 || encoding == enc::RGB8 ||
         encoding == enc::BGRA8 || encoding == enc::RGBA8;
}

}  // namespace

std::string frameProblem(const sensor_msgs::Image& image, const sensor_msgs::CameraInfo& info, bool needs_frame_id) {
  std::ostringstream problem;
  if (image.width == 0 || image.height == 0) {
    problem << "image is empty (" << image.width << "x" << image.height << ")";
  } else if (image.width * static_cast<uint64_t>(image.height) > kMaxImagePixels) {
    problem << "the image is " << image.width << "x" << image.height << ", larger than the "
            << kMaxImagePixels / 1'000'000 << " megapixels this tracker takes";
  } else if (image.header.stamp.isZero()) {
    problem << "the image has no stamp (0)";
  } else if (!supportedEncoding(image.encoding)) {
    problem << "image encoding '" << image.encoding
            << "' is not supported (mono8, bgr8, rgb8, bgra8 or rgba8)";
  } else if (image.step < image.width * static_cast<unsigned>(enc::numChannels(image.encoding))) {
    problem << "image step " << image.step << " is shorter than a row of " << image.width
            << " " << image.encoding << " pixels";
  } else if (image.data.size() != static_cast<size_t>(image.step) * image.height) {
    problem << "image data holds " << image.data.size() << " bytes, step x height = "
            << static_cast<size_t>(image.step) * image.height;
  } else if (info.width != image.width || info.height != image.height) {
    problem << "camera_info is for " << info.width << "x" << info.height << " images, image is "
            << image.width << "x" << image.height;
  } else if (const std::string info_problem = cameraInfoProblem(info); !info_problem.empty()) {
    problem << info_problem;
  } else if (needs_frame_id && image.header.frame_id.empty()) {
    problem << "image header has no frame_id (needed to place the camera in tf)";
  }
  return problem.str();
}

std::string cameraInfoProblem(const sensor_msgs::CameraInfo& info) {
  std::ostringstream problem;
  if (!(std::isfinite(info.K[0]) && info.K[0] > 0 && std::isfinite(info.K[4]) && info.K[4] > 0 &&
        std::isfinite(info.K[2]) && std::isfinite(info.K[5]))) {
    problem << "camera_info K has no valid focal length (fx = " << info.K[0] << ", fy = " << info.K[4]
            << "): is the camera calibrated?";
  } else if (!info.D.empty() && info.distortion_model != sensor_msgs::distortion_models::PLUMB_BOB &&
             info.distortion_model != sensor_msgs::distortion_models::RATIONAL_POLYNOMIAL) {
    problem << "camera_info distortion model '" << info.distortion_model
            << "' is not supported (plumb_bob or rational_polynomial)";
  } else if (!std::all_of(info.D.begin(), info.D.end(), [](double d) { return std::isfinite(d); })) {
    problem << "camera_info D holds a value that is not finite";
  } else if (!(info.D.empty() || info.D.size() == 4 || info.D.size() == 5 || info.D.size() == 8) ||
             (info.distortion_model == sensor_msgs::distortion_models::RATIONAL_POLYNOMIAL && info.D.size() != 8) ||
             (info.distortion_model == sensor_msgs::distortion_models::PLUMB_BOB && info.D.size() == 8)) {
    problem << "camera_info D has " << info.D.size() << " coefficients for model '" << info.distortion_model
            << "' (plumb_bob: 4 or 5, rational_polynomial: 8)";
  }
  return problem.str();
}

sensor_msgs::CameraInfo toCameraInfo(const core::vision::Camera& camera, const std::string& frame_id) {
  sensor_msgs::CameraInfo info;
  info.header.frame_id = frame_id;
  info.width = static_cast<std::uint32_t>(camera.width());
  info.height = static_cast<std::uint32_t>(camera.height());
  const Eigen::Matrix3d& k = camera.intrinsics();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      info.K[3 * r + c] = k(r, c);
      info.R[3 * r + c] = r == c ? 1.0 : 0.0;
      info.P[4 * r + c] = k(r, c);
    }
  info.D = camera.distortion();
  if (info.D.size() == 8) {
    info.distortion_model = sensor_msgs::distortion_models::RATIONAL_POLYNOMIAL;
  } else {
    info.distortion_model = sensor_msgs::distortion_models::PLUMB_BOB;
    info.D.resize(5, 0.0);
  }
  return info;
}

geometry_msgs::TransformStamped cameraPose(const core::vision::Camera& camera, const std::string& world_frame,
                                           const std::string& camera_frame) {
  geometry_msgs::TransformStamped pose;
  pose.header.frame_id = world_frame;
  pose.child_frame_id = camera_frame;
  const Eigen::Vector3d centre = camera.centre();
  pose.transform.translation.x = centre.x();
  pose.transform.translation.y = centre.y();
  pose.transform.translation.z = centre.z();
  const Eigen::Quaterniond rotation(Eigen::Matrix3d(camera.rotation().transpose()));
  pose.transform.rotation.x = rotation.x();
  pose.transform.rotation.y = rotation.y();
  pose.transform.rotation.z = rotation.z();
  pose.transform.rotation.w = rotation.w();
  return pose;
}

core::vision::Camera toCamera(const sensor_msgs::CameraInfo& info, const geometry_msgs::TransformStamped& pose) {
  Eigen::Matrix3d k;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) k(r, c) = info.K[3 * r + c];
  const auto& q = pose.transform.rotation;
  const Eigen::Quaterniond orientation(q.w, q.x, q.y, q.z);
  if (!(std::abs(orientation.norm() - 1.0) < 1e-3))
    throw std::invalid_argument("camera pose " + pose.header.frame_id + " -> " + pose.child_frame_id +
                                " has a rotation quaternion that is not unit length");
  const Eigen::Matrix3d camera_to_world = orientation.normalized().toRotationMatrix();
  const auto& t = pose.transform.translation;
  const Eigen::Vector3d centre(t.x, t.y, t.z);
  std::vector<double> distortion = info.D;
  // plumb_bob's k3 = 0 and no distortion at all are the same camera.
  if (std::all_of(distortion.begin(), distortion.end(), [](double d) { return d == 0.0; })) distortion.clear();
  return core::vision::Camera(k, distortion, camera_to_world.transpose(), -camera_to_world.transpose() * centre,
                static_cast<int>(info.width), static_cast<int>(info.height));
}

namespace {

geometry_msgs::Quaternion yawQuaternion(double yaw_rad) {
  geometry_msgs::Quaternion q;
  q.z = std::sin(0.5 * yaw_rad);
  q.w = std::cos(0.5 * yaw_rad);
  return q;
}

geometry_msgs::Point toPoint(const Eigen::Vector3d& p) {
  geometry_msgs::Point point;
  point.x = p.x();
  point.y = p.y();
  point.z = p.z();
  return point;
}

// The root's pose covariance (x, y, z, rotation about X, Y, Z): the mid-hip's spread, the
// heading's; roll and pitch are not estimated (the walker stays upright in its plane): small.
boost::array<double, 36> rootCovariance(const core::tracking::TrackEstimate& e) {
  boost::array<double, 36> covariance{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) covariance[6 * r + c] = e.waist_covariance_m2(r, c);
  covariance[6 * 3 + 3] = covariance[6 * 4 + 4] = 1e-4;
  covariance[6 * 5 + 5] = e.heading_sd_rad * e.heading_sd_rad;
  return covariance;
}

// The skeleton's bones as joint pairs.
constexpr std::array<std::array<core::body::BodyJoint, 2>, 8> kBones = {{
    {core::body::kWaist, core::body::kNeck},
    {core::body::kNeck, core::body::kHead},
    {core::body::kWaist, core::body::kLeftHip},
    {core::body::kWaist, core::body::kRightHip},
    {core::body::kLeftHip, core::body::kLeftKnee},
    {core::body::kLeftKnee, core::body::kLeftAnkle},
    {core::body::kRightHip, core::body::kRightKnee},
    {core::body::kRightKnee, core::body::kRightAnkle},
}};

std_msgs::ColorRGBA jointColour(core::body::BodyJoint joint) {
  std_msgs::ColorRGBA colour;
  colour.a = 1;
  const std::string name = core::body::jointName(joint);
  if (name.rfind("l_", 0) == 0) {
    colour.r = 0.2f, colour.g = 0.5f, colour.b = 1.0f;  // left: blue
  } else if (name.rfind("r_", 0) == 0) {
    colour.r = 1.0f, colour.g = 0.3f, colour.b = 0.2f;  // right: red
  } else {
    colour.r = colour.g = colour.b = 0.9f;  // trunk and head: white
  }
  return colour;
}

}  // namespace

BodyPose toBodyPose(const core::tracking::TrackEstimate& e, const std_msgs::Header& header, const std::string& body_id,
                    const cv::Rect2d& image_box_px, const cv::Size& image_size) {
  BodyPose message = toBodyPose(e.pose, header, body_id, image_box_px, image_size);
  message.root.pose.orientation = yawQuaternion(e.heading_rad);
  message.root.covariance = rootCovariance(e);
  for (int j = 0; j < core::body::kNumBodyJoints; ++j) message.joint_position_std[j] = e.joint_sd_m[j].norm();
  return message;
}

BodyPose toBodyPose(const core::body::BodyPose& pose, const std_msgs::Header& header, const std::string& body_id,
                    const cv::Rect2d& image_box_px, const cv::Size& image_size) {
  BodyPose message;
  message.header = header;
  message.body_id = body_id;
  const cv::Rect box = cv::Rect(cv::Point(static_cast<int>(std::floor(image_box_px.x)), static_cast<int>(std::floor(image_box_px.y))),
                                cv::Point(static_cast<int>(std::ceil(image_box_px.br().x)),
                                          static_cast<int>(std::ceil(image_box_px.br().y)))) &
                       cv::Rect(cv::Point(), image_size);
  if (!image_box_px.empty() && box.area() > 0) {
    message.image_box.x_offset = static_cast<uint32_t>(box.x);
    message.image_box.y_offset = static_cast<uint32_t>(box.y);
    message.image_box.width = static_cast<uint32_t>(box.width);
    message.image_box.height = static_cast<uint32_t>(box.height);
  }
  message.root.pose.position = toPoint(pose.joints[core::body::kWaist]);
  message.root.pose.orientation = yawQuaternion(std::atan2(pose.forward.y(), pose.forward.x()));
  for (int j = 0; j < core::body::kNumBodyJoints; ++j) {
    message.joint_names.push_back(core::body::jointName(core::body::BodyJoint(j)));
    message.joint_positions.push_back(toPoint(pose.joints[j]));
    message.joint_position_std.push_back(0.0);
  }
  return message;
}

geometry_msgs::PoseWithCovarianceStamped toPose(const core::tracking::TrackEstimate& e, const std_msgs::Header& header) {
  geometry_msgs::PoseWithCovarianceStamped message;
  message.header = header;
  message.pose.pose.position = toPoint(e.pose.joints[core::body::kWaist]);
  message.pose.pose.orientation = yawQuaternion(e.heading_rad);
  message.pose.covariance = rootCovariance(e);
  return message;
}

WalkerState toWalkerState(const core::tracking::TrackEstimate& e, const std_msgs::Header& header) {
  WalkerState message;
  message.header = header;
  message.stance_leg = e.walker.stance_leg == core::dynamics::Leg::kLeft ? WalkerState::LEFT : WalkerState::RIGHT;
  for (int i = 0; i < 5; ++i) {
    message.q[i] = e.walker.q[i];
    message.qdot[i] = e.walker.qdot[i];
  }
  message.ground_slope = e.gait_slope_rad;
  message.time_in_stride = e.walker.time_in_stride;
  message.stride_count = e.walker.heel_strikes;
  const core::dynamics::SpringParameters& s = e.springs;
  message.stance_knee_stiffness = s.stance_knee_stiffness;
  message.stance_knee_damping = s.stance_knee_damping;
  message.swing_knee_stiffness = s.swing_knee_stiffness;
  message.swing_knee_rest_angle = s.swing_knee_rest_angle;
  message.swing_knee_damping = s.swing_knee_damping;
  message.hip_stiffness = s.hip_stiffness;
  message.torso_stiffness = s.torso_stiffness;
  message.torso_rest_angle = s.torso_rest_angle;
  message.torso_damping = s.torso_damping;
  message.toe_off_impulse = e.toe_off_impulse_ns;
  return message;
}

std::vector<geometry_msgs::TransformStamped> toTransforms(const core::tracking::TrackEstimate& e,
                                                          const std_msgs::Header& header, const std::string& body_id) {
  return toTransforms(e.pose, e.heading_rad, header, body_id);
}

std::vector<geometry_msgs::TransformStamped> toTransforms(const core::body::BodyPose& pose, double heading_rad,
                                                          const std_msgs::Header& header, const std::string& body_id) {
  std::vector<geometry_msgs::TransformStamped> transforms;
  const std::string root = "body_" + body_id;
  geometry_msgs::TransformStamped body;
  body.header = header;
  body.child_frame_id = root;
  const Eigen::Vector3d& waist = pose.joints[core::body::kWaist];
  body.transform.translation.x = waist.x();
  body.transform.translation.y = waist.y();
  body.transform.translation.z = waist.z();
  body.transform.rotation = yawQuaternion(heading_rad);
  transforms.push_back(body);
  const Eigen::Matrix3d world_to_body = Eigen::AngleAxisd(heading_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix().transpose();
  for (int j = 0; j < core::body::kNumBodyJoints; ++j) {
    if (j == core::body::kWaist) continue;  // body_<id> is the mid-hip
    geometry_msgs::TransformStamped joint;
    joint.header.stamp = header.stamp;
    joint.header.frame_id = root;
    joint.child_frame_id = std::string(core::body::jointName(core::body::BodyJoint(j))) + "_" + body_id;
    const Eigen::Vector3d offset = world_to_body * (pose.joints[j] - waist);
    joint.transform.translation.x = offset.x();
    joint.transform.translation.y = offset.y();
    joint.transform.translation.z = offset.z();
    joint.transform.rotation.w = 1;
    transforms.push_back(joint);
  }
  return transforms;
}

visualization_msgs::MarkerArray toMarkers(const core::tracking::TrackEstimate& e, const std_msgs::Header& header,
                                          const std::string& body_id, double lifetime_s,
                                          const core::body::BodyShape& shape) {
  visualization_msgs::MarkerArray markers;
  visualization_msgs::Marker bones;
  bones.header = header;
  bones.ns = "skeleton_" + body_id;
  bones.type = visualization_msgs::Marker::LINE_LIST;
  bones.action = visualization_msgs::Marker::ADD;
  bones.pose.orientation.w = 1;
  bones.scale.x = 0.04;  // line width, m
  bones.lifetime = ros::Duration(lifetime_s);
  for (const auto& [from, to] : kBones) {
    bones.points.push_back(toPoint(e.pose.joints[from]));
    bones.points.push_back(toPoint(e.pose.joints[to]));
    bones.colors.push_back(jointColour(to));
    bones.colors.push_back(jointColour(to));
  }
  visualization_msgs::Marker joints = bones;
  joints.ns = "joints_" + body_id;
  joints.type = visualization_msgs::Marker::SPHERE_LIST;
  joints.scale.x = joints.scale.y = joints.scale.z = 0.07;  // sphere diameter, m
  joints.points.clear();
  joints.colors.clear();
  for (int j = 0; j < core::body::kNumBodyJoints; ++j) {
    joints.points.push_back(toPoint(e.pose.joints[j]));
    joints.colors.push_back(jointColour(core::body::BodyJoint(j)));
  }
  // The parts: each a tapered elliptical cylinder, its side and end caps as triangles.
  visualization_msgs::Marker parts = bones;
  parts.ns = "parts_" + body_id;
  parts.type = visualization_msgs::Marker::TRIANGLE_LIST;
  parts.scale.x = parts.scale.y = parts.scale.z = 1;
  parts.color.r = parts.color.g = parts.color.b = 1;  // rviz multiplies the vertex colours by this
  parts.color.a = 0.5f;                              // half transparent: the skeleton shows through
  parts.points.clear();
  parts.colors.clear();
  const core::vision::PartAxes axes = core::vision::partAxes(e.pose, shape);
  for (int p = 0; p < core::body::kNumBodyParts; ++p) {
    const core::vision::PartFrame frame = core::vision::partFrame(e.pose, axes, p);
    const core::body::PartShape& part = shape.parts[p];
    auto surface = [&](int end, int k) {
      const double angle = 2 * M_PI * k / kPartMeshSides;
      const Eigen::Vector3d& centre = end == 0 ? axes.proximal[p] : axes.distal[p];
      const double half_width = 0.5 * (end == 0 ? part.proximal_width_m : part.distal_width_m);
      const double half_depth = 0.5 * (end == 0 ? part.proximal_depth_m : part.distal_depth_m);
      return Eigen::Vector3d(centre + half_width * std::cos(angle) * frame.across +
                             half_depth * std::sin(angle) * frame.depth);
    };
    std_msgs::ColorRGBA colour = p == core::body::kTorsoPart || p == core::body::kHeadPart
                                     ? jointColour(core::body::kWaist)
                                     : jointColour((p - core::body::kLeftThighPart) % 2 == 0 ? core::body::kLeftKnee
                                                                                              : core::body::kRightKnee);
    auto triangle = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
      for (const Eigen::Vector3d* v : {&a, &b, &c}) {
        parts.points.push_back(toPoint(*v));
        parts.colors.push_back(colour);
      }
    };
    for (int k = 0; k < kPartMeshSides; ++k) {
      const Eigen::Vector3d p0 = surface(0, k), p1 = surface(0, k + 1), d0 = surface(1, k), d1 = surface(1, k + 1);
      triangle(p0, p1, d1);
      triangle(p0, d1, d0);
      triangle(axes.proximal[p], p1, p0);
      triangle(axes.distal[p], d0, d1);
    }
  }
  markers.markers = {bones, joints, parts};
  return markers;
}

GroundTrack toGroundTrack(const core::person::GroundTrackEstimate& track, const std_msgs::Header& header,
                          const std::string& body_id, double ground_height_m) {
  GroundTrack message;
  message.header = header;
  message.body_id = body_id;
  message.measured = track.measured;
  message.position.x = track.mean(core::person::kX);
  message.position.y = track.mean(core::person::kY);
  message.position.z = ground_height_m;
  message.velocity.x = track.mean(core::person::kVx);
  message.velocity.y = track.mean(core::person::kVy);
  message.stature = track.stature();
  for (int r = 0; r < core::person::kGroundTrackDims; ++r)
    for (int c = 0; c < core::person::kGroundTrackDims; ++c)
      message.covariance[core::person::kGroundTrackDims * r + c] = track.covariance(r, c);
  return message;
}

visualization_msgs::MarkerArray toGroundTrackMarkers(const GroundTrack& track, double lifetime_s) {
  visualization_msgs::Marker spread;
  spread.header = track.header;
  spread.ns = "ground_track_" + track.body_id;
  spread.id = 0;
  spread.type = visualization_msgs::Marker::CYLINDER;
  spread.action = visualization_msgs::Marker::ADD;
  spread.lifetime = ros::Duration(lifetime_s);
  // The position's 2-sd ellipse: the cylinder's x and y along the covariance's principal axes.
  Eigen::Matrix2d position_covariance;
  position_covariance << track.covariance[0], track.covariance[1], track.covariance[5], track.covariance[6];
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> axes(position_covariance);
  const Eigen::Vector2d major = axes.eigenvectors().col(1);
  spread.pose.position = track.position;
  spread.pose.orientation = yawQuaternion(std::atan2(major.y(), major.x()));
  spread.scale.x = std::max(0.02, 4 * std::sqrt(std::max(0.0, axes.eigenvalues()(1))));  // diameters, m
  spread.scale.y = std::max(0.02, 4 * std::sqrt(std::max(0.0, axes.eigenvalues()(0))));
  spread.scale.z = 0.01;
  spread.color.r = 1.0f, spread.color.g = 0.8f, spread.color.b = 0.1f, spread.color.a = track.measured ? 0.6f : 0.3f;
  visualization_msgs::Marker velocity = spread;
  velocity.id = 1;
  velocity.type = visualization_msgs::Marker::ARROW;
  velocity.pose = geometry_msgs::Pose();
  velocity.pose.orientation.w = 1;
  velocity.scale.x = 0.04, velocity.scale.y = 0.08, velocity.scale.z = 0.1;  // shaft, head diameters and head length, m
  geometry_msgs::Point ahead = track.position;
  ahead.x += track.velocity.x;
  ahead.y += track.velocity.y;
  velocity.points = {track.position, ahead};
  visualization_msgs::Marker stature = velocity;
  stature.id = 2;
  stature.type = visualization_msgs::Marker::LINE_LIST;
  stature.scale.x = 0.02;  // line width, m
  geometry_msgs::Point top = track.position;
  top.z += track.stature;
  stature.points = {track.position, top};
  visualization_msgs::MarkerArray markers;
  markers.markers = {spread, velocity, stature};
  return markers;
}

geometry_msgs::PoseArray toParticleCloud(const std::vector<core::tracking::TrackerParticle>& particles,
                                         const std_msgs::Header& header) {
  geometry_msgs::PoseArray cloud;
  cloud.header = header;
  cloud.poses.reserve(particles.size());
  for (const core::tracking::TrackerParticle& p : particles) {
    geometry_msgs::Pose pose;
    pose.position = toPoint(p.joints[core::body::kWaist].cast<double>());
    pose.orientation = yawQuaternion(p.body.placement.value.heading_rad);
    cloud.poses.push_back(pose);
  }
  return cloud;
}

}  // namespace kneed_walker::ros_glue
