// The tracked body drawn on a frame, for people to judge the track (track_offline's overlay
// video, the nodelet's ~overlay image): the parts' outlines coloured by kind, the REP 155
// skeleton, and the particle cloud's waists as faint dots.
#pragma once

#include <opencv2/core.hpp>

#include <vector>

#include "kneed_walker/core/vision/body_projection.h"

namespace kneed_walker::core::vision {

void drawOverlay(cv::Mat& bgr, const Camera& camera, const body::BodyPose& pose, const BodyOutlines& outlines,
                 const std::vector<Eigen::Vector2f>& cloud_px = {});

}  // namespace kneed_walker::core::vision
