#include "kneed_walker/ros/conversions.h"

#include <sensor_msgs/distortion_models.h>
#include <sensor_msgs/image_encodings.h>

#include <cmath>
#include <sstream>

namespace kneed_walker {
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

}  // namespace kneed_walker
