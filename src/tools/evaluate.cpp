// evaluate: accuracy of a tracked sequence against ground truth, both as CSV
// `frame,stamp,joint,x,y,z` (world frame, metres; make_synthetic's ground truth and
// track_offline's estimate). Prints, over the frames and REP 155 joints present in both:
//   mean_joint_error_mm=     mean Euclidean joint error, world frame (MPJPE, global)
//   root_relative_error_mm=  the same with each pose's mid-hip (waist) subtracted
//   lost_frames=             frames whose mean joint error exceeds --lost-mm (150)
//   footskate_mm=            mean horizontal slide of the estimated stance foot (the lower ankle,
//                            on the ground: within --contact-mm of its lowest height) between
//                            adjacent frames while it stays the stance foot. The walker's feet
//                            roll, so its stance ankle moves even without slip: the truth's own
//                            figure (truth_footskate_mm=) is the reference
//   ground_penetration_mm=   mean depth of the estimated soles (ankle less --ankle-height) below
//                            the ground (truth_ground_penetration_mm= the truth's)
// and the mean error per joint (`error_mm_<joint>=`). Exits 1 when no frame is in both files.
//
//   rosrun kneed_walker evaluate TRUTH.csv ESTIMATE.csv [--ground CAMERA.yml] [--lost-mm 150]
#include <CLI/CLI.hpp>
#include <Eigen/Core>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "kneed_walker/core/body/body_model.h"
#include "kneed_walker/core/vision/ground_plane.h"
#include "options.h"

namespace kw = kneed_walker::core;
using kneed_walker::tools::FiniteRange;

namespace {

using Pose = std::map<std::string, Eigen::Vector3d>;

std::map<int, Pose> readPoses(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::string line;
  if (!std::getline(in, line) || line.rfind("frame,stamp,joint,x,y,z", 0) != 0)
    throw std::runtime_error(path + ": not a pose CSV (header frame,stamp,joint,x,y,z)");
  std::map<int, Pose> poses;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    std::istringstream fields(line);
    std::string frame, stamp, joint, x, y, z;
    if (!std::getline(fields, frame, ',') || !std::getline(fields, stamp, ',') || !std::getline(fields, joint, ',') ||
        !std::getline(fields, x, ',') || !std::getline(fields, y, ',') || !std::getline(fields, z, ','))
      throw std::runtime_error(path + ":" + std::to_string(number) + ": expected frame,stamp,joint,x,y,z");
    try {
      const Eigen::Vector3d p(std::stod(x), std::stod(y), std::stod(z));
      if (!p.allFinite()) throw std::invalid_argument("not finite");
      poses[std::stoi(frame)][joint] = p;
    } catch (const std::exception&) {
      throw std::runtime_error(path + ":" + std::to_string(number) + ": not numbers: " + line);
    }
  }
  return poses;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Joint errors, lost frames, foot skate and ground penetration of a track against ground truth."};
  std::string truth_path, estimate_path, ground_path;
  double lost_mm = 150, contact_mm = 20, ankle_height_m = 0.068;
  app.add_option("truth", truth_path, "ground truth CSV")->required()->check(CLI::ExistingFile);
  app.add_option("estimate", estimate_path, "estimate CSV")->required()->check(CLI::ExistingFile);
  app.add_option("--ground", ground_path, "calibration file with the ground plane (default: level Z = 0)")
      ->check(CLI::ExistingFile);
  app.add_option("--lost-mm", lost_mm, "a frame whose mean joint error exceeds this is lost")->capture_default_str()
      ->check(FiniteRange(1e-3, 1e6));
  app.add_option("--contact-mm", contact_mm, "an ankle within this of its lowest height is on the ground")
      ->capture_default_str()->check(FiniteRange(1e-3, 1e3));
  app.add_option("--ankle-height", ankle_height_m, "ankle above the sole, m (0.039 x height)")->capture_default_str()
      ->check(FiniteRange(0.0, 0.3));
  CLI11_PARSE(app, argc, argv);
  try {
    const auto truth = readPoses(truth_path), estimate = readPoses(estimate_path);
    const kw::vision::GroundPlane ground = ground_path.empty() ? kw::vision::GroundPlane{} : kw::vision::loadGroundPlane(ground_path);
    std::map<std::string, std::pair<double, int>> per_joint;
    double sum = 0, root_sum = 0;
    int count = 0, frames = 0, lost = 0;
    for (const auto& [frame, t] : truth) {
      const auto e = estimate.find(frame);
      if (e == estimate.end()) continue;
      const bool roots = t.count("waist") && e->second.count("waist");
      double frame_sum = 0;
      int frame_count = 0;
      for (const auto& [joint, p] : t) {
        const auto q = e->second.find(joint);
        if (q == e->second.end()) continue;
        const double error = (q->second - p).norm();
        frame_sum += error;
        ++frame_count;
        per_joint[joint].first += error;
        ++per_joint[joint].second;
        if (roots) root_sum += ((q->second - e->second.at("waist")) - (p - t.at("waist"))).norm();
      }
      if (frame_count == 0) continue;
      sum += frame_sum;
      count += frame_count;
      ++frames;
      lost += 1000 * frame_sum / frame_count > lost_mm;
    }
    if (frames == 0) throw std::runtime_error("no frame with common joints in both files");
    // Foot skate and penetration, of the estimate and (for reference) of the truth.
    struct Contact {
      double skate_mm = 0, penetration_mm = 0;
    };
    auto contact = [&](const std::map<int, Pose>& poses) {
      double skate = 0, penetration = 0;
      int skate_count = 0, penetration_count = 0;
      const Pose* previous = nullptr;
      std::string previous_foot;
      for (const auto& [frame, pose] : poses) {
        if (!pose.count("l_ankle") || !pose.count("r_ankle")) {
          previous = nullptr;
          continue;
        }
        auto above = [&](const Eigen::Vector3d& p) { return p.z() - ground.height(p.head<2>()); };
        const Eigen::Vector3d &l = pose.at("l_ankle"), &r = pose.at("r_ankle");
        const std::string foot = above(l) <= above(r) ? "l_ankle" : "r_ankle";
        const double lowest = std::min(above(l), above(r));
        penetration += std::max(0.0, -(lowest - ankle_height_m));
        ++penetration_count;
        const bool on_ground = lowest - ankle_height_m < contact_mm / 1000;
        if (previous && on_ground && foot == previous_foot)
          skate += (pose.at(foot) - previous->at(foot)).head<2>().norm(), ++skate_count;
        previous = on_ground ? &pose : nullptr;
        previous_foot = foot;
      }
      return Contact{skate_count ? 1000 * skate / skate_count : 0.0,
                     penetration_count ? 1000 * penetration / penetration_count : 0.0};
    };
    const Contact estimated = contact(estimate), true_contact = contact(truth);
    std::printf("frames=%d joints=%d\n", frames, count / frames);
    std::printf("mean_joint_error_mm=%.1f\n", 1000 * sum / count);
    std::printf("root_relative_error_mm=%.1f\n", 1000 * root_sum / count);
    std::printf("lost_frames=%d\n", lost);
    std::printf("footskate_mm=%.2f\n", estimated.skate_mm);
    std::printf("ground_penetration_mm=%.2f\n", estimated.penetration_mm);
    std::printf("truth_footskate_mm=%.2f\n", true_contact.skate_mm);
    std::printf("truth_ground_penetration_mm=%.2f\n", true_contact.penetration_mm);
    for (const auto& [joint, e] : per_joint) std::printf("error_mm_%s=%.1f\n", joint.c_str(), 1000 * e.first / e.second);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "evaluate: %s\n", e.what());
    return 1;
  }
  return 0;
}
