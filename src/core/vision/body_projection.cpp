#include "kneed_walker/core/vision/body_projection.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace kneed_walker::core::vision {
namespace {

// Andrew's monotone chain on a fixed-size point set; writes the hull counter-clockwise (in
// image coordinates, y down) into `hull` and returns its size. No allocation.
template <size_t N>
int convexHull(std::array<Eigen::Vector2d, N> points, Eigen::Vector2d* hull) {
  std::sort(points.begin(), points.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::array<Eigen::Vector2d, 2 * N> chain;
  int k = 0;
  for (size_t i = 0; i < N; ++i) {  // lower hull
    while (k >= 2 && cross(chain[k - 2], chain[k - 1], points[i]) <= 0) --k;
    chain[k++] = points[i];
  }
  for (int i = static_cast<int>(N) - 2, lower = k + 1; i >= 0; --i) {  // upper hull
    while (k >= lower && cross(chain[k - 2], chain[k - 1], points[i]) <= 0) --k;
    chain[k++] = points[i];
  }
  const int size = std::min<int>(k - 1, N);  // the last point repeats the first
  std::copy(chain.begin(), chain.begin() + size, hull);
  return size;
}

// A part's width and depth axes (PartFrame) turned into the camera frame.
struct CameraAxes {
  Eigen::Vector3d across, depth;
};
CameraAxes cameraAxes(const Camera& camera, const body::BodyPose& pose, const PartAxes& axes, int part) {
  const PartFrame frame = partFrame(pose, axes, part);
  return {camera.toCameraDirection(frame.across), camera.toCameraDirection(frame.depth)};
}

}  // namespace

PartAxes partAxes(const body::BodyPose& pose, const body::BodyShape& shape) {
  PartAxes axes;
  const auto& j = pose.joints;
  axes.proximal[body::kTorsoPart] = j[body::kWaist];
  axes.distal[body::kTorsoPart] = j[body::kNeck];
  const Eigen::Vector3d head_axis = (j[body::kHead] - j[body::kNeck]).normalized();
  const double head_half = 0.6 * shape.parts[body::kHeadPart].proximal_depth_m;
  axes.proximal[body::kHeadPart] = j[body::kHead] - head_half * head_axis;
  axes.distal[body::kHeadPart] = j[body::kHead] + head_half * head_axis;
  for (int side = 0; side < 2; ++side) {
    const Eigen::Vector3d& hip = j[body::kLeftHip + side];
    const Eigen::Vector3d& knee = j[body::kLeftKnee + side];
    const Eigen::Vector3d& ankle = j[body::kLeftAnkle + side];
    axes.proximal[body::kLeftThighPart + side] = hip;
    axes.distal[body::kLeftThighPart + side] = knee;
    axes.proximal[body::kLeftShankPart + side] = knee;
    axes.distal[body::kLeftShankPart + side] = ankle;
    // The foot is rigid with the shank: along the walking direction made square to the shank,
    // half way between the ankle and the sole, a quarter of its length behind the ankle.
    const Eigen::Vector3d down = (ankle - knee).normalized();
    const Eigen::Vector3d ahead = (pose.forward - pose.forward.dot(down) * down).normalized();
    const Eigen::Vector3d middle = ankle + 0.5 * shape.ankle_height_m * down;
    axes.proximal[body::kLeftFootPart + side] = middle - 0.25 * shape.foot_length_m * ahead;
    axes.distal[body::kLeftFootPart + side] = middle + 0.75 * shape.foot_length_m * ahead;
  }
  return axes;
}

void standFeetOnGround(const body::BodyPose& pose, const body::BodyShape& shape, PartAxes& axes) {
  for (const int foot : {body::kLeftFootPart, body::kRightFootPart}) {
    const PartFrame frame = partFrame(pose, axes, foot);
    const body::PartShape& part = shape.parts[foot];
    // A tapered cylinder reaches lowest at one of its end ellipses.
    auto below_ground_m = [&](const Eigen::Vector3d& centre, double width_m, double depth_m) {
      const double reach_down_m = 0.5 * std::hypot(width_m * frame.across.dot(pose.up), depth_m * frame.depth.dot(pose.up));
      return reach_down_m - (centre - pose.ground_point_m).dot(pose.up);
    };
    const double lift_m = std::max({0.0, below_ground_m(axes.proximal[foot], part.proximal_width_m, part.proximal_depth_m),
                                    below_ground_m(axes.distal[foot], part.distal_width_m, part.distal_depth_m)});
    axes.proximal[foot] += lift_m * pose.up;
    axes.distal[foot] += lift_m * pose.up;
  }
}

void projectBodyParts(const Camera& camera, const body::BodyPose& pose, const body::BodyShape& shape,
                      BodyOutlines& outlines) {
  constexpr int K = kOutlineVertices;
  const PartAxes axes = partAxes(pose, shape);
  // The image directions whose support points make an outline, computed once.
  using Row = Eigen::Array<float, K, 1>;
  static const Row direction_x = Eigen::Array<double, K, 1>::LinSpaced(K, 0, 2 * M_PI * (K - 1) / K).cos().cast<float>();
  static const Row direction_y = Eigen::Array<double, K, 1>::LinSpaced(K, 0, 2 * M_PI * (K - 1) / K).sin().cast<float>();
  for (int p = 0; p < body::kNumBodyParts; ++p) {
    PartOutline& outline = outlines[p];
    const body::PartShape& part = shape.parts[p];
    const auto [across, depth] = cameraAxes(camera, pose, axes, p);
    // Each end ellipse's image: the centre's pixel plus S (cos θ, sin θ), S = the camera's
    // derivative at the centre times the ellipse's two semi-axes in the camera frame. Its
    // support point in a unit direction n is c + Q n / √(nᵀ Q n) with Q = S Sᵀ, at the
    // distance n·c + √(nᵀ Q n) along n.
    std::array<Row, 2> reach, support_x, support_y;
    outline.visible = true;
    for (int end = 0; end < 2; ++end) {
      const Eigen::Vector3d centre = camera.toCamera(end == 0 ? axes.proximal[p] : axes.distal[p]);
      Eigen::Matrix<double, 3, 2> semi_axes;
      semi_axes.col(0) = 0.5 * (end == 0 ? part.proximal_width_m : part.distal_width_m) * across;
      semi_axes.col(1) = 0.5 * (end == 0 ? part.proximal_depth_m : part.distal_depth_m) * depth;
      Eigen::Matrix<double, 2, 3> jacobian;
      const double nearest_z = centre.z() - std::sqrt(semi_axes(2, 0) * semi_axes(2, 0) + semi_axes(2, 1) * semi_axes(2, 1));
      if (nearest_z <= Camera::kMinimumDepthM || !camera.projectFromCamera(centre, outline.ends_px[end], jacobian)) {
        outline.visible = false;
        break;
      }
      const Eigen::Matrix2d s = jacobian * semi_axes;
      const Eigen::Matrix2d q = s * s.transpose();
      // Widened by 0.001 px, so that an ellipse seen edge-on (a segment) has a support point in
      // every direction.
      const float q00 = q(0, 0) + 1e-6, q01 = q(0, 1), q11 = q(1, 1) + 1e-6;
      const float cx = outline.ends_px[end].x(), cy = outline.ends_px[end].y();
      // Eigen's packet arithmetic: all directions at once, square roots included.
      const Row qx = q00 * direction_x + q01 * direction_y, qy = q01 * direction_x + q11 * direction_y;
      const Row spread = (direction_x * qx + direction_y * qy).sqrt();
      const Row inverse = spread.inverse();
      reach[end] = direction_x * cx + direction_y * cy + spread;
      support_x[end] = cx + qx * inverse;
      support_y[end] = cy + qy * inverse;
    }
    outline.size = 0;
    if (!outline.visible) continue;
    // The hull's support point in each direction is the farther ellipse's (chosen in all
    // directions at once); consecutive directions can share one.
    const auto distal_farther = reach[1] > reach[0];
    const Row hull_x = distal_farther.select(support_x[1], support_x[0]);
    const Row hull_y = distal_farther.select(support_y[1], support_y[0]);
    outline.hull[0] = Eigen::Vector2d(hull_x(0), hull_y(0));
    outline.size = 1;
    for (int k = 1; k < K; ++k) {
      const Eigen::Vector2d& last = outline.hull[outline.size - 1];
      if (hull_x(k) != last.x() || hull_y(k) != last.y()) outline.hull[outline.size++] = Eigen::Vector2d(hull_x(k), hull_y(k));
    }
    if (outline.size > 1 && outline.hull[outline.size - 1] == outline.hull[0]) --outline.size;
    outline.depth_m = camera.depth(0.5 * (axes.proximal[p] + axes.distal[p]));
  }
}

void projectBodyPartsExactly(const Camera& camera, const body::BodyPose& pose, const body::BodyShape& shape,
                             const PartAxes& axes, BodyOutlines& outlines) {
  // The sample directions around an ellipse, computed once.
  static const auto directions = [] {
    std::array<std::array<double, kOutlineSamples>, 2> cs;
    for (int i = 0; i < kOutlineSamples; ++i) {
      cs[0][i] = std::cos(2 * M_PI * i / kOutlineSamples);
      cs[1][i] = std::sin(2 * M_PI * i / kOutlineSamples);
    }
    return cs;
  }();
  const std::array<double, kOutlineSamples>& cosines = directions[0];
  const std::array<double, kOutlineSamples>& sines = directions[1];
  for (int p = 0; p < body::kNumBodyParts; ++p) {
    PartOutline& outline = outlines[p];
    const body::PartShape& part = shape.parts[p];
    // The ellipses' axes in the camera frame: a sample is then 6 multiply-adds from its pixel.
    const auto [across, depth] = cameraAxes(camera, pose, axes, p);
    std::array<Eigen::Vector2d, 2 * kOutlineSamples> points;
    outline.visible = true;
    for (int end = 0; end < 2 && outline.visible; ++end) {
      const Eigen::Vector3d centre = camera.toCamera(end == 0 ? axes.proximal[p] : axes.distal[p]);
      const double half_width = 0.5 * (end == 0 ? part.proximal_width_m : part.distal_width_m);
      const double half_depth = 0.5 * (end == 0 ? part.proximal_depth_m : part.distal_depth_m);
      for (int i = 0; i < kOutlineSamples; ++i) {
        const auto pixel = camera.projectFromCamera(centre + half_width * cosines[i] * across +
                                                    half_depth * sines[i] * depth);
        if (!pixel) {
          outline.visible = false;
          break;
        }
        points[end * kOutlineSamples + i] = *pixel;
      }
    }
    outline.size = outline.visible ? convexHull(points, outline.hull.data()) : 0;
    if (outline.visible) {
      for (int end = 0; end < 2; ++end) {
        Eigen::Vector2d sum = Eigen::Vector2d::Zero();
        for (int i = 0; i < kOutlineSamples; ++i) sum += points[end * kOutlineSamples + i];
        outline.ends_px[end] = sum / kOutlineSamples;
      }
      outline.depth_m = camera.depth(0.5 * (axes.proximal[p] + axes.distal[p]));
    }
  }
}

}  // namespace kneed_walker::core::vision
