// A calibrated static camera (paper §4–5: "roughly calibrated camera and ground plane"):
// OpenCV's pinhole model with lens distortion and the world → camera transform.
//
// World frame (REP 103): metres, right-handed, Z up, the ground plane Z = 0, as in
// ../shared/data/pets2009/View_001_camera.yml. Camera frame: OpenCV's (and REP 103's
// `_optical`): z forward, x right, y down. A world point X maps to the camera as R X + t.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/core/persistence.hpp>

#include <optional>
#include <string>
#include <vector>

namespace kneed_walker::core::vision {

class Camera {
 public:
  // distortion: OpenCV's order (k1, k2, p1, p2[, k3[, k4, k5, k6]]): 0, 4, 5 or 8 values.
  // translation in metres. Throws std::invalid_argument naming a bad argument.
  Camera(const Eigen::Matrix3d& intrinsics, const std::vector<double>& distortion,
         const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation_m, int width_px,
         int height_px);

  // Reads OpenCV FileStorage YAML with camera_matrix, distortion_coefficients, R, t,
  // image_width, image_height; t is in `file_length_unit_m` metres per file unit (0.001 for
  // the PETS calibration, which is in mm). Calibrations are often written to a few decimals:
  // an R within kRotationTolerance of orthonormal (‖RᵀR − I‖, Frobenius) is made the nearest
  // rotation, and `warning` (if given) says so with the size of the error; beyond, the file is
  // refused with it.
  static Camera load(const std::string& path, double file_length_unit_m, std::string* warning = nullptr);
  static constexpr double kRotationTolerance = 1e-4;
  // Writes the same format (t in file units of file_length_unit_m metres); load reads it back.
  void save(const std::string& path, double file_length_unit_m) const;
  // The same keys into an open file, beside the caller's own.
  void write(cv::FileStorage& file, double file_length_unit_m) const;

  // Pixel of a world point (metres), distortion applied; nullopt behind the camera (z ≤ 1 cm).
  // Written out rather than calling cv::projectPoints: it is called per body part per
  // particle, and agrees with cv::projectPoints to 1e-6 px (test_camera).
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& world_m) const {
    return projectFromCamera(toCamera(world_m));
  }
  // The same in two halves, inline for the per-particle path: a world point (or, with
  // toCameraDirection, a direction) in the camera frame, then the pixel of a camera-frame point.
  Eigen::Vector3d toCamera(const Eigen::Vector3d& world_m) const { return rotation_ * world_m + translation_; }
  Eigen::Vector3d toCameraDirection(const Eigen::Vector3d& world) const { return rotation_ * world; }
  std::optional<Eigen::Vector2d> projectFromCamera(const Eigen::Vector3d& c) const {
    if (c.z() <= kMinimumDepthM) return std::nullopt;
    // OpenCV's distortion model (cv::projectPoints without thin prism or tilt).
    const double x = c.x() / c.z(), y = c.y() / c.z();
    const double r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
    double radial = 1 + k1_ * r2 + k2_ * r4 + k3_ * r6;
    if (rational_) radial /= 1 + k4_ * r2 + k5_ * r4 + k6_ * r6;
    const double xd = x * radial + 2 * p1_ * x * y + p2_ * (r2 + 2 * x * x);
    const double yd = y * radial + p1_ * (r2 + 2 * y * y) + 2 * p2_ * x * y;
    return Eigen::Vector2d(k_(0, 0) * xd + k_(0, 2), k_(1, 1) * yd + k_(1, 2));
  }
  // The same pixel and its 2×3 derivative with respect to the camera-frame point (the
  // distortion model's Jacobian chained with the perspective division's); false behind the
  // camera. The likelihood's outlines use it to map a small ellipse around the point.
  bool projectFromCamera(const Eigen::Vector3d& c, Eigen::Vector2d& pixel,
                         Eigen::Matrix<double, 2, 3>& jacobian) const {
    if (c.z() <= kMinimumDepthM) return false;
    // One division, not four: on the per-particle path their latency was the outlines' largest
    // stall (perf, bench_tracker).
    const double inverse_z = 1.0 / c.z();
    const double x = c.x() * inverse_z, y = c.y() * inverse_z;
    const double r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
    double radial = 1 + k1_ * r2 + k2_ * r4 + k3_ * r6;
    double radial_d_r2 = k1_ + 2 * k2_ * r2 + 3 * k3_ * r4;  // d radial / d r²
    if (rational_) {
      const double denominator = 1 + k4_ * r2 + k5_ * r4 + k6_ * r6;
      const double denominator_d_r2 = k4_ + 2 * k5_ * r2 + 3 * k6_ * r4;
      radial_d_r2 = (radial_d_r2 * denominator - radial * denominator_d_r2) / (denominator * denominator);
      radial /= denominator;
    }
    const double xd = x * radial + 2 * p1_ * x * y + p2_ * (r2 + 2 * x * x);
    const double yd = y * radial + p1_ * (r2 + 2 * y * y) + 2 * p2_ * x * y;
    pixel = Eigen::Vector2d(k_(0, 0) * xd + k_(0, 2), k_(1, 1) * yd + k_(1, 2));
    // d(xd, yd) / d(x, y): symmetric off the diagonal.
    const double xx = radial + 2 * x * x * radial_d_r2 + 2 * p1_ * y + 6 * p2_ * x;
    const double xy = 2 * x * y * radial_d_r2 + 2 * p1_ * x + 2 * p2_ * y;
    const double yy = radial + 2 * y * y * radial_d_r2 + 6 * p1_ * y + 2 * p2_ * x;
    // d(x, y) / dc = [1/z, 0, -x/z; 0, 1/z, -y/z].
    const double fx_z = k_(0, 0) * inverse_z, fy_z = k_(1, 1) * inverse_z;
    jacobian << fx_z * xx, fx_z * xy, -fx_z * (xx * x + xy * y),
                fy_z * xy, fy_z * yy, -fy_z * (xy * x + yy * y);
    return true;
  }
  static constexpr double kMinimumDepthM = 0.01;  // nearer than this along z is behind the camera

  // Depth of a world point along the optical axis (camera z), metres.
  double depth(const Eigen::Vector3d& world_m) const { return rotation_.row(2).dot(world_m) + translation_.z(); }

  // The viewing rays of pixels: world-frame directions (not normalised) from centre(),
  // distortion undone. One call undistorts all pixels at once.
  std::vector<Eigen::Vector3d> rays(const std::vector<Eigen::Vector2d>& pixels) const;

  // The world point on the ground plane Z = ground_height_m seen at a pixel; nullopt when the
  // ray misses the ground (points at or above the horizon).
  std::optional<Eigen::Vector3d> groundPoint(const Eigen::Vector2d& pixel,
                                             double ground_height_m = 0.0) const;

  // The camera centre in the world, metres.
  Eigen::Vector3d centre() const { return -rotation_.transpose() * translation_; }
  const Eigen::Matrix3d& intrinsics() const { return k_; }
  const std::vector<double>& distortion() const { return distortion_; }
  const Eigen::Matrix3d& rotation() const { return rotation_; }
  const Eigen::Vector3d& translation() const { return translation_; }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  Eigen::Matrix3d k_;
  std::vector<double> distortion_;
  double k1_ = 0, k2_ = 0, p1_ = 0, p2_ = 0, k3_ = 0, k4_ = 0, k5_ = 0, k6_ = 0;
  bool rational_ = false;  // k4..k6 given: the radial factor has a denominator
  Eigen::Matrix3d rotation_;
  Eigen::Vector3d translation_;
  int width_, height_;
};

}  // namespace kneed_walker::core::vision
