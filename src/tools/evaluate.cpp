// evaluate: accuracy of a tracked sequence against ground truth, both as CSV
// `frame,stamp,joint,x,y,z[,body[,track]]` (world frame, metres; make_synthetic's ground truth and
// track_offline's estimate, whose body column is the REP 155 body id: one body is evaluated,
// --body when the file has several; its track column numbers the body's tracks, and adjacent
// frames of two tracks, a restart's jump, are not joined). Prints, over the frames and REP 155
// joints present in both:
//   mean_joint_error_mm=     mean Euclidean joint error, world frame (MPJPE, global)
//   root_relative_error_mm=  the same with each pose's mid-hip (waist) subtracted
//   estimated_frames=N/M     the truth's frames that the estimate has (the figures are over them)
//   lost_frames=             frames whose mean joint error exceeds --lost-mm (150), and the
//                            truth's frames the estimate does not have
//   legs_swapped_percent=    frames whose estimate, its left and right joints exchanged, is
//                            nearer the truth (root-relative): the legs the wrong way round; and
//                            root_relative_swap_free_mm= the root-relative error with each such
//                            frame's swap undone
//   knee_angle_error_deg=    mean error of each knee's flexion, hip_angle_error_deg= of each
//                            thigh's angle to the torso in the sagittal plane, torso_lean_error_deg=
//                            of the torso's forward lean (each frame's swap undone): which part of
//                            the pose is wrong
//   heading_error_1s_deg=    the walking direction's error 1 s after the estimate's first frame
//                            (each the waist's over ±0.5 s; over 90°: started mirrored)
//   depth_bias_mm=           with --ground (the calibration: the camera's position), the mean
//                            signed error of the waist's distance to the camera (positive: the
//                            body placed too far), and lateral_error_mm= the mean error of the
//                            waist across the camera's horizontal line of sight to it: depth and
//                            sideways errors told apart (from a low camera depth is the weak one);
//                            range_error_mm= the median |error| of the waist's ground point's
//                            distance from the camera's (and _p95_mm=, and as a share of the
//                            distance, range_error_percent=), as the ground track's below
//   footskate_mm=            mean slip of the estimated stance foot along the ground between
//                            adjacent frames: the walker's rolling foot, recovered from knee and
//                            ankle (body::rollingFoot; sized by the estimate's own thighs, the
//                            truth's by --height), moves by −R·Δφ as it rolls; what it moves
//                            beyond that is slip. The stance foot of a pair of frames is the foot
//                            on the ground in both (its sole within --contact-mm) that slips least
//                            (near a heel strike both feet are near the ground and the lower one
//                            may be the one landing). truth_footskate_mm= is the truth's own (0
//                            up to the recovery's approximation, body_model.h)
//   ground_penetration_mm=   mean depth of the estimated lower sole below the ground
//                            (truth_ground_penetration_mm= the truth's)
//   torso_lean_deg=          mean forward lean of the torso (waist to neck) from the vertical
//                            (truth_torso_lean_deg= the truth's)
//   knee_at_contact_deg=     mean flexion of a leg's knee at the first frame its foot is on the
//                            ground again (truth_knee_at_contact_deg= the truth's): with the lean,
//                            the paper's Fig. 5 findings (more of both walking uphill)
// and the mean error per joint (`error_mm_<joint>=`). With --ground-track (track_offline
// --out-ground-track) and --ground, the person's ground track against the truth's waist:
//   ground_range_error_mm=   median |error| of the distance from the camera (and _p95_mm=; as a
//                            share of the distance, ground_range_error_percent=; the median signed
//                            error, ground_range_bias_mm=: positive too far)
//   ground_lateral_error_mm= median error across the line of sight
//   ground_heading_error_1s_deg=, _3s_deg=  the walking direction's error 1 s and 3 s after the
//                            track's first frame (the truth's over ±0.5 s)
//   ground_stature_error_mm= median error of the stature against --height
// Exits 1 when no frame is in both files.
//
//   rosrun kneed_walker evaluate TRUTH.csv ESTIMATE.csv [--body ID] [--ground CAMERA.yml [--camera-unit 0.001]]
//          [--ground-track GROUND_TRACK.csv]
//          [--lost-mm 150] [--height 1.75] [--walker-model config/walker_model.yaml]
#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "kneed_walker/core/body/body_model.h"
#include "kneed_walker/core/vision/camera.h"
#include "kneed_walker/core/vision/ground_plane.h"
#include "median.h"
#include "options.h"
#include "package_files.h"
#include "camera_file.h"

namespace kw = kneed_walker::core;
using kneed_walker::tools::FiniteRange;

namespace {

using Pose = std::map<std::string, Eigen::Vector3d>;

// The height of the body model whose thighs (hip to knee) the poses have: the median over frames
// and legs of the thigh's length over its share of the height. nullopt without a thigh.
std::optional<double> heightFromThighs(const std::map<int, Pose>& poses, const kw::dynamics::BodyProportions& p) {
  std::vector<double> heights;
  for (const auto& [frame, pose] : poses)
    for (const auto& [hip, knee] : {std::pair{"l_hip", "l_knee"}, std::pair{"r_hip", "r_knee"}})
      if (pose.count(hip) && pose.count(knee))
        heights.push_back((pose.at(hip) - pose.at(knee)).norm() / (p.thigh.length * p.leg_length_per_height));
  if (heights.empty()) return std::nullopt;
  std::nth_element(heights.begin(), heights.begin() + heights.size() / 2, heights.end());
  const double height_m = heights[heights.size() / 2];
  return std::isfinite(height_m) && height_m > 0 ? std::optional<double>(height_m) : std::nullopt;
}

// The sum over the joints both poses have of the error with each pose's waist subtracted
// (both must have a waist), m.
double rootRelativeSum(const Pose& truth, const Pose& estimated) {
  double total = 0;
  for (const auto& [joint, p] : truth) {
    const auto q = estimated.find(joint);
    if (q != estimated.end()) total += ((q->second - estimated.at("waist")) - (p - truth.at("waist"))).norm();
  }
  return total;
}

// The pose with its left and right joints exchanged (l_* <-> r_*).
Pose mirroredLegs(const Pose& pose) {
  Pose mirrored;
  for (const auto& [joint, p] : pose) {
    std::string name = joint;
    if (name.rfind("l_", 0) == 0) name[0] = 'r';
    else if (name.rfind("r_", 0) == 0) name[0] = 'l';
    mirrored[name] = p;
  }
  return mirrored;
}

// A pose's sagittal angles: each knee's flexion (left, right), each hip's (the thigh against the
// torso's axis, in the plane of the walking direction and the vertical; forward positive), and the
// torso's forward lean. The walking direction is the hips' left-to-right axis crossed with up.
struct SagittalAngles {
  std::array<double, 2> knee_rad{}, hip_rad{};
  double lean_rad = 0;
};
std::optional<SagittalAngles> sagittalAngles(const Pose& pose, const Eigen::Vector3d& up) {
  for (const char* joint : {"waist", "neck", "l_hip", "r_hip", "l_knee", "r_knee", "l_ankle", "r_ankle"})
    if (!pose.count(joint)) return std::nullopt;
  const Eigen::Vector3d forward = (pose.at("l_hip") - pose.at("r_hip")).cross(up).normalized();
  const Eigen::Vector3d torso_down = (pose.at("waist") - pose.at("neck")).normalized();
  SagittalAngles angles;
  angles.lean_rad = kw::body::torsoLeanRad(pose.at("waist"), pose.at("neck"), forward);
  // The torso's frame in the sagittal plane: its downward axis, and forward square to it.
  const Eigen::Vector3d ahead = (forward - forward.dot(torso_down) * torso_down).normalized();
  static const char* const kLeg[2][3] = {{"l_hip", "l_knee", "l_ankle"}, {"r_hip", "r_knee", "r_ankle"}};
  for (int side : {0, 1}) {
    const Eigen::Vector3d& hip = pose.at(kLeg[side][0]);
    const Eigen::Vector3d& knee = pose.at(kLeg[side][1]);
    angles.knee_rad[side] = kw::body::kneeFlexionRad(hip, knee, pose.at(kLeg[side][2]));
    const Eigen::Vector3d thigh = knee - hip;
    angles.hip_rad[side] = std::atan2(thigh.dot(ahead), thigh.dot(torso_down));
  }
  return angles;
}

// The poses of one body: `body` (empty: the file's only one); each frame's stamp into `stamps`,
// and with a track column (track_offline's), each frame's track of the body into `tracks`.
std::map<int, Pose> readPoses(const std::string& path, const std::string& body, std::map<int, double>* stamps = nullptr,
                              std::map<int, int>* tracks = nullptr) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::string line;
  if (!std::getline(in, line) || line.rfind("frame,stamp,joint,x,y,z", 0) != 0)
    throw std::runtime_error(path + ": not a pose CSV (header frame,stamp,joint,x,y,z[,body[,track]])");
  const bool has_bodies = line.rfind("frame,stamp,joint,x,y,z,body", 0) == 0;
  const bool has_tracks = line.rfind("frame,stamp,joint,x,y,z,body,track", 0) == 0;
  std::map<std::string, std::map<int, Pose>> bodies;
  std::map<std::string, std::map<int, int>> body_tracks;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    std::istringstream fields(line);
    std::string frame, stamp, joint, x, y, z, id, track;
    if (!std::getline(fields, frame, ',') || !std::getline(fields, stamp, ',') || !std::getline(fields, joint, ',') ||
        !std::getline(fields, x, ',') || !std::getline(fields, y, ',') || !std::getline(fields, z, ',') ||
        (has_bodies && (!std::getline(fields, id, ',') || id.empty())) ||
        (has_tracks && (!std::getline(fields, track, ',') || track.empty())))
      throw std::runtime_error(path + ":" + std::to_string(number) + ": expected frame,stamp,joint,x,y,z" +
                               (has_tracks ? ",body,track" : has_bodies ? ",body" : ""));
    Eigen::Vector3d p;
    int frame_number = 0;
    try {
      p = Eigen::Vector3d(std::stod(x), std::stod(y), std::stod(z));
      frame_number = std::stoi(frame);
      if (stamps) (*stamps)[frame_number] = std::stod(stamp);
      if (has_tracks) body_tracks[id][frame_number] = std::stoi(track);
      if (!p.allFinite()) throw std::invalid_argument("not finite");
    } catch (const std::exception&) {
      throw std::runtime_error(path + ":" + std::to_string(number) + ": not numbers: " + line);
    }
    // A joint given twice for a frame: the same position is a repeat; another is a conflict
    // that no figure could be trusted with.
    const auto [it, added] = bodies[id][frame_number].emplace(joint, p);
    if (!added && it->second != p)
      throw std::runtime_error(path + ":" + std::to_string(number) + ": frame " + frame + " " + joint +
                               (has_bodies ? " of body " + id : "") + " again, at another position");
  }
  std::string ids;
  for (const auto& [id, poses] : bodies) ids += (ids.empty() ? "" : ", ") + id;
  if (!body.empty() && has_bodies) {
    const auto it = bodies.find(body);
    if (it == bodies.end()) throw std::runtime_error("--body " + body + ": " + path + " has bodies " + ids);
    if (tracks) *tracks = body_tracks[body];
    return it->second;
  }
  if (bodies.size() > 1) throw std::runtime_error(path + " has bodies " + ids + ": choose one with --body");
  if (bodies.empty()) return {};
  if (tracks) *tracks = body_tracks[bodies.begin()->first];
  return bodies.begin()->second;
}

struct GroundTrackRow {
  double stamp_s = 0;
  Eigen::Vector2d position_m, velocity_mps;
  double stature_m = 0;
};

// track_offline --out-ground-track's rows of one body (empty: 1), by frame.
std::map<int, GroundTrackRow> readGroundTrack(const std::string& path, const std::string& body) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::string line;
  if (!std::getline(in, line) || line.rfind("frame,stamp,body,x,y,vx,vy,stature", 0) != 0)
    throw std::runtime_error(path + ": not a ground track CSV (header frame,stamp,body,x,y,vx,vy,stature,...)");
  const int wanted = body.empty() ? 1 : std::stoi(body);
  std::map<int, GroundTrackRow> rows;
  for (int number = 2; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    std::istringstream fields(line);
    std::vector<double> values;
    for (std::string field; std::getline(fields, field, ',') && values.size() < 8;) {
      try {
        values.push_back(std::stod(field));
      } catch (const std::exception&) {
        throw std::runtime_error(path + ":" + std::to_string(number) + ": not numbers: " + line);
      }
    }
    if (values.size() < 8 || !std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); }))
      throw std::runtime_error(path + ":" + std::to_string(number) + ": expected 8 finite numbers first: " + line);
    if (static_cast<int>(values[2]) != wanted) continue;
    rows[static_cast<int>(values[0])] = {values[1], {values[3], values[4]}, {values[5], values[6]}, values[7]};
  }
  return rows;
}

// The ground track's figures against the truth's waist (see the header).
void printGroundTrackFigures(const std::map<int, Pose>& truth, const std::map<int, GroundTrackRow>& track,
                             const Eigen::Vector3d& camera_m, double height_m) {
  using kneed_walker::tools::median;
  using kneed_walker::tools::percentile;
  std::vector<double> range_abs, range_signed, range_share, lateral, stature, stamps;
  for (const auto& [frame, row] : track) stamps.push_back(row.stamp_s);
  std::vector<double> intervals;
  for (size_t i = 1; i < stamps.size(); ++i) intervals.push_back(stamps[i] - stamps[i - 1]);
  const double dt = intervals.empty() ? 0 : median(intervals);
  const auto waist = [&](int frame) -> std::optional<Eigen::Vector2d> {
    const auto t = truth.find(frame);
    if (t == truth.end() || !t->second.count("waist")) return std::nullopt;
    return t->second.at("waist").head<2>();
  };
  const Eigen::Vector2d camera = camera_m.head<2>();
  for (const auto& [frame, row] : track) {
    const auto w = waist(frame);
    if (!w) continue;
    const double distance = (*w - camera).norm();
    const double error = (row.position_m - camera).norm() - distance;
    range_abs.push_back(std::abs(error));
    range_signed.push_back(error);
    range_share.push_back(std::abs(error) / distance);
    const Eigen::Vector2d sight = (*w - camera).normalized();
    const Eigen::Vector2d offset = row.position_m - *w;
    lateral.push_back(std::abs(sight.x() * offset.y() - sight.y() * offset.x()));
    stature.push_back(row.stature_m - height_m);
  }
  if (range_abs.empty()) throw std::runtime_error("--ground-track: no frame of the ground track is in the truth");
  std::printf("ground_track_frames=%zu\n", range_abs.size());
  std::printf("ground_range_error_mm=%.1f\nground_range_error_p95_mm=%.1f\nground_range_error_percent=%.2f\n",
              1000 * median(range_abs), 1000 * percentile(range_abs, 95), 100 * median(range_share));
  std::printf("ground_range_bias_mm=%.1f\nground_lateral_error_mm=%.1f\nground_stature_error_mm=%.1f\n",
              1000 * median(range_signed), 1000 * median(lateral), 1000 * median(stature));
  // The walking direction after 1 s and 3 s: the truth's from its waist over ±0.5 s.
  const int half = dt > 0 ? std::max(1, static_cast<int>(std::lround(0.5 / dt))) : 1;
  const double start_s = track.begin()->second.stamp_s;
  for (const double after_s : {1.0, 3.0}) {
    std::optional<double> error_deg;
    for (const auto& [frame, row] : track) {
      if (row.stamp_s < start_s + after_s - 1e-6) continue;
      const auto before = waist(frame - half), after = waist(frame + half);
      if (before && after && row.velocity_mps.norm() > 0) {
        const Eigen::Vector2d walked = *after - *before;
        const double difference = std::atan2(row.velocity_mps.y(), row.velocity_mps.x()) - std::atan2(walked.y(), walked.x());
        error_deg = std::abs(std::remainder(difference, 2 * M_PI)) * 180 / M_PI;
      }
      break;
    }
    if (error_deg)
      std::printf("ground_heading_error_%.0fs_deg=%.1f\n", after_s, *error_deg);
    else
      std::printf("ground_heading_error_%.0fs_deg=n/a (the track or the truth is shorter)\n", after_s);
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Joint errors, lost frames, foot skate and ground penetration of a track against ground truth."};
  std::string truth_path, estimate_path, ground_path, ground_track_path, body;
  double lost_mm = 150, contact_mm = 5, height_m = 1.75, camera_unit_m = 0.001;
  std::string walker_model = kneed_walker::tools::packageFile("config/walker_model.yaml");
  app.add_option("truth", truth_path, "ground truth CSV")->required()->check(CLI::ExistingFile);
  app.add_option("estimate", estimate_path, "estimate CSV")->required()->check(CLI::ExistingFile);
  app.add_option("--body", body, "the estimate's body (its body column) to evaluate; needed when it has several");
  app.add_option("--ground", ground_path, "calibration file with the ground plane (default: level Z = 0)")
      ->check(CLI::ExistingFile);
  app.add_option("--ground-track", ground_track_path,
                 "track_offline --out-ground-track's CSV: its figures against the truth's waist (needs --ground)")
      ->check(CLI::ExistingFile);
  app.add_option("--camera-unit", camera_unit_m, "metres per unit of the calibration's t (with --ground)")
      ->capture_default_str()->check(FiniteRange(1e-6, 1e3));
  app.add_option("--lost-mm", lost_mm, "a frame whose mean joint error exceeds this is lost")->capture_default_str()
      ->check(FiniteRange(1e-3, 1e6));
  app.add_option("--contact-mm", contact_mm, "a sole within this of the ground is on it")
      ->capture_default_str()->check(FiniteRange(1e-3, 1e3));
  app.add_option("--height", height_m, "the person's height, m (sizes the truth's rolling feet; the estimate's are its body's)")->capture_default_str()
      ->check(FiniteRange(1.0, 2.3));
  app.add_option("--walker-model", walker_model, "body proportions (the feet's radius and offset)")
      ->capture_default_str()->check(CLI::ExistingFile);
  CLI11_PARSE(app, argc, argv);
  try {
    std::map<int, double> truth_stamps;
    std::map<int, int> estimate_tracks;  // a frame's track of the body: poses of two tracks are not joined
    const auto truth = readPoses(truth_path, "", &truth_stamps), estimate = readPoses(estimate_path, body, nullptr, &estimate_tracks);
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
      }
      if (frame_count == 0) continue;
      if (roots) root_sum += rootRelativeSum(t, e->second);
      sum += frame_sum;
      count += frame_count;
      ++frames;
      lost += 1000 * frame_sum / frame_count > lost_mm;
    }
    if (frames == 0) throw std::runtime_error("no frame with common joints in both files");
    // Where the pose's error comes from: the legs swapped (a frame is swapped when the estimate
    // with its left and right joints exchanged is nearer the truth, root-relative), and the
    // joint angles with each frame's swap undone.
    const Eigen::Vector3d vertical = ground.normal();
    int compared_frames = 0, swapped_frames = 0, angle_frames = 0, knee_count = 0;
    double swap_free_sum = 0, knee_sum = 0, hip_sum = 0, lean_sum = 0;
    int swap_free_count = 0;
    for (const auto& [frame, t] : truth) {
      const auto e = estimate.find(frame);
      if (e == estimate.end() || !t.count("waist") || !e->second.count("waist")) continue;
      const int joints = static_cast<int>(std::count_if(
          t.begin(), t.end(), [&](const auto& joint) { return e->second.count(joint.first) > 0; }));
      if (joints == 0) continue;
      const Pose swapped = mirroredLegs(e->second);
      const double as_is = rootRelativeSum(t, e->second), exchanged = rootRelativeSum(t, swapped);
      const bool swap = exchanged < as_is;
      ++compared_frames;
      swapped_frames += swap;
      swap_free_sum += swap ? exchanged : as_is;
      swap_free_count += joints;
      const Pose& estimated = swap ? swapped : e->second;
      const auto angles = sagittalAngles(t, vertical), estimated_angles = sagittalAngles(estimated, vertical);
      if (!angles || !estimated_angles) continue;
      ++angle_frames;
      for (int side : {0, 1}) {
        knee_sum += std::abs(estimated_angles->knee_rad[side] - angles->knee_rad[side]);
        hip_sum += std::abs(estimated_angles->hip_rad[side] - angles->hip_rad[side]);
        ++knee_count;
      }
      lean_sum += std::abs(estimated_angles->lean_rad - angles->lean_rad);
    }
    // A truth frame the estimate does not have (a lost track's gap) is lost too.
    const int missing = static_cast<int>(truth.size()) - frames;
    lost += missing;
    // The waist's error along and across the camera's horizontal line of sight to the truth.
    double depth_sum = 0, lateral_sum = 0;
    int sight_frames = 0;
    std::vector<double> range_abs, range_share;  // the waist's ground point's distance from the camera's
    if (!ground_path.empty()) {
      const Eigen::Vector3d camera = kneed_walker::tools::loadCamera("evaluate", ground_path, camera_unit_m).centre();
      for (const auto& [frame, t] : truth) {
        const auto e = estimate.find(frame);
        if (e == estimate.end() || !t.count("waist") || !e->second.count("waist")) continue;
        const Eigen::Vector3d& true_waist = t.at("waist");
        const Eigen::Vector3d& estimated_waist = e->second.at("waist");
        depth_sum += (estimated_waist - camera).norm() - (true_waist - camera).norm();
        const Eigen::Vector2d sight = (true_waist - camera).head<2>().normalized();
        const Eigen::Vector2d error = (estimated_waist - true_waist).head<2>();
        lateral_sum += std::abs(sight.x() * error.y() - sight.y() * error.x());
        ++sight_frames;
        const double true_range = (true_waist - camera).head<2>().norm();
        range_abs.push_back(std::abs((estimated_waist - camera).head<2>().norm() - true_range));
        range_share.push_back(range_abs.back() / true_range);
      }
    }
    // Foot skate and penetration, of the estimate and (for reference) of the truth. The truth's
    // rolling feet are sized by --height; the estimate's by its own body (the tracker's height,
    // which it measures when none is given), read from its thighs.
    const kw::dynamics::BodyProportions proportions = kw::dynamics::loadBodyProportions(walker_model);
    const kw::body::FootGeometry true_foot = kw::body::FootGeometry::of(proportions, height_m);
    const kw::body::FootGeometry estimated_foot =
        kw::body::FootGeometry::of(proportions, heightFromThighs(estimate, proportions).value_or(height_m));
    const Eigen::Vector3d up = ground.normal();
    // Each figure is empty when nothing could be measured (printed as n/a, never as 0).
    struct Contact {
      std::optional<double> skate_mm, penetration_mm, lean_deg, knee_at_contact_deg;
      int landings = 0;
    };
    auto contact = [&](const std::map<int, Pose>& poses, const kw::body::FootGeometry& foot,
                       const std::map<int, int>& tracks) {
      const auto same_track = [&](int a, int b) {
        const auto i = tracks.find(a), j = tracks.find(b);
        return i == tracks.end() || j == tracks.end() || i->second == j->second;
      };
      double skate = 0, penetration = 0, lean = 0, knee_at_contact = 0;
      int skate_count = 0, penetration_count = 0, lean_count = 0, landings = 0;
      struct Feet {
        std::array<kw::body::RollingFoot, 2> feet;  // left, right
        std::array<bool, 2> on_ground{};
        Eigen::Vector3d forward;
        int frame = -2;  // -2: none yet
      } previous;
      static const char* const kJoints[2][3] = {{"l_knee", "l_ankle", "l_hip"}, {"r_knee", "r_ankle", "r_hip"}};
      for (const auto& [frame, pose] : poses) {
        const bool complete = pose.count("l_hip") && pose.count("r_hip") && pose.count("l_knee") &&
                              pose.count("r_knee") && pose.count("l_ankle") && pose.count("r_ankle");
        if (!complete) continue;
        Feet now;
        now.frame = frame;
        now.forward = (pose.at("l_hip") - pose.at("r_hip")).cross(up).normalized();
        double lowest = 1e9;
        for (int side : {0, 1}) {
          now.feet[side] = kw::body::rollingFoot(pose.at(kJoints[side][0]), pose.at(kJoints[side][1]), now.forward, up, foot);
          const Eigen::Vector3d& centre = now.feet[side].centre_m;
          const double sole = (centre.z() - ground.height(centre.head<2>())) * up.z() - foot.radius_m;  // along the normal
          now.on_ground[side] = sole < contact_mm / 1000;
          lowest = std::min(lowest, sole);
        }
        penetration += std::max(0.0, -lowest);
        ++penetration_count;
        if (pose.count("waist") && pose.count("neck")) {
          const Eigen::Vector3d heading = Eigen::Vector3d(now.forward.x(), now.forward.y(), 0).normalized();
          lean += kw::body::torsoLeanRad(pose.at("waist"), pose.at("neck"), heading);
          ++lean_count;
        }
        if (frame == previous.frame + 1 && same_track(frame, previous.frame)) {
          for (int side : {0, 1})
            if (now.on_ground[side] && !previous.on_ground[side]) {
              knee_at_contact += kw::body::kneeFlexionRad(pose.at(kJoints[side][2]), pose.at(kJoints[side][0]),
                                                          pose.at(kJoints[side][1]));
              ++landings;
            }
          // Rolling moves the centre by −R·Δφ along the walk; the rest, along the ground, is slip.
          const Eigen::Vector3d forward = (now.forward + previous.forward).normalized();
          double least = -1;
          for (int side : {0, 1}) {
            if (!now.on_ground[side] || !previous.on_ground[side]) continue;
            Eigen::Vector3d slip = now.feet[side].centre_m - previous.feet[side].centre_m +
                                   foot.radius_m * (now.feet[side].roll_rad - previous.feet[side].roll_rad) * forward;
            slip -= slip.dot(up) * up;
            if (least < 0 || slip.norm() < least) least = slip.norm();
          }
          if (least >= 0) skate += least, ++skate_count;
        }
        previous = now;
      }
      constexpr double kDeg = 180 / M_PI;
      auto mean = [](double sum, int n, double scale) {
        return n > 0 ? std::optional<double>(scale * sum / n) : std::nullopt;
      };
      return Contact{mean(skate, skate_count, 1000), mean(penetration, penetration_count, 1000),
                     mean(lean, lean_count, kDeg), mean(knee_at_contact, landings, kDeg), landings};
    };
    const Contact estimated = contact(estimate, estimated_foot, estimate_tracks),
                  true_contact = contact(truth, true_foot, {});
    std::printf("frames=%d joints=%d\n", frames, count / frames);
    std::printf("estimated_frames=%d/%zu\n", frames, truth.size());
    std::printf("mean_joint_error_mm=%.1f\n", 1000 * sum / count);
    std::printf("root_relative_error_mm=%.1f\n", 1000 * root_sum / count);
    std::printf("lost_frames=%d\n", lost);
    if (compared_frames > 0)
      std::printf("legs_swapped_percent=%.1f\nroot_relative_swap_free_mm=%.1f\n", 100.0 * swapped_frames / compared_frames,
                  1000 * swap_free_sum / swap_free_count);
    if (angle_frames > 0)
      std::printf("knee_angle_error_deg=%.1f\nhip_angle_error_deg=%.1f\ntorso_lean_error_deg=%.1f\n",
                  180 / M_PI * knee_sum / knee_count, 180 / M_PI * hip_sum / knee_count, 180 / M_PI * lean_sum / angle_frames);
    if (sight_frames > 0)
      std::printf("depth_bias_mm=%.1f\nlateral_error_mm=%.1f\nrange_error_mm=%.1f\nrange_error_p95_mm=%.1f\n"
                  "range_error_percent=%.2f\n",
                  1000 * depth_sum / sight_frames, 1000 * lateral_sum / sight_frames,
                  1000 * kneed_walker::tools::median(range_abs), 1000 * kneed_walker::tools::percentile(range_abs, 95),
                  100 * kneed_walker::tools::median(range_share));
    // The estimate's walking direction 1 s after its first frame against the truth's, each its
    // waist's over ±0.5 s: over 90° is a track that started on the mirrored heading.
    {
      std::vector<double> intervals;
      for (auto it = truth_stamps.begin(); it != truth_stamps.end() && std::next(it) != truth_stamps.end(); ++it)
        intervals.push_back((std::next(it)->second - it->second) / (std::next(it)->first - it->first));
      const double dt = intervals.empty() ? 0 : kneed_walker::tools::median(intervals);
      const auto direction = [&](const std::map<int, Pose>& poses, int frame, int half) -> std::optional<double> {
        const auto before = poses.find(frame - half), after = poses.find(frame + half);
        if (before == poses.end() || after == poses.end() || !before->second.count("waist") ||
            !after->second.count("waist"))
          return std::nullopt;
        const Eigen::Vector3d walked = after->second.at("waist") - before->second.at("waist");
        if (walked.head<2>().norm() < 1e-3) return std::nullopt;
        return std::atan2(walked.y(), walked.x());
      };
      std::optional<double> error_deg;
      if (dt > 0) {
        const int half = std::max(1, static_cast<int>(std::lround(0.5 / dt)));
        const int at = estimate.begin()->first + static_cast<int>(std::lround(1.0 / dt));
        const auto estimated = direction(estimate, at, half), true_direction = direction(truth, at, half);
        if (estimated && true_direction)
          error_deg = std::abs(std::remainder(*estimated - *true_direction, 2 * M_PI)) * 180 / M_PI;
      }
      if (error_deg)
        std::printf("heading_error_1s_deg=%.1f\n", *error_deg);
      else
        std::printf("heading_error_1s_deg=n/a (the estimate or the truth is shorter, or did not move)\n");
    }
    // A figure, or n/a and why.
    auto figure = [](const char* name, const std::optional<double>& value, const char* why) {
      if (value)
        std::printf("%s=%.2f\n", name, *value);
      else
        std::printf("%s=n/a (%s)\n", name, why);
    };
    constexpr const char* kNoStance = "no foot on the ground in two adjacent frames";
    constexpr const char* kNoLegs = "no frame with both legs' hips, knees and ankles";
    constexpr const char* kNoTorso = "no frame with the legs, waist and neck";
    figure("footskate_mm", estimated.skate_mm, kNoStance);
    figure("ground_penetration_mm", estimated.penetration_mm, kNoLegs);
    figure("truth_footskate_mm", true_contact.skate_mm, kNoStance);
    figure("truth_ground_penetration_mm", true_contact.penetration_mm, kNoLegs);
    figure("torso_lean_deg", estimated.lean_deg, kNoTorso);
    figure("truth_torso_lean_deg", true_contact.lean_deg, kNoTorso);
    const std::string estimated_landings = "(" + std::to_string(estimated.landings) + " landings)";
    const std::string true_landings = "(" + std::to_string(true_contact.landings) + " landings)";
    if (estimated.knee_at_contact_deg)
      std::printf("knee_at_contact_deg=%.2f %s\n", *estimated.knee_at_contact_deg, estimated_landings.c_str());
    else
      std::printf("knee_at_contact_deg=n/a (no landing: no foot came down in adjacent frames)\n");
    if (true_contact.knee_at_contact_deg)
      std::printf("truth_knee_at_contact_deg=%.2f %s\n", *true_contact.knee_at_contact_deg, true_landings.c_str());
    else
      std::printf("truth_knee_at_contact_deg=n/a (no landing: no foot came down in adjacent frames)\n");
    if (!ground_track_path.empty()) {
      if (ground_path.empty()) throw std::runtime_error("--ground-track needs --ground (the camera's position)");
      printGroundTrackFigures(truth, readGroundTrack(ground_track_path, body),
                              kneed_walker::tools::loadCamera("evaluate", ground_path, camera_unit_m).centre(), height_m);
    }
    for (const auto& [joint, e] : per_joint) std::printf("error_mm_%s=%.1f\n", joint.c_str(), 1000 * e.first / e.second);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "evaluate: %s\n", e.what());
    return 1;
  }
  return 0;
}
