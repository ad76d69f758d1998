#include "kneed_walker/ros/conversions.h"

#include <sensor_msgs/distortion_models.h>
#include <sensor_msgs/image_encodings.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace kneed_walker::ros_glue {
namespace {

namespace enc = sensor_msgs::image_encodings;

bool supportedEncoding(const std::string& encoding) {
  return encoding == enc::MONO8 || encoding == enc::BGR8 || encoding == enc::RGB8 ||
         encoding == enc::BGRA8 || encoding == enc::RGBA8;
}

}  // namespace

std::string frameProblem(const sensor_msgs::Image& image, const sensor_msgs::CameraInfo& info) {
  std::ostringstream problem;
  if (image.width == 0 || image.height == 0) {
    problem << "image is empty (" << image.width << "x" << image.height << ")";
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
  } else if (!(std::isfinite(info.K[0]) && info.K[0] > 0 && std::isfinite(info.K[4]) &&
               info.K[4] > 0 && std::isfinite(info.K[2]) && std::isfinite(info.K[5]))) {
    problem << "camera_info K has no valid focal length (fx = " << info.K[0]
            << ", fy = " << info.K[4] << "): is the camera calibrated?";
  } else if (!info.D.empty() && info.distortion_model != sensor_msgs::distortion_models::PLUMB_BOB &&
             info.distortion_model != sensor_msgs::distortion_models::RATIONAL_POLYNOMIAL) {
    problem << "camera_info distortion model '" << info.distortion_model
            << "' is not supported (plumb_bob or rational_polynomial)";
  } else if (image.header.frame_id.empty()) {
    problem << "image header has no frame_id (needed to place the camera in tf)";
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

}  // namespace kneed_walker::ros_glue
