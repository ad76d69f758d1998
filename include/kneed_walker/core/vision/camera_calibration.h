// A static camera's pose from points on the ground: what a user of their own camera measures
// (a few marks on the floor, their positions in metres and their pixels in a frame) and the
// camera's intrinsics become the calibration the tracker reads (Camera: world Z up, ground Z = 0).
//
// The pose is cv::solvePnP's (IPPE for a plane, both of its solutions tried, then refined by
// Levenberg–Marquardt), choosing the solution with the camera above the ground.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

#include "kneed_walker/core/vision/camera.h"

namespace kneed_walker::core::vision {

// A camera's intrinsics alone: what a camera driver's camera_info or OpenCV's calibration gives.
struct CameraIntrinsics {
  Eigen::Matrix3d matrix = Eigen::Matrix3d::Identity();  // [fx 0 cx; 0 fy cy; 0 0 1], px
  std::vector<double> distortion;                         // OpenCV's order: 0, 4, 5 or 8 values
  int width_px = 0;
  int height_px = 0;
};

// Reads the intrinsics from either form: OpenCV FileStorage YAML (camera_matrix and
// distortion_coefficients as !!opencv-matrix, as Camera::save writes and cv::calibrateCamera's
// samples store) or ROS's camera_info YAML (camera_calibration_parsers: camera_matrix.data,
// distortion_model, distortion_coefficients.data). Both need image_width and image_height.
// Throws std::invalid_argument naming the file and every problem (a distortion model other than
// plumb_bob or rational_polynomial included).
CameraIntrinsics loadCameraIntrinsics(const std::string& path);

// One measured ground point: where it is on the ground (metres, world X, Y; Z = 0) and where it
// is seen in the image (px, distorted, as in the frame).
struct GroundPointObservation {
  Eigen::Vector2d ground_m;
  Eigen::Vector2d pixel;
};

// Reads ground points from a CSV file with the header `u,v,x,y` (pixel column, pixel row, ground
// X and Y in metres), one point per line; blank lines and lines starting with '#' are skipped.
// Throws std::invalid_argument naming the file and line of every problem.
std::vector<GroundPointObservation> loadGroundPoints(const std::string& path);

struct GroundPoseFit {
  Camera camera;
  std::vector<double> residuals_px;  // per observation: |projected − measured|
  double rms_px = 0;
  double max_px = 0;
};

// The camera's pose from four or more ground points (not all on one line). Throws
// std::invalid_argument naming what is wrong: too few points, a non-finite value, a pixel
// outside the image, two points at one place, points on a line, or no pose with the camera
// above the ground and every point in front of it.
GroundPoseFit solveGroundPose(const CameraIntrinsics& intrinsics,
                              const std::vector<GroundPointObservation>& observations);

// A mark that does not agree with the others (a mis-click, a mis-measured position): least
// squares spreads its error over every mark, so its own residual understates it. Each mark is
// left out in turn and the pose fitted from the rest; the mark furthest from where the others'
// pose puts it is the one, when that distance is over `min_disagreement_px` and over three times
// the others' rms. Needs five marks or more (four remain); nullopt when none disagrees.
struct DisagreeingMark {
  int index = 0;                 // into the observations, from 0
  double disagreement_px = 0;    // its distance from where the others' pose puts it
  GroundPoseFit without;         // the pose from the others (residuals over them)
};
std::optional<DisagreeingMark> findDisagreeingMark(const CameraIntrinsics& intrinsics,
                                                   const std::vector<GroundPointObservation>& observations,
                                                   double min_disagreement_px = 5.0);

}  // namespace kneed_walker::core::vision
