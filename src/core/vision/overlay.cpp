#include "kneed_walker/core/vision/overlay.h"

#include <opencv2/imgproc.hpp>

#include "kneed_walker/core/vision/appearance_model.h"

namespace kneed_walker::core::vision {

void drawOverlay(cv::Mat& image, const Camera& camera, const body::BodyPose& pose, const BodyOutlines& outlines,
                 const std::vector<Eigen::Vector2f>& cloud_px) {
  for (const Eigen::Vector2f& p : cloud_px)
    if (p.x() >= 0 && p.y() >= 0 && p.x() < image.cols && p.y() < image.rows) {
      cv::Vec3b& pixel = image.at<cv::Vec3b>(static_cast<int>(p.y()), static_cast<int>(p.x()));
      pixel = cv::Vec3b(static_cast<uchar>(0.6 * pixel[0]), static_cast<uchar>(0.6 * pixel[1] + 100),
                        static_cast<uchar>(0.6 * pixel[2] + 100));
    }
  // BGR per part kind: foot, shank, thigh, torso, head.
  static const cv::Scalar kColours[kNumPartKinds] = {{0, 200, 255}, {255, 160, 0}, {255, 0, 160},
                                                      {60, 220, 60}, {0, 80, 255}};
  for (int p = 0; p < body::kNumBodyParts; ++p) {
    const PartOutline& outline = outlines[p];
    if (!outline.visible || outline.size < 3) continue;
    std::vector<cv::Point> points;
    for (int i = 0; i < outline.size; ++i)
      points.emplace_back(cvRound(outline.hull[i].x() * 16), cvRound(outline.hull[i].y() * 16));
    cv::polylines(image, points, true, kColours[partKind(static_cast<body::BodyPart>(p))], 1, cv::LINE_AA, 4);
  }
  const std::pair<int, int> bones[] = {{body::kWaist, body::kNeck},         {body::kNeck, body::kHead},
                                       {body::kLeftHip, body::kRightHip},    {body::kLeftHip, body::kLeftKnee},
                                       {body::kLeftKnee, body::kLeftAnkle},  {body::kRightHip, body::kRightKnee},
                                       {body::kRightKnee, body::kRightAnkle}};
  for (const auto& [a, b] : bones) {
    const auto pa = camera.project(pose.joints[a]), pb = camera.project(pose.joints[b]);
    if (!pa || !pb) continue;
    const bool left = a == body::kLeftHip || a == body::kLeftKnee;
    const bool right = a == body::kRightKnee || (a == body::kRightHip && b == body::kRightKnee);
    const cv::Scalar colour = left ? cv::Scalar(255, 80, 0) : right ? cv::Scalar(0, 0, 255) : cv::Scalar(255, 255, 255);
    cv::line(image, cv::Point(cvRound(pa->x() * 16), cvRound(pa->y() * 16)),
             cv::Point(cvRound(pb->x() * 16), cvRound(pb->y() * 16)), colour, 2, cv::LINE_AA, 4);
  }
}

}  // namespace kneed_walker::core::vision
