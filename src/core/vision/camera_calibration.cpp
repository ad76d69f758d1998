#include "kneed_walker/core/vision/camera_calibration.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "kneed_walker/core/common/config_file.h"

namespace kneed_walker::core::vision {

CameraIntrinsics loadCameraIntrinsics(const std::string& path) {
  common::ConfigFile file(path, "camera intrinsics");
  CameraIntrinsics intrinsics;
  file.read("image_width", intrinsics.width_px, common::Need::kRequired);
  file.read("image_height", intrinsics.height_px, common::Need::kRequired);
  // Both forms hold the matrices as maps with a `data` list: OpenCV's !!opencv-matrix (rows,
  // cols, dt, data) and camera_info's (rows, cols, data).
  std::vector<double> matrix;
  file.map("camera_matrix", common::Need::kRequired).read("data", matrix, common::Need::kRequired, 9);
  file.map("distortion_coefficients", common::Need::kRequired)
      .read("data", intrinsics.distortion, common::Need::kRequired);
  std::string model;
  if (file.read("distortion_model", model) && model != "plumb_bob" && model != "rational_polynomial")
    file.problem("distortion_model", "is " + model +
                                         ": only plumb_bob and rational_polynomial (OpenCV's pinhole "
                                         "model) are supported");
  // camera_info's rectification and projection matrices, its camera name, and OpenCV's own
  // calibration outputs may stand beside these keys.
  file.finish({}, true);
  if (matrix.size() == 9) intrinsics.matrix = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(matrix.data());
  // Camera's constructor checks the matrix, the distortion's length and the size.
  try {
    Camera(intrinsics.matrix, intrinsics.distortion, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(),
           intrinsics.width_px, intrinsics.height_px);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
  return intrinsics;
}

std::vector<GroundPointObservation> loadGroundPoints(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path + ": cannot read the ground points");
  std::vector<GroundPointObservation> points;
  std::vector<std::string> problems;
  std::string line;
  bool header_seen = false;
  for (int number = 1; std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    if (!header_seen) {
      std::string compact;
      for (char c : line)
        if (c != ' ' && c != '\t') compact += c;
      if (compact != "u,v,x,y") {
        problems.push_back("line " + std::to_string(number) + ": the header must be u,v,x,y, is " + line);
        break;
      }
      header_seen = true;
      continue;
    }
    std::istringstream fields(line);
    std::string field;
    double values[4];
    int count = 0;
    bool bad = false;
    while (std::getline(fields, field, ',')) {
      if (count == 4) {
        bad = true;
        break;
      }
      try {
        std::size_t used = 0;
        values[count] = std::stod(field, &used);
        if (field.find_first_not_of(" \t", used) != std::string::npos || !std::isfinite(values[count])) bad = true;
      } catch (const std::exception&) {
        bad = true;
      }
      ++count;
    }
    if (bad || count != 4) {
      problems.push_back("line " + std::to_string(number) + ": needs four finite numbers u,v,x,y, is " + line);
      continue;
    }
    points.push_back({Eigen::Vector2d(values[2], values[3]), Eigen::Vector2d(values[0], values[1])});
  }
  if (!header_seen && problems.empty()) problems.push_back("no header u,v,x,y");
  common::throwIfProblems(path, "ground points", problems);
  return points;
}

namespace {

// Why a set of observations cannot give a pose, or "" when it can.
std::string observationProblem(const CameraIntrinsics& intrinsics,
                               const std::vector<GroundPointObservation>& observations) {
  const std::size_t n = observations.size();
  if (n < 4) return "needs at least 4 ground points, has " + std::to_string(n);
  for (std::size_t i = 0; i < n; ++i) {
    const GroundPointObservation& o = observations[i];
    const std::string which = "point " + std::to_string(i + 1);
    if (!o.ground_m.allFinite() || !o.pixel.allFinite()) return which + " is not finite";
    if (o.pixel.x() < 0 || o.pixel.y() < 0 || o.pixel.x() > intrinsics.width_px ||
        o.pixel.y() > intrinsics.height_px) {
      std::ostringstream message;
      message << which << ": pixel (" << o.pixel.x() << ", " << o.pixel.y() << ") is outside the "
              << intrinsics.width_px << "x" << intrinsics.height_px << " image";
      return message.str();
    }
    for (std::size_t j = 0; j < i; ++j)
      if ((observations[j].ground_m - o.ground_m).norm() < 1e-3)
        return "points " + std::to_string(j + 1) + " and " + std::to_string(i + 1) +
               " are at the same place on the ground";
  }
  // Points on one line leave the rotation about that line free: the ground points' second
  // principal spread must be a real fraction of the first.
  Eigen::MatrixXd centred(n, 2);
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const GroundPointObservation& o : observations) mean += o.ground_m / static_cast<double>(n);
  for (std::size_t i = 0; i < n; ++i) centred.row(static_cast<Eigen::Index>(i)) = (observations[i].ground_m - mean).transpose();
  const Eigen::Vector2d spread = Eigen::JacobiSVD<Eigen::MatrixXd>(centred).singularValues();
  if (spread(1) < 0.05 * spread(0)) return "the ground points lie (nearly) on one line: spread them over the ground";
  return "";
}

}  // namespace

GroundPoseFit solveGroundPose(const CameraIntrinsics& intrinsics,
                              const std::vector<GroundPointObservation>& observations) {
  const std::string problem = observationProblem(intrinsics, observations);
  if (!problem.empty()) throw std::invalid_argument(problem);
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (const GroundPointObservation& o : observations) {
    object.emplace_back(o.ground_m.x(), o.ground_m.y(), 0.0);
    image.emplace_back(o.pixel.x(), o.pixel.y());
  }
  cv::Mat k;
  cv::eigen2cv(intrinsics.matrix, k);
  const cv::Mat distortion = intrinsics.distortion.empty() ? cv::Mat() : cv::Mat(intrinsics.distortion).clone();
  // A plane seen by a camera has two poses that explain it nearly as well (IPPE returns both);
  // one puts the camera below the ground.
  std::vector<cv::Mat> rotations, translations;
  cv::solvePnPGeneric(object, image, k, distortion, rotations, translations, false, cv::SOLVEPNP_IPPE);
  std::optional<GroundPoseFit> best;
  for (std::size_t s = 0; s < rotations.size(); ++s) {
    cv::Mat rvec = rotations[s].clone(), tvec = translations[s].clone();
    cv::solvePnPRefineLM(object, image, k, distortion, rvec, tvec);
    cv::Mat r;
    cv::Rodrigues(rvec, r);
    Eigen::Matrix3d rotation;
    Eigen::Vector3d translation;
    cv::cv2eigen(r, rotation);
    cv::cv2eigen(tvec, translation);
    const Camera camera(intrinsics.matrix, intrinsics.distortion, rotation, translation, intrinsics.width_px,
                        intrinsics.height_px);
    if (camera.centre().z() <= 0) continue;
    GroundPoseFit fit{camera, {}, 0.0, 0.0};
    bool all_in_front = true;
    for (const GroundPointObservation& o : observations) {
      const std::optional<Eigen::Vector2d> pixel = camera.project(Eigen::Vector3d(o.ground_m.x(), o.ground_m.y(), 0));
      if (!pixel) {
        all_in_front = false;
        break;
      }
      fit.residuals_px.push_back((*pixel - o.pixel).norm());
      fit.rms_px += fit.residuals_px.back() * fit.residuals_px.back();
      fit.max_px = std::max(fit.max_px, fit.residuals_px.back());
    }
    if (!all_in_front) continue;
    fit.rms_px = std::sqrt(fit.rms_px / static_cast<double>(observations.size()));
    if (!best || fit.rms_px < best->rms_px) best = std::move(fit);
  }
  if (!best)
    throw std::invalid_argument(
        "no camera pose puts the camera above the ground with every point in front of it: check that "
        "each pixel belongs to its ground point (u is the column, v the row) and that x, y are metres");
  return *best;
}

std::optional<DisagreeingMark> findDisagreeingMark(const CameraIntrinsics& intrinsics,
                                                   const std::vector<GroundPointObservation>& observations,
                                                   double min_disagreement_px) {
  if (observations.size() < 5) return std::nullopt;
  std::optional<DisagreeingMark> worst;
  for (std::size_t i = 0; i < observations.size(); ++i) {
    std::vector<GroundPointObservation> others = observations;
    others.erase(others.begin() + static_cast<std::ptrdiff_t>(i));
    std::optional<GroundPoseFit> without;
    try {
      without = solveGroundPose(intrinsics, others);
    } catch (const std::invalid_argument&) {
      continue;  // the others alone give no pose (on a line, say): this mark is needed
    }
    const GroundPointObservation& left_out = observations[i];
    const std::optional<Eigen::Vector2d> seen =
        without->camera.project(Eigen::Vector3d(left_out.ground_m.x(), left_out.ground_m.y(), 0));
    const double disagreement = seen ? (*seen - left_out.pixel).norm() : std::numeric_limits<double>::infinity();
    if (!worst || disagreement > worst->disagreement_px)
      worst = DisagreeingMark{static_cast<int>(i), disagreement, std::move(*without)};
  }
  if (!worst || worst->disagreement_px <= std::max(min_disagreement_px, 3 * worst->without.rms_px)) return std::nullopt;
  return worst;
}

}  // namespace kneed_walker::core::vision
