#include "kneed_walker/core/synthetic/captured_walk.h"

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

#include "kneed_walker/core/common/random.h"

namespace kneed_walker::core::synthetic {
namespace {

// The words of a BVH file with their line numbers.
class Words {
 public:
  explicit Words(const std::string& path) : path_(path) {
    std::ifstream in(path);
    if (!in) throw std::invalid_argument(path + ": cannot read the BVH file");
    std::string line, word;
    for (int number = 1; std::getline(in, line); ++number) {
      std::istringstream words(line);
      while (words >> word) words_.push_back({word, number});
    }
  }
  bool done() const { return next_ >= words_.size(); }
  const std::string& peek() const { return done() ? empty_ : words_[next_].text; }
  std::string take() {
    if (done()) fail("the file ends early");
    return words_[next_++].text;
  }
  void expect(const std::string& word) {
    const std::string got = take();
    if (got != word) fail("expected " + word + ", found " + got, -1);
  }
  double number() {
    const std::string text = take();
    try {
      size_t used = 0;
      const double value = std::stod(text, &used);
      if (used != text.size() || !std::isfinite(value)) throw std::invalid_argument(text);
      return value;
    } catch (const std::exception&) {
      fail("expected a number, found " + text, -1);
    }
    return 0;
  }
  [[noreturn]] void fail(const std::string& what, int back = 0) const {
    const size_t at = std::min(words_.empty() ? 0 : words_.size() - 1, next_ + back);
    throw std::invalid_argument(path_ + ":" + std::to_string(words_.empty() ? 0 : words_[at].line) + ": " + what);
  }

 private:
  struct Word {
    std::string text;
    int line;
  };
  std::string path_, empty_;
  std::vector<Word> words_;
  size_t next_ = 0;
};

enum class Channel { kXPosition, kYPosition, kZPosition, kXRotation, kYRotation, kZRotation };

struct BvhJoint {
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  std::vector<Channel> channels;
};

Channel channelNamed(Words& words) {
  const std::string name = words.take();
  static const std::pair<const char*, Channel> kNames[] = {
      {"Xposition", Channel::kXPosition}, {"Yposition", Channel::kYPosition}, {"Zposition", Channel::kZPosition},
      {"Xrotation", Channel::kXRotation}, {"Yrotation", Channel::kYRotation}, {"Zrotation", Channel::kZRotation}};
  for (const auto& [text, channel] : kNames)
    if (name == text) return channel;
  words.fail("unknown channel " + name, -1);
}

// One joint's block after its name: { OFFSET .. CHANNELS .. children }.
void readJoint(Words& words, const std::string& name, int parent, CapturedMotion& motion, std::vector<BvhJoint>& joints) {
  const int self = static_cast<int>(joints.size());
  motion.joints.push_back(name);
  motion.parents.push_back(parent);
  joints.emplace_back();
  words.expect("{");
  words.expect("OFFSET");
  for (int i = 0; i < 3; ++i) joints[self].offset[i] = words.number();
  words.expect("CHANNELS");
  const double count = words.number();
  if (count < 0 || count > 6 || count != std::floor(count)) words.fail("CHANNELS needs a count from 0 to 6", -1);
  for (int i = 0; i < static_cast<int>(count); ++i) joints[self].channels.push_back(channelNamed(words));
  while (words.peek() != "}") {
    const std::string word = words.take();
    if (word == "JOINT") {
      const std::string child = words.take();
      readJoint(words, child, self, motion, joints);
    } else if (word == "End") {
      words.expect("Site");
      words.expect("{");
      words.expect("OFFSET");
      for (int i = 0; i < 3; ++i) words.number();
      words.expect("}");
    } else {
      words.fail("expected JOINT, End Site or }, found " + word, -1);
    }
  }
  words.expect("}");
}

// BVH (Y up) to the world (Z up), a right-handed turn about X.
Eigen::Vector3d zUp(const Eigen::Vector3d& p) { return Eigen::Vector3d(p.x(), -p.z(), p.y()); }

cv::Scalar shade(const cv::Scalar& colour, double factor) {
  return cv::Scalar(colour[0] * factor, colour[1] * factor, colour[2] * factor);
}

}  // namespace

int CapturedMotion::index(const std::string& name) const {
  const auto it = std::find(joints.begin(), joints.end(), name);
  if (it == joints.end()) throw std::invalid_argument("the captured motion has no joint " + name);
  return static_cast<int>(it - joints.begin());
}

CapturedMotion loadBvh(const std::string& path, double unit_m) {
  Words words(path);
  CapturedMotion motion;
  std::vector<BvhJoint> joints;
  words.expect("HIERARCHY");
  words.expect("ROOT");
  const std::string root = words.take();
  readJoint(words, root, -1, motion, joints);
  words.expect("MOTION");
  words.expect("Frames:");
  const double frames = words.number();
  if (frames < 1 || frames != std::floor(frames)) words.fail("Frames: needs a positive count", -1);
  words.expect("Frame");
  words.expect("Time:");
  motion.frame_time_s = words.number();
  if (!(motion.frame_time_s > 0)) words.fail("Frame Time: must be positive", -1);
  motion.positions_m.resize(static_cast<size_t>(frames));
  std::vector<Eigen::Isometry3d> global(joints.size());
  for (auto& positions : motion.positions_m) {
    positions.resize(joints.size());
    for (size_t j = 0; j < joints.size(); ++j) {
      Eigen::Vector3d translation = joints[j].offset;
      Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
      for (const Channel channel : joints[j].channels) {
        const double value = words.number();
        const double angle = value * M_PI / 180;
        switch (channel) {
          case Channel::kXPosition: translation.x() = value; break;
          case Channel::kYPosition: translation.y() = value; break;
          case Channel::kZPosition: translation.z() = value; break;
          case Channel::kXRotation: rotation = rotation * Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()); break;
          case Channel::kYRotation: rotation = rotation * Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()); break;
          case Channel::kZRotation: rotation = rotation * Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()); break;
        }
      }
      Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
      local.translation() = translation;
      local.linear() = rotation;
      const int parent = motion.parents[j];
      global[j] = parent < 0 ? local : global[parent] * local;
      positions[j] = unit_m * zUp(global[j].translation());
    }
  }
  if (!words.done()) words.fail("more numbers than Frames: and CHANNELS say");
  return motion;
}

std::vector<Eigen::Vector3d> jointsAt(const CapturedMotion& motion, double t_s) {
  const double f = std::clamp(t_s / motion.frame_time_s, 0.0, static_cast<double>(motion.positions_m.size() - 1));
  const size_t i = std::min(static_cast<size_t>(f), motion.positions_m.size() - 1);
  const size_t k = std::min(i + 1, motion.positions_m.size() - 1);
  const double w = f - static_cast<double>(i);
  std::vector<Eigen::Vector3d> joints(motion.joints.size());
  for (size_t j = 0; j < joints.size(); ++j)
    joints[j] = (1 - w) * motion.positions_m[i][j] + w * motion.positions_m[k][j];
  return joints;
}

Eigen::Isometry3d placeCaptured(const CapturedMotion& motion, const CapturedPlacement& placement) {
  const int left = motion.index("UpperLeg_L"), right = motion.index("UpperLeg_R");
  auto waist = [&](const std::vector<Eigen::Vector3d>& p) { return 0.5 * (p[left] + p[right]); };
  const Eigen::Vector3d first = waist(motion.positions_m.front()), last = waist(motion.positions_m.back());
  const Eigen::Vector2d travel = (last - first).head<2>();
  const double turn = placement.heading_rad - (travel.norm() > 1e-6 ? std::atan2(travel.y(), travel.x()) : 0.0);
  double lowest = std::numeric_limits<double>::infinity();
  const CapturedFigure figure;
  for (const char* side : {"_L", "_R"}) {
    const int ankle = motion.index(std::string("Foot") + side), toes = motion.index(std::string("Toes") + side);
    for (const auto& p : motion.positions_m)
      lowest = std::min({lowest, p[toes].z(), capturedHeel(p[ankle], p[toes], figure).z()});
  }
  Eigen::Isometry3d world = Eigen::Isometry3d::Identity();
  world.linear() = Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d turned = world.linear() * first;
  // The lowest toe or heel stands a drawn foot's radius above the ground.
  world.translation() = Eigen::Vector3d(placement.start_m.x() - turned.x(), placement.start_m.y() - turned.y(),
                                        figure.foot_radius_m - lowest);
  return world;
}

body::BodyPose capturedBodyPose(const CapturedMotion& motion, const std::vector<Eigen::Vector3d>& joints,
                                const Eigen::Vector3d& forward) {
  body::BodyPose pose;
  auto at = [&](const char* name) { return joints[motion.index(name)]; };
  pose.joints[body::kLeftHip] = at("UpperLeg_L");
  pose.joints[body::kRightHip] = at("UpperLeg_R");
  pose.joints[body::kWaist] = 0.5 * (pose.joints[body::kLeftHip] + pose.joints[body::kRightHip]);
  pose.joints[body::kNeck] = at("Neck");
  // The capture's Head joint is the top of the neck; the body model's head joint is the head's
  // centre, where the figure draws it.
  pose.joints[body::kHead] = at("Head") + kHeadCentreAboveHeadJoint_m * (at("Head") - at("Neck")).normalized();
  pose.joints[body::kLeftKnee] = at("LowerLeg_L");
  pose.joints[body::kRightKnee] = at("LowerLeg_R");
  pose.joints[body::kLeftAnkle] = at("Foot_L");
  pose.joints[body::kRightAnkle] = at("Foot_R");
  pose.foot_centres = {at("Foot_L"), at("Foot_R")};
  pose.forward = forward.normalized();
  pose.up = Eigen::Vector3d::UnitZ();
  pose.left = pose.up.cross(pose.forward);
  pose.ground_point_m = Eigen::Vector3d::Zero();  // the capture stands on z = 0 (capturedPlacement)
  return pose;
}

Eigen::Vector3d capturedHeel(const Eigen::Vector3d& ankle, const Eigen::Vector3d& toes, const CapturedFigure& figure) {
  const Eigen::Vector3d along = (toes - ankle).normalized();
  Eigen::Vector3d down = -Eigen::Vector3d::UnitZ() + along.z() * along;  // −Z made square to the foot
  if (down.norm() < 1e-9) down = -along.cross(Eigen::Vector3d::UnitX());   // a vertical foot: any square direction
  return ankle + figure.heel_below_ankle_m * down.normalized();
}

CapturedFigure capturedFigure(std::uint64_t seed) {
  common::Random random(common::splitMix64(seed));
  auto uniform = [&](double low, double high) { return std::uniform_real_distribution<double>(low, high)(random); };
  CapturedFigure figure;
  figure.breadth_scale = uniform(0.8, 1.5);
  auto colour = [&](double low, double high) { return cv::Scalar(uniform(low, high), uniform(low, high), uniform(low, high)); };
  const double tone = uniform(0.45, 1.0);  // skin from dark to light
  figure.skin = cv::Scalar(110 * tone + 20, 140 * tone + 20, 190 * tone + 30);
  figure.top = colour(20, 230);
  figure.bottom = colour(20, 180);
  figure.shoes = colour(10, 90);
  return figure;
}

void drawCapturedPerson(cv::Mat& image, const vision::Camera& camera, const CapturedMotion& motion,
                        const std::vector<Eigen::Vector3d>& joints, const CapturedFigure& figure) {
  struct Segment {
    Eigen::Vector3d from, to;
    double from_radius_m, to_radius_m;
    cv::Scalar colour;
    double depth_m = 0;
  };
  auto at = [&](const char* name) { return joints[motion.index(name)]; };
  const double b = figure.breadth_scale;
  const Eigen::Vector3d hips = 0.5 * (at("UpperLeg_L") + at("UpperLeg_R"));
  const Eigen::Vector3d shoulders = 0.5 * (at("UpperArm_L") + at("UpperArm_R"));
  const Eigen::Vector3d head_up = (at("Head") - at("Neck")).normalized();
  std::vector<Segment> segments = {
      {hips, shoulders, 0.9 * figure.torso_half_width_m * b, figure.torso_half_width_m * b, figure.top},
      {shoulders, at("Head"), 0.05 * b, 0.05 * b, figure.skin},
      {at("Head") + 0.08 * head_up, at("Head") + kHeadCentreAboveHeadJoint_m * 4 / 3 * head_up, figure.head_radius_m,
       0.9 * figure.head_radius_m, figure.skin}};
  for (const char* side : {"_L", "_R"}) {
    auto joint = [&](const char* name) { return at((std::string(name) + side).c_str()); };
    segments.push_back({joint("UpperLeg"), joint("LowerLeg"), figure.thigh_radius_m * b, 0.75 * figure.thigh_radius_m * b,
                        figure.bottom});
    segments.push_back({joint("LowerLeg"), joint("Foot"), figure.shank_radius_m * b, 0.8 * figure.shank_radius_m * b,
                        figure.bottom});
    const Eigen::Vector3d heel = capturedHeel(joint("Foot"), joint("Toes"), figure);
    segments.push_back({joint("Foot"), heel, figure.foot_radius_m, figure.foot_radius_m, figure.shoes});
    segments.push_back({heel, joint("Toes"), figure.foot_radius_m, 0.8 * figure.foot_radius_m, figure.shoes});
    segments.push_back({joint("UpperArm"), joint("LowerArm"), figure.upper_arm_radius_m * b,
                        0.85 * figure.upper_arm_radius_m * b, figure.top});
    segments.push_back({joint("LowerArm"), joint("Hand"), figure.forearm_radius_m * b, 0.8 * figure.forearm_radius_m * b,
                        figure.skin});
  }
  const double body_depth = camera.toCamera(hips).z();
  for (Segment& s : segments) s.depth_m = 0.5 * (camera.toCamera(s.from).z() + camera.toCamera(s.to).z());
  std::sort(segments.begin(), segments.end(), [](const Segment& a, const Segment& b) { return a.depth_m > b.depth_m; });
  const double focal_px = camera.intrinsics()(0, 0);
  constexpr int kShift = 4;
  for (const Segment& s : segments) {
    const Eigen::Vector3d a = camera.toCamera(s.from), c = camera.toCamera(s.to);
    const auto pa = camera.project(s.from), pc = camera.project(s.to);
    if (a.z() < 0.1 || c.z() < 0.1 || !pa || !pc) continue;
    const double ra = s.from_radius_m * focal_px / a.z(), rc = s.to_radius_m * focal_px / c.z();
    // Limbs on the far side of the body a little darker, as drawPerson shades them.
    const cv::Scalar colour = shade(s.colour, s.depth_m > body_depth + 0.05 ? 0.8 : 1.0);
    Eigen::Vector2d axis = *pc - *pa;
    const double length = axis.norm();
    const Eigen::Vector2d normal = length > 1e-9 ? Eigen::Vector2d(-axis.y(), axis.x()) / length : Eigen::Vector2d(1, 0);
    auto point = [&](const Eigen::Vector2d& p) {
      return cv::Point(static_cast<int>(std::lround(p.x() * (1 << kShift))), static_cast<int>(std::lround(p.y() * (1 << kShift))));
    };
    const cv::Point quad[4] = {point(*pa + ra * normal), point(*pc + rc * normal), point(*pc - rc * normal),
                               point(*pa - ra * normal)};
    cv::fillConvexPoly(image, quad, 4, colour, cv::LINE_AA, kShift);
    cv::circle(image, point(*pa), static_cast<int>(std::lround(ra * (1 << kShift))), colour, cv::FILLED, cv::LINE_AA, kShift);
    cv::circle(image, point(*pc), static_cast<int>(std::lround(rc * (1 << kShift))), colour, cv::FILLED, cv::LINE_AA, kShift);
  }
}

}  // namespace kneed_walker::core::synthetic
