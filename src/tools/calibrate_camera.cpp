// calibrate_camera: your own static camera's calibration for the tracker, from its intrinsics
// and four or more marks on the ground whose positions you measured.
//
//   rosrun kneed_walker calibrate_camera --intrinsics camera_info.yaml --points marks.csv   (one line)
//          --out my_camera.yml [--check frame.png --check-out check.png --person 2 3]
//   rosrun kneed_walker calibrate_camera --camera my_camera.yml --check frame.png --check-out check.png
//
// --intrinsics: a camera driver's camera_info YAML (camera_calibration's output) or an OpenCV
// calibration with camera_matrix and distortion_coefficients. --points: a CSV `u,v,x,y`, one
// mark a line: its pixel (column, row) in a frame of the camera and its position on the ground
// in metres, in any world frame you choose on the ground (Z is up, the ground is Z = 0). Prints
// the reprojection error of every mark and the camera's place, and writes the calibration the
// tools and the nodelet's camera_file read (t in --camera-unit metres, default mm). With five
// marks or more, each is left out in turn: a mark far from where the others put the camera's
// view (a mis-click) is named, with the calibration without it beside the one with it. A
// calibration whose reprojection rms is over --accept-rms (3 px) is not written.
//
// --check draws on a frame (an image, or a video's first frame) the ground's 1 m grid, the world
// axes (X red, Y green, 1 m), the marks (measured: green circles; where the calibration puts
// them: red crosses) and a person --person-height tall standing at each --person X Y: lines on
// the floor should lie on the grid, and a person standing there should be as tall as the figure.
#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "kneed_walker/core/vision/camera_calibration.h"
#include "options.h"
#include "tool_main.h"
#include "camera_file.h"

namespace kw = kneed_walker::core;
using kneed_walker::tools::FiniteRange;

namespace {

cv::Point toPoint(const Eigen::Vector2d& p) { return {static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y()))}; }

// A world polyline drawn where both ends of a piece are in front of the camera and near the image.
void drawWorldLine(cv::Mat& image, const kw::vision::Camera& camera, const Eigen::Vector3d& from,
                   const Eigen::Vector3d& to, const cv::Scalar& colour, int thickness) {
  const int pieces = std::max(1, static_cast<int>(std::ceil((to - from).norm() / 0.1)));
  const double margin = 0.5 * std::max(camera.width(), camera.height());
  auto near_image = [&](const Eigen::Vector2d& p) {
    return p.x() > -margin && p.y() > -margin && p.x() < camera.width() + margin && p.y() < camera.height() + margin;
  };
  std::optional<Eigen::Vector2d> last = camera.project(from);
  for (int i = 1; i <= pieces; ++i) {
    const std::optional<Eigen::Vector2d> next = camera.project(from + (to - from) * (double(i) / pieces));
    if (last && next && near_image(*last) && near_image(*next))
      cv::line(image, toPoint(*last), toPoint(*next), colour, thickness, cv::LINE_AA);
    last = next;
  }
}

// The ground's extent seen in the image (metres, X then Y), within 40 m of the camera.
std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> visibleGround(const kw::vision::Camera& camera) {
  std::vector<Eigen::Vector2d> pixels;
  for (int v = 0; v <= camera.height(); v += std::max(1, camera.height() / 24))
    for (int u = 0; u <= camera.width(); u += std::max(1, camera.width() / 24)) pixels.emplace_back(u, v);
  const std::vector<Eigen::Vector3d> rays = camera.rays(pixels);
  const Eigen::Vector3d centre = camera.centre();
  Eigen::Vector2d low = Eigen::Vector2d::Constant(1e18), high = Eigen::Vector2d::Constant(-1e18);
  bool any = false;
  for (const Eigen::Vector3d& ray : rays) {
    if (ray.z() >= 0) continue;
    const Eigen::Vector3d ground = centre - centre.z() / ray.z() * ray;
    if ((ground - centre).norm() > 40) continue;
    low = low.cwiseMin(ground.head<2>());
    high = high.cwiseMax(ground.head<2>());
    any = true;
  }
  if (!any) return std::nullopt;
  return std::make_pair(low, high);
}

void drawCheck(cv::Mat& image, const kw::vision::Camera& camera,
               const std::vector<kw::vision::GroundPointObservation>& marks, const std::vector<double>& people_xy,
               double person_height_m) {
  if (const auto extent = visibleGround(camera)) {
    const Eigen::Vector2d low = extent->first.array().floor(), high = extent->second.array().ceil();
    for (double x = low.x(); x <= high.x(); x += 1)
      drawWorldLine(image, camera, {x, low.y(), 0}, {x, high.y(), 0}, cv::Scalar(255, 255, 0), 1);
    for (double y = low.y(); y <= high.y(); y += 1)
      drawWorldLine(image, camera, {low.x(), y, 0}, {high.x(), y, 0}, cv::Scalar(255, 255, 0), 1);
  }
  drawWorldLine(image, camera, {0, 0, 0}, {1, 0, 0}, cv::Scalar(0, 0, 255), 3);
  drawWorldLine(image, camera, {0, 0, 0}, {0, 1, 0}, cv::Scalar(0, 255, 0), 3);
  for (std::size_t i = 0; i < marks.size(); ++i) {
    const cv::Point measured = toPoint(marks[i].pixel);
    cv::circle(image, measured, 6, cv::Scalar(0, 255, 0), 2, cv::LINE_AA);
    cv::putText(image, std::to_string(i + 1), measured + cv::Point(8, -8), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                cv::Scalar(0, 255, 0), 1, cv::LINE_AA);
    if (const auto projected = camera.project({marks[i].ground_m.x(), marks[i].ground_m.y(), 0}))
      cv::drawMarker(image, toPoint(*projected), cv::Scalar(0, 0, 255), cv::MARKER_CROSS, 12, 2);
  }
  // A person: a box 0.45 m broad across the line of sight, person_height_m tall.
  for (std::size_t i = 0; i + 1 < people_xy.size(); i += 2) {
    const Eigen::Vector3d foot(people_xy[i], people_xy[i + 1], 0);
    Eigen::Vector3d across = (foot - camera.centre()).cross(Eigen::Vector3d::UnitZ());
    across = across.norm() > 1e-9 ? Eigen::Vector3d(0.225 * across.normalized()) : Eigen::Vector3d(0.225, 0, 0);
    const Eigen::Vector3d up(0, 0, person_height_m);
    const Eigen::Vector3d corners[4] = {foot - across, foot + across, foot + across + up, foot - across + up};
    for (int c = 0; c < 4; ++c) drawWorldLine(image, camera, corners[c], corners[(c + 1) % 4], cv::Scalar(0, 165, 255), 2);
    if (const auto head = camera.project(foot + up)) {
      char label[32];
      std::snprintf(label, sizeof label, "%.2f m", person_height_m);
      cv::putText(image, label, toPoint(*head) + cv::Point(6, -6), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                  cv::Scalar(0, 165, 255), 1, cv::LINE_AA);
    }
  }
}

cv::Mat readFrame(const std::string& path) {
  cv::Mat frame = cv::imread(path, cv::IMREAD_COLOR);
  if (frame.empty()) {
    cv::VideoCapture video(path);
    if (video.isOpened()) video.read(frame);
  }
  if (frame.empty()) throw std::runtime_error("--check " + path + ": not an image or video OpenCV can read");
  return frame;
}

int run(int argc, char** argv) {
  CLI::App app{"A static camera's calibration (pose over the ground) from its intrinsics and ground points."};
  std::string intrinsics_path, points_path, out_path, camera_path, check_path, check_out_path;
  double camera_unit_m = 0.001, person_height_m = 1.75, accept_rms_px = 3.0;
  std::vector<double> people_xy;
  auto* intrinsics_option = app.add_option("--intrinsics", intrinsics_path,
                                           "camera_info YAML or OpenCV calibration with camera_matrix, "
                                           "distortion_coefficients, image_width, image_height")
                                ->check(CLI::ExistingFile);
  auto* points_option =
      app.add_option("--points", points_path, "CSV u,v,x,y: each mark's pixel and its ground position, m")
          ->check(CLI::ExistingFile);
  auto* out_option = app.add_option("--out", out_path, "calibration to write (OpenCV YAML, as the tools read)");
  auto* camera_option = app.add_option("--camera", camera_path, "an existing calibration to check instead")
                            ->check(CLI::ExistingFile);
  app.add_option("--accept-rms", accept_rms_px,
                 "write the calibration only when the marks' reprojection rms is at most this, px")
      ->capture_default_str()->check(FiniteRange(0, 1e4));
  app.add_option("--camera-unit", camera_unit_m, "metres per unit of the calibration's t")
      ->capture_default_str()->check(FiniteRange(1e-6, 1e3));
  auto* check_option = app.add_option("--check", check_path, "a frame of the camera (image, or a video's first frame) to draw on")
                           ->check(CLI::ExistingFile);
  auto* check_out_option = app.add_option("--check-out", check_out_path, "the drawn check image to write (.png, .jpg)");
  auto* person_option = app.add_option("--person", people_xy, "ground point X Y (m) where a person is drawn; repeat for more")
                            ->expected(2)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
                            ->check(FiniteRange(-1e4, 1e4));
  app.add_option("--person-height", person_height_m, "the drawn person's height, m")
      ->capture_default_str()->check(FiniteRange(0.5, 2.5));
  intrinsics_option->needs(points_option, out_option)->excludes(camera_option);
  points_option->needs(intrinsics_option);
  out_option->needs(intrinsics_option);
  check_option->needs(check_out_option);
  check_out_option->needs(check_option);
  person_option->needs(check_option);
  if (!kneed_walker::tools::refuseEmptyArguments("calibrate_camera", argc, argv)) return 1;
  CLI11_PARSE(app, argc, argv);
  if (intrinsics_path.empty() && camera_path.empty()) {
    std::fprintf(stderr, "calibrate_camera: give --intrinsics, --points and --out to calibrate, or --camera and --check to check\n");
    return 1;
  }
  if (!camera_path.empty() && check_path.empty()) {
    std::fprintf(stderr, "calibrate_camera: --camera is checked on a frame: give --check and --check-out\n");
    return 1;
  }
  if (!check_out_path.empty() && !cv::haveImageWriter(check_out_path)) {
    std::fprintf(stderr, "calibrate_camera: --check-out %s: not an image file name OpenCV can write (.png, .jpg, ...)\n",
                 check_out_path.c_str());
    return 1;
  }
  // Both outputs are tried before any work, so that a run that cannot write one writes neither.
  for (const auto& [option, path] : {std::pair<const char*, const std::string*>{"--out", &out_path},
                                     {"--check-out", &check_out_path}}) {
    if (path->empty() || std::filesystem::exists(*path)) continue;
    const bool writable = static_cast<bool>(std::ofstream(*path));
    std::filesystem::remove(*path);
    if (!writable) {
      std::fprintf(stderr, "calibrate_camera: %s %s: cannot write\n", option, path->c_str());
      return 1;
    }
  }
  const cv::Mat frame = check_path.empty() ? cv::Mat() : readFrame(check_path);

  std::vector<kw::vision::GroundPointObservation> marks;
  std::optional<kw::vision::Camera> camera;
  if (!camera_path.empty()) {
    camera = kneed_walker::tools::loadCamera("calibrate_camera", camera_path, camera_unit_m);
  } else {
    const kw::vision::CameraIntrinsics intrinsics = kw::vision::loadCameraIntrinsics(intrinsics_path);
    marks = kw::vision::loadGroundPoints(points_path);
    const kw::vision::GroundPoseFit fit = [&] {
      try {
        return kw::vision::solveGroundPose(intrinsics, marks);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument("--points " + points_path + ": " + e.what());
      }
    }();
    for (std::size_t i = 0; i < marks.size(); ++i)
      std::printf("point %zu: pixel (%.1f, %.1f), ground (%.3f, %.3f) m: reprojection error %.2f px\n", i + 1,
                  marks[i].pixel.x(), marks[i].pixel.y(), marks[i].ground_m.x(), marks[i].ground_m.y(),
                  fit.residuals_px[i]);
    std::printf("reprojection_rms_px=%.3f\nreprojection_max_px=%.3f\n", fit.rms_px, fit.max_px);
    // Least squares spreads one bad mark's error over all: the marks left out in turn name it.
    const std::optional<kw::vision::DisagreeingMark> bad = kw::vision::findDisagreeingMark(intrinsics, marks);
    if (bad) {
      const Eigen::Vector3d with = fit.camera.centre(), without = bad->without.camera.centre();
      std::printf("disagreeing_mark=%d\ndisagreement_px=%.1f\nwithout_it_rms_px=%.3f\nwithout_it_camera_height_m=%.3f\n",
                  bad->index + 1, bad->disagreement_px, bad->without.rms_px, without.z());
      char text[640];
      std::snprintf(text, sizeof text,
                    "mark %d does not agree with the others: it is %.1f px from where the "
                    "other %zu marks put it. With it: rms %.1f px, the camera %.3f m up at (%.3f, %.3f); without it: "
                    "rms %.2f px, the camera %.3f m up at (%.3f, %.3f). Check its pixel and its ground position "
                    "(draw them with --check), or leave it out",
                    bad->index + 1, bad->disagreement_px, marks.size() - 1, fit.rms_px, with.z(),
                    with.x(), with.y(), bad->without.rms_px, without.z(), without.x(), without.y());
      std::fprintf(stderr, "calibrate_camera: %s\n", text);
    } else if (fit.max_px > 5) {
      std::fprintf(stderr,
                   "calibrate_camera: warning: a mark is %.1f px from where the calibration puts it; check its "
                   "pixel and its ground position (draw them with --check)\n",
                   fit.max_px);
    }
    if (fit.rms_px > accept_rms_px) {
      std::fprintf(stderr,
                   "calibrate_camera: the marks' reprojection rms is %.1f px, over --accept-rms %g: %s not written "
                   "(%s; --accept-rms %.0f writes it anyway)\n",
                   fit.rms_px, accept_rms_px, out_path.c_str(),
                   bad ? ("mark " + std::to_string(bad->index + 1) + " does not agree").c_str()
                       : "check the marks' pixels and ground positions",
                   std::ceil(fit.rms_px));
      return 1;
    }
    try {
      fit.camera.save(out_path, camera_unit_m);
    } catch (const std::exception& e) {
      throw std::runtime_error("--out " + out_path + ": " + e.what());
    }
    std::printf("wrote %s (t in units of %g m)\n", out_path.c_str(), camera_unit_m);
    camera = fit.camera;
  }
  const Eigen::Vector3d centre = camera->centre();
  std::printf("camera_position_m=%.3f,%.3f,%.3f\ncamera_height_m=%.3f\n", centre.x(), centre.y(), centre.z(),
              centre.z());
  if (!frame.empty()) {
    if (frame.cols != camera->width() || frame.rows != camera->height())
      throw std::runtime_error("--check " + check_path + ": the frame is " + std::to_string(frame.cols) + "x" +
                               std::to_string(frame.rows) + ", the calibration's image " +
                               std::to_string(camera->width()) + "x" + std::to_string(camera->height()));
    cv::Mat drawn = frame.clone();
    drawCheck(drawn, *camera, marks, people_xy, person_height_m);
    if (!cv::imwrite(check_out_path, drawn)) throw std::runtime_error("--check-out " + check_out_path + ": cannot write");
    std::printf("wrote %s\n", check_out_path.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return kneed_walker::tools::runTool("calibrate_camera", run, argc, argv); }
