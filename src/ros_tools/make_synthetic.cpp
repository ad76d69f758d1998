// make_synthetic: a synthetic walking sequence with ground truth, for testing the tracker.
// A person walks by the stochastic prior (paper §3.4) around a table gait (or, with --end-speed
// and/or --end-step, around the gait of each stride's moment of a linear change), or by measured
// joint-angle curves (--norms: the Schwartz 2008 gait norms, a motion the prior did not make;
// synthetic/norm_walk.h) or by a motion capture (--bvh: ../shared/data/mocap's real walks,
// drawn as a person unlike the body model, with arms; synthetic/captured_walk.h), is rendered as the
// tracker's body model over a real background (the median of a video from the same static
// camera) or a textured ground plane, with sensor noise and optionally an occluder crossing in
// front. Writes into --out-dir:
//   NAME.bag                    /camera/image_raw (sensor_msgs/Image, bgr8),
//                               /camera/camera_info, /tf_static (world -> camera_optical)
//   NAME_ground_truth.csv       frame,stamp,joint,x,y,z: REP 155 joints, metres, world frame
//   NAME_boxes.csv              frame,x1,y1,x2,y2,score: the drawn person's image box, px (as
//                               a person detector's boxes: where a user would start the track)
//   NAME_camera.yml             the calibration (world units mm, as the PETS file) and the
//                               ground plane: ground_point_mm, ground_slope_rad,
//                               ground_uphill_heading_rad
//   NAME.avi                    the same frames as a Motion-JPEG video, to watch
// The output is byte-identical for the same options and seed.
//
//   rosrun kneed_walker make_synthetic --camera ../shared/data/pets2009/View_001_camera.yml
//       --background ../shared/data/pets2009/vtest.avi --out-dir /tmp/synthetic  (one line)
//   rosrun kneed_walker make_synthetic --config test/sequences/level_slow.ini --out-dir DIR
#include <CLI/CLI.hpp>
#include <cv_bridge/cv_bridge.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <ros/package.h>
#include <ros/time.h>
#include <rosbag/bag.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <sstream>

#include "options.h"
#include "kneed_walker/core/synthetic/captured_walk.h"
#include "kneed_walker/core/synthetic/norm_walk.h"
#include "kneed_walker/core/synthetic/synthetic_scene.h"
#include "kneed_walker/core/vision/background.h"
#include "kneed_walker/ros/bag_writing.h"
#include "kneed_walker/ros/conversions.h"
#include "camera_file.h"

namespace kw = kneed_walker::core;

namespace {

struct Settings {
  std::string out_dir, name = "synthetic";
  std::string table, prior, walker_model;
  std::string camera_path, background = "textured";
  double camera_unit_m = 0.001;
  int background_samples = 25;
  std::vector<double> start_pixel;  // x, y; empty: the image point chosen by default
  double noise_sigma = 3.0;
  bool occluder = false;
  bool heading_given = false;
  double oblique_deg = 0;  // the default heading turned away from the camera by this
  std::string norms;       // drive the walk by these gait norms instead of the prior
  std::string bvh;         // or play this motion capture, drawn as a person unlike the body model
  double bvh_start_s = 0;  // from this time of the capture
  double end_speed_kmh = 0;  // the speed at the end (0: the start speed)
  double end_step_m = 0;     // by the prior: the step length at the end (0: the start's)
  double start_stamp_s = 1.7e9;
  kw::synthetic::SyntheticWalkOptions walk;
};

bool isImageFile(const std::string& path) {
  std::string lower = path;
  std::transform(lower.begin(), lower.end(), lower.begin(), ::tolower);
  for (const char* ext : {".png", ".jpg", ".jpeg", ".bmp", ".ppm"})
    if (lower.size() > std::strlen(ext) && lower.compare(lower.size() - std::strlen(ext), std::string::npos, ext) == 0)
      return true;
  return false;
}

cv::Mat background(const Settings& s, const kw::vision::Camera& camera, const kw::vision::GroundPlane& ground) {
  cv::Mat image;
  if (s.background == "textured") {
    image = kw::synthetic::texturedGround(camera, ground, s.walk.seed);
  } else if (isImageFile(s.background)) {
    image = cv::imread(s.background, cv::IMREAD_COLOR);
    if (image.empty()) throw std::runtime_error(s.background + ": cannot read the background image");
  } else {
    image = kw::vision::medianBackground(s.background, s.background_samples);
  }
  if (image.cols != camera.width() || image.rows != camera.height())
    throw std::runtime_error("the background is " + std::to_string(image.cols) + "x" +
                             std::to_string(image.rows) + " but the camera's images are " +
                             std::to_string(camera.width()) + "x" + std::to_string(camera.height()));
  return image;
}

void writeCameraAndGround(const std::string& path, const kw::vision::Camera& camera, const kw::vision::GroundPlane& ground) {
  cv::FileStorage file(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
  if (!file.isOpened()) throw std::runtime_error(path + ": cannot write the calibration");
  camera.write(file, 0.001);
  kw::vision::writeGroundPlane(file, ground);
}

// Pixel height of the person (head top to lowest foot) in a frame, for the summary.
double pixelHeight(const kw::vision::Camera& camera, const kw::body::BodyPose& pose, double height_m) {
  const auto top = camera.project(pose.joints[kw::body::kHead] + 0.06 * height_m * Eigen::Vector3d::UnitZ());
  const auto foot = camera.project(0.5 * (pose.foot_centres[0] + pose.foot_centres[1]));
  return top && foot ? (*foot - *top).norm() : 0.0;
}

// The walk: by the gait norms (--norms) or by the prior around a table gait.
kw::synthetic::SyntheticWalk synthesize(const Settings& s, const kw::synthetic::SyntheticWalkOptions& options) {
  const kw::dynamics::BodyProportions proportions = kw::dynamics::loadBodyProportions(s.walker_model);
  if (s.norms.empty())
    return kw::synthetic::synthesizeWalk(kw::gait::loadGaitTable(s.table, proportions),
                                         kw::prior::loadPriorOptions(s.prior), options);
  kw::synthetic::NormWalkOptions norm;
  norm.start_speed_kmh = options.speed_kmh;
  norm.end_speed_kmh = s.end_speed_kmh > 0 ? s.end_speed_kmh : options.speed_kmh;
  norm.heading_rad = options.heading_rad;
  norm.slope_rad = options.slope_rad;
  norm.start_m = options.start_m;
  norm.duration_s = options.duration_s;
  norm.fps = options.fps;
  norm.person_height_m = options.person_height_m;
  norm.seed = options.seed;
  kw::gait::GaitNorms norms;
  try {
    norms = kw::gait::loadGaitNorms(s.norms);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(std::string("--norms: ") + e.what());
  }
  return kw::synthetic::synthesizeNormWalk(norms, proportions, norm);
}

// Mean step length over the walk's whole steps (heel strike to heel strike), m; 0 if fewer than two.
double meanStepLength(const kw::synthetic::SyntheticWalk& walk) {
  std::vector<Eigen::Vector3d> strikes;
  for (size_t i = 1; i < walk.frames.size(); ++i)
    if (walk.frames[i].walker.heel_strikes != walk.frames[i - 1].walker.heel_strikes)
      strikes.push_back(walk.frames[i].pose.joints[kw::body::kWaist]);
  return strikes.size() < 2 ? 0.0 : (strikes.back() - strikes.front()).norm() / static_cast<double>(strikes.size() - 1);
}

// Writes the sequence; `outputs` receives the files it creates, so that a failure can remove them.
int run(const Settings& s, std::vector<std::string>& outputs) {
  if (!s.bvh.empty() && s.walk.slope_rad != 0)
    throw std::runtime_error("--slope: a --bvh capture is played on level ground");
  const kw::vision::Camera camera = kneed_walker::tools::loadCamera("make_synthetic", s.camera_path, s.camera_unit_m);
  kw::synthetic::SyntheticWalkOptions options = s.walk;
  if (s.end_speed_kmh > 0) options.end_speed_kmh = s.end_speed_kmh;
  if (s.end_step_m > 0) options.end_step_length_m = s.end_step_m;
  const Eigen::Vector2d start_pixel = s.start_pixel.size() == 2
                                          ? Eigen::Vector2d(s.start_pixel[0], s.start_pixel[1])
                                          : Eigen::Vector2d(0.75 * camera.width(), 0.85 * camera.height());
  if (!(start_pixel.x() >= 0 && start_pixel.x() < camera.width() && start_pixel.y() >= 0 &&
        start_pixel.y() < camera.height())) {
    char text[160];
    std::snprintf(text, sizeof text, "--start-pixel (%g, %g) lies outside the camera's %dx%d image", start_pixel.x(),
                  start_pixel.y(), camera.width(), camera.height());
    throw std::runtime_error(text);
  }
  const auto start = camera.groundPoint(start_pixel);
  if (!start) throw std::runtime_error("--start-pixel does not see the ground (it is above the horizon)");
  options.start_m = start->head<2>();
  if (!s.heading_given) {  // across the camera's line of sight, towards the image's left
    const Eigen::Vector2d from_camera = options.start_m - camera.centre().head<2>();
    const Eigen::Vector2d across(from_camera.y(), -from_camera.x());
    const auto ahead = camera.project(*start + 0.5 * Eigen::Vector3d(across.normalized().x(), across.normalized().y(), 0));
    const double sign = ahead && ahead->x() < start_pixel.x() ? 1.0 : -1.0;
    options.heading_rad = std::atan2(sign * across.y(), sign * across.x());
    // Turned away from the camera by --oblique: counter-clockwise when that leads away from it.
    const double turn = s.oblique_deg * M_PI / 180.0;
    const Eigen::Vector2d direction(std::cos(options.heading_rad), std::sin(options.heading_rad));
    const double cross = direction.x() * from_camera.y() - direction.y() * from_camera.x();
    options.heading_rad += (cross > 0 ? 1.0 : -1.0) * turn;
  }
  // A motion capture: its joints per frame, placed in the scene, and the truth's REP 155 joints.
  std::optional<kw::synthetic::CapturedMotion> captured;
  std::vector<std::vector<Eigen::Vector3d>> captured_joints;
  const kw::synthetic::SyntheticWalk walk = s.bvh.empty() ? synthesize(s, options) : [&] {
    try {
      captured = kw::synthetic::loadBvh(s.bvh);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(std::string("--bvh ") + e.what());
    }
    const double length_s = captured->frame_time_s * (captured->positions_m.size() - 1) - s.bvh_start_s;
    if (length_s <= 0) throw std::runtime_error("--bvh-start lies past the capture's end");
    const Eigen::Isometry3d place = kw::synthetic::placeCaptured(*captured, {options.start_m, options.heading_rad});
    const Eigen::Vector3d forward(std::cos(options.heading_rad), std::sin(options.heading_rad), 0);
    kw::synthetic::SyntheticWalk w;
    const int frames = 1 + static_cast<int>(std::floor(std::min(options.duration_s, length_s) * options.fps + 1e-9));
    double top_m = 0;
    for (int i = 0; i < frames; ++i) {
      std::vector<Eigen::Vector3d> joints = kw::synthetic::jointsAt(*captured, s.bvh_start_s + i / options.fps);
      for (Eigen::Vector3d& p : joints) p = place * p;
      kw::synthetic::SyntheticFrame frame;
      frame.time_s = i / options.fps;
      frame.pose = kw::synthetic::capturedBodyPose(*captured, joints, forward);
      top_m = std::max(top_m, frame.pose.joints[kw::body::kHead].z());
      w.frames.push_back(frame);
      captured_joints.push_back(std::move(joints));
    }
    options.person_height_m = top_m + 0.11;  // the head's centre lies a head's radius below the crown
    return w;
  }();
  const kw::body::BodyShape shape = kw::body::BodyShape::forHeight(options.person_height_m);
  const kw::synthetic::CapturedFigure figure = kw::synthetic::capturedFigure(options.seed);
  const cv::Mat scene = background(s, camera, walk.ground);
  const kw::synthetic::SyntheticFrame& middle = walk.frames[walk.frames.size() / 2];
  const kw::synthetic::Occluder occluder = kw::synthetic::crossingOccluder(
      camera, middle.pose.joints[kw::body::kWaist], middle.time_s, middle.pose.forward.head<2>());

  double smallest_px = 1e9, largest_px = 0;
  for (const kw::synthetic::SyntheticFrame& frame : walk.frames) {
    const double px = pixelHeight(camera, frame.pose, options.person_height_m);
    smallest_px = std::min(smallest_px, px);
    largest_px = std::max(largest_px, px);
  }

  const std::string stem = s.out_dir + "/" + s.name;
  outputs = {stem + ".bag", stem + "_ground_truth.csv", stem + ".avi", stem + "_camera.yml", stem + "_boxes.csv"};
  rosbag::Bag bag(stem + ".bag", rosbag::bagmode::Write);
  std::ofstream csv(stem + "_ground_truth.csv");
  if (!csv) throw std::runtime_error(stem + "_ground_truth.csv: cannot write");
  csv << "frame,stamp,joint,x,y,z\n" << std::fixed;
  // The drawn person's image box per frame (all of them, an occluder notwithstanding), as a
  // person detector's boxes (track_offline --boxes, --init-box): a box to start from.
  std::ofstream boxes(stem + "_boxes.csv");
  if (!boxes) throw std::runtime_error(stem + "_boxes.csv: cannot write");
  boxes << "frame,x1,y1,x2,y2,score\n";
  cv::VideoWriter video(stem + ".avi", cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'),
                        options.fps, cv::Size(camera.width(), camera.height()));
  if (!video.isOpened()) throw std::runtime_error(stem + ".avi: cannot write the video");
  writeCameraAndGround(stem + "_camera.yml", camera, walk.ground);

  const std::string camera_frame = "camera_optical", world_frame = "world";
  const ros::Time first_stamp(s.start_stamp_s);
  kneed_walker::ros_glue::writeStaticCameraPose(bag, camera, world_frame, camera_frame, first_stamp, "/make_synthetic");
  sensor_msgs::CameraInfo info = kneed_walker::ros_glue::toCameraInfo(camera, camera_frame);
  for (size_t i = 0; i < walk.frames.size(); ++i) {
    const kw::synthetic::SyntheticFrame& frame = walk.frames[i];
    cv::Mat image = scene.clone();
    if (captured)
      kw::synthetic::drawCapturedPerson(image, camera, *captured, captured_joints[i], figure);
    else
      kw::synthetic::drawPerson(image, camera, frame.pose, shape, kw::synthetic::PersonAppearance{});
    {
      cv::Mat changed;
      cv::absdiff(image, scene, changed);
      cv::cvtColor(changed, changed, cv::COLOR_BGR2GRAY);
      const cv::Rect box = cv::boundingRect(changed > 0);
      if (!box.empty()) boxes << i << ',' << box.x << ',' << box.y << ',' << box.x + box.width << ',' << box.y + box.height << ",1\n";
    }
    if (s.occluder) kw::synthetic::drawOccluder(image, camera, occluder, frame.time_s);
    kw::synthetic::addSensorNoise(image, s.noise_sigma, options.seed * 1000003u + i);

    const ros::Time stamp = first_stamp + ros::Duration(frame.time_s);
    std_msgs::Header header;
    header.seq = static_cast<std::uint32_t>(i);
    header.stamp = stamp;
    header.frame_id = camera_frame;
    info.header = header;
    bag.write("/camera/image_raw", stamp, *cv_bridge::CvImage(header, "bgr8", image).toImageMsg());
    bag.write("/camera/camera_info", stamp, info);
    video.write(image);
    for (int j = 0; j < kw::body::kNumBodyJoints; ++j) {
      const Eigen::Vector3d& p = frame.pose.joints[j];
      csv << i << ',' << std::setprecision(6) << stamp.toSec() << ',' << kw::body::jointName(kw::body::BodyJoint(j)) << ','
          << std::setprecision(6) << p.x() << ',' << p.y() << ',' << p.z() << '\n';
    }
  }
  bag.close();
  csv.close();
  boxes.close();
  if (!csv || !boxes) throw std::runtime_error(stem + "_ground_truth.csv, _boxes.csv: cannot write (disk full?)");
  if (!walk.gait_note.empty()) std::fprintf(stderr, "make_synthetic: %s\n", walk.gait_note.c_str());
  if (captured) {
    std::printf("make_synthetic: %zu frames at %.1f fps, played from %s from %.2f s, heading %.3f rad, a person "
                "%.2f m tall drawn %.2f times as broad as the body model, seed %llu\n",
                walk.frames.size(), options.fps, s.bvh.c_str(), s.bvh_start_s, options.heading_rad,
                options.person_height_m, figure.breadth_scale, static_cast<unsigned long long>(options.seed));
  } else if (s.norms.empty()) {
    char gait[96];
    if (options.end_speed_kmh || options.end_step_length_m)
      std::snprintf(gait, sizeof gait, "%.2f to %.2f km/h, %.2f to %.2f m steps", options.speed_kmh,
                    options.end_speed_kmh.value_or(options.speed_kmh), options.step_length_m,
                    options.end_step_length_m.value_or(options.step_length_m));
    else
      std::snprintf(gait, sizeof gait, "%.2f km/h, %.2f m steps", options.speed_kmh, options.step_length_m);
    std::printf("make_synthetic: %zu frames at %.1f fps, %s, slope %.3f rad, seed %llu (%d prior sample%s)\n",
                walk.frames.size(), options.fps, gait, options.slope_rad,
                static_cast<unsigned long long>(options.seed), walk.attempts, walk.attempts == 1 ? "" : "s");
  } else {
    std::printf("make_synthetic: %zu frames at %.1f fps, walked by the gait norms %s at %.2f to %.2f km/h, "
                "%.2f m mean steps, slope %.3f rad, heading %.3f rad, seed %llu\n",
                walk.frames.size(), options.fps, s.norms.c_str(), options.speed_kmh,
                s.end_speed_kmh > 0 ? s.end_speed_kmh : options.speed_kmh, meanStepLength(walk),
                options.slope_rad, options.heading_rad, static_cast<unsigned long long>(options.seed));
  }
  std::printf("person %.0f-%.0f px tall; wrote %s.bag, %s_ground_truth.csv, %s_boxes.csv, %s_camera.yml, %s.avi\n",
              smallest_px, largest_px, stem.c_str(), stem.c_str(), stem.c_str(), stem.c_str(), stem.c_str());
  return 0;
}

// Paths read from the --config file are relative to that file (the command line's to the
// working directory); every input file must then exist. Returns the problem, naming the option.
std::string resolveFiles(const CLI::App& app, int argc, char** argv, Settings& s) {
  const std::string config = app.get_option("--config")->as<std::string>();
  std::error_code error;  // the file's real directory: a config reached through a link resolves from where it is
  const std::string config_dir =
      config.empty() ? "" : std::filesystem::canonical(config, error).parent_path().string();
  auto on_command_line = [&](const std::string& option) {
    for (int i = 1; i < argc; ++i)
      if (argv[i] == option || std::string(argv[i]).rfind(option + "=", 0) == 0) return true;
    return false;
  };
  struct PathOption {
    const char* name;
    std::string* value;
  };
  const bool video_background = s.background != "textured";
  for (const PathOption& o : {PathOption{"--camera", &s.camera_path}, PathOption{"--background", &s.background},
                              PathOption{"--norms", &s.norms}, PathOption{"--bvh", &s.bvh}, PathOption{"--table", &s.table},
                              PathOption{"--prior", &s.prior}, PathOption{"--walker-model", &s.walker_model}}) {
    if (o.value->empty() || (o.value == &s.background && !video_background)) continue;
    if (app.count(o.name) > 0 && !on_command_line(o.name) && !config_dir.empty() &&
        std::filesystem::path(*o.value).is_relative())
      *o.value = (std::filesystem::path(config_dir) / *o.value).lexically_normal().string();
    if (!std::filesystem::is_regular_file(*o.value))
      return std::string(o.name) + ": " + *o.value + " is not a readable file" +
             (app.count(o.name) > 0 && !on_command_line(o.name) ? " (from " + config + ")" : "");
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Renders a synthetic walking sequence with ground truth (bag, CSV, calibration, video)."};
  app.set_config("--config", "", "read these options from an INI/TOML file (command line wins; relative paths in "
                 "it are relative to the file)");
  app.allow_config_extras(CLI::config_extras_mode::error);  // a misspelt key is an error, not ignored
  Settings s;
  const std::string share = ros::package::getPath("kneed_walker");
  s.table = share + "/config/prior_gait_table.yaml";
  s.prior = share + "/config/prior.yaml";
  s.walker_model = share + "/config/walker_model.yaml";
  kw::synthetic::SyntheticWalkOptions& w = s.walk;
  app.add_option("--out-dir", s.out_dir, "directory to write into (must exist)")->required()->check(CLI::ExistingDirectory);
  app.add_option("--name", s.name, "file name stem of the outputs")->capture_default_str();
  app.add_option("--camera", s.camera_path, "calibration (OpenCV YAML: camera_matrix, distortion_coefficients, R, t)")
      ->required();
  app.add_option("--camera-unit", s.camera_unit_m, "metres per length unit of the calibration's t")->capture_default_str()
      ->check(kneed_walker::tools::FiniteRange(1e-6, 1e3));
  app.add_option("--background", s.background,
                 "'textured' (a paved ground plane), an image, or a video whose median frame is the empty scene")->capture_default_str();
  app.add_option("--background-samples", s.background_samples, "frames of the video in the median")->capture_default_str()
      ->check(CLI::Range(1, 1000));
  app.add_option("--table", s.table, "gait table the prior walks around")->capture_default_str();
  app.add_option("--prior", s.prior, "prior parameters")->capture_default_str();
  app.add_option("--walker-model", s.walker_model, "body proportions; the table must be made for them")
      ->capture_default_str();
  app.add_option("--speed", w.speed_kmh, "walking speed, km/h")->capture_default_str()->check(kneed_walker::tools::FiniteRange(0.5, 10));
  auto* step = app.add_option("--step", w.step_length_m, "step length, m (not with --norms: the norms set it)")
                   ->capture_default_str()->check(kneed_walker::tools::FiniteRange(0.1, 3));
  app.add_option("--slope", w.slope_rad, "ground slope along the walk, rad, positive uphill")
      ->capture_default_str()->check(kneed_walker::tools::FiniteRange(-0.2, 0.2));
  auto* norms = app.add_option("--norms", s.norms,
                 "walk by these gait norms (Schwartz2008_Joint_Rotations.csv) instead of the prior: a motion the "
                 "prior did not make")->excludes(step);
  auto* bvh = app.add_option("--bvh", s.bvh,
                              "play this motion capture (BVH, cm, Y up: ../shared/data/mocap) instead of the prior, "
                              "drawn as a person unlike the tracker's body model (breadth, arms, head and colours of "
                              "--seed); on level ground, its speed and height its own")
                  ->excludes(norms)->excludes(step);
  app.add_option("--bvh-start", s.bvh_start_s, "with --bvh: start this far into the capture, s (past a standing start)")
      ->capture_default_str()->check(kneed_walker::tools::FiniteRange(0, 3600))->needs(bvh);
  app.add_option("--end-speed", s.end_speed_kmh,
                 "the speed at the end, km/h; the speed changes linearly from --speed (default: --speed); by the "
                 "prior, each stride walks the gait of its heel strike's moment")
      ->check(kneed_walker::tools::FiniteRange(0.5, 10));
  app.add_option("--end-step", s.end_step_m,
                 "by the prior: the step length at the end, m; it changes linearly from --step (default: --step)")
      ->excludes(norms)->check(kneed_walker::tools::FiniteRange(0.1, 3));
  app.add_option("--oblique", s.oblique_deg,
                 "turn the default walking direction (across the view) away from the camera by this, degrees")
      ->capture_default_str()->check(kneed_walker::tools::FiniteRange(-80, 80));
  app.add_option("--heading", w.heading_rad,
                 "walking direction in the world XY plane, rad from +X towards +Y; default: across the view, "
                 "towards the image's left")->check(kneed_walker::tools::FiniteRange(-10, 10));
  app.add_option("--start-pixel", s.start_pixel, "image point (x y) where the walk starts on the ground")
      ->expected(2)->check(kneed_walker::tools::FiniteRange(-1e12, 1e12));
  app.add_option("--duration", w.duration_s, "length, s")->capture_default_str()->check(kneed_walker::tools::FiniteRange(0.01, 3600));
  app.add_option("--fps", w.fps, "frame rate, frames/s")->capture_default_str()->check(kneed_walker::tools::FiniteRange(1, 1000));
  app.add_option("--height", w.person_height_m, "the person's height, m")->capture_default_str()->check(kneed_walker::tools::FiniteRange(1.0, 2.3));
  app.add_option("--seed", w.seed, "random seed: the same seed gives the same files")->capture_default_str()
      ->check(kneed_walker::tools::FiniteRange(0, 1.8e19));
  app.add_option("--noise", s.noise_sigma, "sensor noise, grey levels (standard deviation)")->capture_default_str()
      ->check(kneed_walker::tools::FiniteRange(0.0, 100.0));
  app.add_flag("--occluder", s.occluder, "a board crosses in front of the person mid-sequence");
  app.add_option("--start-stamp", s.start_stamp_s, "stamp of the first frame, s since the epoch")->capture_default_str()
      ->check(kneed_walker::tools::FiniteRange(1e-3, 4e9));
  if (!kneed_walker::tools::refuseEmptyArguments("make_synthetic", argc, argv)) return 1;
  CLI11_PARSE(app, argc, argv);
  if (const std::string problem = resolveFiles(app, argc, argv, s); !problem.empty()) {
    std::fprintf(stderr, "make_synthetic: %s\n", problem.c_str());
    return 2;
  }
  s.heading_given = app.count("--heading") > 0;
  if (s.heading_given && app.count("--oblique") > 0) {
    std::fprintf(stderr, "make_synthetic: --oblique turns the default heading; give it or --heading, not both\n");
    return 2;
  }
  if (w.duration_s * w.fps > 100000) {
    std::fprintf(stderr, "make_synthetic: --duration times --fps is %g frames; at most 100000\n", w.duration_s * w.fps);
    return 2;
  }
  std::vector<std::string> outputs;
  try {
    ros::Time::init();
    return run(s, outputs);
  } catch (const std::exception& e) {
    for (const std::string& path : outputs) std::remove(path.c_str());  // no partial sequence is left behind
    std::fprintf(stderr, "make_synthetic: %s\n", e.what());
    return 1;
  }
}
