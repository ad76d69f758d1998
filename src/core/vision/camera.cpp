#include "kneed_walker/core/vision/camera.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include <Eigen/LU>
#include <Eigen/SVD>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "kneed_walker/core/common/config_file.h"

namespace kneed_walker::core::vision {
Camera::Camera(const Eigen::Matrix3d& intrinsics, const std::vector<double>& distortion,
               const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation_m,
               int width_px, int height_px)
    : k_(intrinsics),
      distortion_(distortion),
      rotation_(rotation),
      translation_(translation_m),
      width_(width_px),
      height_(height_px) {
  if (!(k_.allFinite() && k_(0, 0) > 0 && k_(1, 1) > 0 && k_(2, 2) == 1 && k_(0, 1) == 0 &&
        k_(1, 0) == 0 && k_(2, 0) == 0 && k_(2, 1) == 0))
    throw std::invalid_argument(
        "camera intrinsics must be [fx 0 cx; 0 fy cy; 0 0 1] with fx, fy > 0 (OpenCV's model has "
        "no skew)");
  const size_t n = distortion.size();
  if (n != 0 && n != 4 && n != 5 && n != 8)
    throw std::invalid_argument("camera distortion needs 0, 4, 5 or 8 coefficients (OpenCV order), got " +
                                std::to_string(n));
  for (double d : distortion)
    if (!std::isfinite(d)) throw std::invalid_argument("camera distortion coefficients must be finite");
  const double* d = distortion.data();
  if (n >= 4) k1_ = d[0], k2_ = d[1], p1_ = d[2], p2_ = d[3];
  if (n >= 5) k3_ = d[4];
  if (n == 8) k4_ = d[5], k5_ = d[6], k6_ = d[7];
  rational_ = k4_ != 0 || k5_ != 0 || k6_ != 0;
  if (!rotation.allFinite() ||
      (rotation * rotation.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
      rotation.determinant() < 0)
    throw std::invalid_argument("camera rotation R must be a rotation matrix (RᵀR = I, det R = 1)");
  if (!translation_m.allFinite()) throw std::invalid_argument("camera translation must be finite");
  if (width_px <= 0 || height_px <= 0)
    throw std::invalid_argument("camera image size must be positive");
}

Camera Camera::load(const std::string& path, double file_length_unit_m, std::string* warning) {
  if (!(file_length_unit_m > 0)) throw std::invalid_argument("file_length_unit_m must be > 0");
  common::ConfigFile file(path, "calibration");
  cv::Mat k, d, r, t;
  int width = 0, height = 0;
  auto sized = [&](const char* key, cv::Mat& m, int rows, int cols) {
    if (file.read(key, m, common::Need::kRequired) && (m.rows != rows || m.cols != cols))
      file.problem(key, "must be " + std::to_string(rows) + "x" + std::to_string(cols) + ", is " +
                            std::to_string(m.rows) + "x" + std::to_string(m.cols));
  };
  sized("camera_matrix", k, 3, 3);
  sized("R", r, 3, 3);
  if (file.read("t", t, common::Need::kRequired) && t.total() != 3) file.problem("t", "must hold 3 values");
  file.read("distortion_coefficients", d, common::Need::kRequired);
  file.read("image_width", width, common::Need::kRequired);
  file.read("image_height", height, common::Need::kRequired);
  // A calibration file may carry other programs' keys beside these (make_synthetic adds the
  // ground plane): they are not refused.
  file.finish({}, true);
  Eigen::Matrix3d intrinsics, rotation;
  cv::cv2eigen(k, intrinsics);
  cv::cv2eigen(r, rotation);
  const std::vector<double> distortion(d.begin<double>(), d.end<double>());
  if (rotation.allFinite() && rotation.determinant() > 0) {
    const double error = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm();
    char size[64];
    std::snprintf(size, sizeof size, "%.2g", error);
    if (error > kRotationTolerance)
      throw std::invalid_argument(path + ": R is not a rotation: |R^T R - I| = " + size + ", more than the " +
                                  "1e-4 that rounding explains; write R to at least 6 decimals (calibrate_camera does)");
    if (error > 1e-9) {
      const Eigen::JacobiSVD<Eigen::Matrix3d> svd(rotation, Eigen::ComputeFullU | Eigen::ComputeFullV);
      rotation = svd.matrixU() * svd.matrixV().transpose();  // the nearest rotation
      if (warning && error > 1e-6)
        *warning = path + ": R is a rotation only to |R^T R - I| = " + size +
                   " (rounded?): the nearest rotation is used";
    }
  }
  const Eigen::Vector3d translation =
      Eigen::Vector3d(t.at<double>(0), t.at<double>(1), t.at<double>(2)) * file_length_unit_m;
  try {
    return Camera(intrinsics, distortion, rotation, translation, width, height);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

void Camera::save(const std::string& path, double file_length_unit_m) const {
  cv::FileStorage file(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
  if (!file.isOpened()) throw std::runtime_error(path + ": cannot write the calibration");
  write(file, file_length_unit_m);
}

void Camera::write(cv::FileStorage& file, double file_length_unit_m) const {
  if (!(file_length_unit_m > 0)) throw std::invalid_argument("file_length_unit_m must be > 0");
  cv::Mat k, r, t;
  cv::eigen2cv(k_, k);
  cv::eigen2cv(rotation_, r);
  const Eigen::Vector3d translation = translation_ / file_length_unit_m;
  cv::eigen2cv(translation, t);
  file << "image_width" << width_ << "image_height" << height_ << "camera_matrix" << k
       << "distortion_coefficients" << cv::Mat(1, static_cast<int>(distortion_.size()), CV_64F,
                                                const_cast<double*>(distortion_.data()))
       << "R" << r << "t" << t;
}

std::vector<Eigen::Vector3d> Camera::rays(const std::vector<Eigen::Vector2d>& pixels) const {
  std::vector<Eigen::Vector3d> result;
  if (pixels.empty()) return result;
  cv::Mat k;
  cv::eigen2cv(k_, k);
  std::vector<cv::Point2d> in, out;
  in.reserve(pixels.size());
  for (const Eigen::Vector2d& p : pixels) in.emplace_back(p.x(), p.y());
  cv::undistortPoints(in, out, k, distortion_.empty() ? cv::Mat() : cv::Mat(distortion_),
                      cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-14));
  result.reserve(out.size());
  for (const cv::Point2d& n : out) result.push_back(rotation_.transpose() * Eigen::Vector3d(n.x, n.y, 1.0));
  return result;
}

std::optional<Eigen::Vector3d> Camera::groundPoint(const Eigen::Vector2d& pixel,
                                                   double ground_height_m) const {
  const Eigen::Vector3d ray = rays({pixel}).front();
  const Eigen::Vector3d origin = centre();
  if (std::abs(ray.z()) < 1e-12) return std::nullopt;
  const double s = (ground_height_m - origin.z()) / ray.z();
  if (s <= 0) return std::nullopt;
  return origin + s * ray;
}

}  // namespace kneed_walker::core::vision
