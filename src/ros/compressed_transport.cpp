// A "compressed" image_transport: images as JPEG in sensor_msgs/CompressedImage, on the
// "<topic>/compressed" sub-topic, with the ROS compressed transport's format field
// ("bgr8; jpeg compressed bgr8"), so that bags recorded with compressed images play into the
// nodelet (~image_transport: compressed) and rqt_image_view shows what it publishes. Debian
// packages image_transport with its raw transport only (compressed_image_transport is not
// packaged), hence this one; it reads PNG-compressed images too (OpenCV decodes either).
#include <cv_bridge/cv_bridge.h>
#include <image_transport/simple_publisher_plugin.h>
#include <image_transport/simple_subscriber_plugin.h>
#include <opencv2/imgcodecs.hpp>
#include <pluginlib/class_list_macros.hpp>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/image_encodings.h>

#include <string>
#include <vector>

namespace kneed_walker::ros_glue {

class CompressedPublisher : public image_transport::SimplePublisherPlugin<sensor_msgs::CompressedImage> {
 public:
  std::string getTransportName() const override { return "compressed"; }

 protected:
  void publish(const sensor_msgs::Image& message, const PublishFn& publish_fn) const override {
    namespace enc = sensor_msgs::image_encodings;
    const std::string encoding = message.encoding == enc::MONO8 ? enc::MONO8 : enc::BGR8;
    cv_bridge::CvImageConstPtr image;
    try {
      image = cv_bridge::toCvCopy(message, encoding);
    } catch (const cv_bridge::Exception& e) {
      ROS_ERROR_THROTTLE(5.0, "compressed transport: cannot convert a '%s' image: %s", message.encoding.c_str(), e.what());
      return;
    }
    sensor_msgs::CompressedImage compressed;
    compressed.header = message.header;
    compressed.format = encoding + "; jpeg compressed " + encoding;
    if (!cv::imencode(".jpg", image->image, compressed.data, {cv::IMWRITE_JPEG_QUALITY, 95})) {
      ROS_ERROR_THROTTLE(5.0, "compressed transport: JPEG encoding failed");
      return;
    }
    publish_fn(compressed);
  }
};

class CompressedSubscriber : public image_transport::SimpleSubscriberPlugin<sensor_msgs::CompressedImage> {
 public:
  std::string getTransportName() const override { return "compressed"; }

 protected:
  void internalCallback(const sensor_msgs::CompressedImageConstPtr& message, const Callback& user_cb) override {
    const cv::Mat decoded = cv::imdecode(cv::Mat(message->data), cv::IMREAD_UNCHANGED);
    if (decoded.empty() || decoded.depth() != CV_8U) {
      ROS_ERROR_THROTTLE(5.0, "compressed transport: cannot decode an image of format '%s' (%zu bytes)",
                         message->format.c_str(), message->data.size());
      return;
    }
    namespace enc = sensor_msgs::image_encodings;
    const std::string encoding = decoded.channels() == 1 ? enc::MONO8 : decoded.channels() == 4 ? enc::BGRA8 : enc::BGR8;
    user_cb(cv_bridge::CvImage(message->header, encoding, decoded).toImageMsg());
  }
};

}  // namespace kneed_walker::ros_glue

PLUGINLIB_EXPORT_CLASS(kneed_walker::ros_glue::CompressedPublisher, image_transport::PublisherPlugin)
PLUGINLIB_EXPORT_CLASS(kneed_walker::ros_glue::CompressedSubscriber, image_transport::SubscriberPlugin)
