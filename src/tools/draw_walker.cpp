// draw_walker: pictures of the Kneed Walker walking, for people to see the dynamics.
// Simulates McGeer's passive walker scaled to a person (torso mass at the hip) walking its
// periodic gait down 0.0456 rad (the optimal gaits will replace it), and writes a
// stroboscopic strip of stick figures as a PNG and, optionally, an animation.
//
//   rosrun kneed_walker draw_walker --out walker_strip.png [--video walker.avi]
//          [--strides 3] [--snapshots 10] [--height 1.75] [--mass 70]
#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cstdio>
#include <filesystem>

#include "kneed_walker/core/optimizer/periodic_gait.h"
#include "options.h"
#include "tool_main.h"
#include "kneed_walker/core/dynamics/walker_drawing.h"

namespace kw = kneed_walker::core;

int run(int argc, char** argv) {
  CLI::App app{"Draws the Kneed Walker walking: a PNG strip and optionally an animation."};
  std::string out, video;
  int strides = 3, snapshots = 10, width = 1400, fps = 30;
  double height_m = 1.75, mass_kg = 70;
  app.add_option("--out", out, "PNG strip to write")->required();
  app.add_option("--video", video, "animation to write (.avi, MJPG), one frame per 1/fps s");
  app.add_option("--strides", strides, "strides to simulate")->check(CLI::Range(1, 20));
  app.add_option("--snapshots", snapshots, "stick figures in the strip")->check(CLI::Range(2, 200));
  app.add_option("--width", width, "image width, px")->check(CLI::Range(200, 8000));
  app.add_option("--fps", fps, "animation frame rate")->check(CLI::Range(1, 240));
  app.add_option("--height", height_m, "person's height, m")->check(kneed_walker::tools::FiniteRange(1.0, 2.3));
  app.add_option("--mass", mass_kg, "person's mass, kg")->check(kneed_walker::tools::FiniteRange(20.0, 250.0));
  CLI11_PARSE(app, argc, argv);
  // Refuse outputs OpenCV cannot write before any work.
  if (!cv::haveImageWriter(out)) {
    std::fprintf(stderr, "draw_walker: --out %s: not an image file name OpenCV can write (.png, .jpg, ...)\n",
                 out.c_str());
    return 1;
  }
  if (!video.empty() && std::filesystem::path(video).extension() != ".avi") {
    std::fprintf(stderr, "draw_walker: --video %s: the animation is written as MJPG in an .avi file\n",
                 video.c_str());
    return 1;
  }

  const kw::dynamics::WalkerSimulator sim(kw::dynamics::scaleToPerson(kw::dynamics::mcGeerProportions(), height_m, mass_kg));
  kw::dynamics::WalkerControls controls;
  controls.ground_slope = kw::optimizer::kMcGeerSlope;
  const kw::optimizer::PeriodicGait gait = kw::optimizer::mcGeerPassiveGait();
  if (!gait.converged) {
    std::fprintf(stderr, "draw_walker: the passive gait was not found (residual %g)\n", gait.residual);
    return 1;
  }
  const kw::dynamics::WalkerState start = kw::optimizer::fromDimensionless(gait.start, sim);
  const double stride_s = gait.stride.duration * sim.naturalTime();
  const double total_s = strides * stride_s;
  const double distance = strides * gait.stride.step_length * sim.model().legLength();

  kw::dynamics::SideView view;
  view.ground_slope = controls.ground_slope;
  view.pixels_per_unit = (width - 80) / (distance + 1.0);
  const int image_height = static_cast<int>(view.pixels_per_unit * (height_m + 0.4)) + 40;
  view.origin_px = {40 + 0.5 * view.pixels_per_unit, image_height - 20.0};
  cv::Mat strip(image_height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  kw::dynamics::drawGround(strip, view);

  cv::VideoWriter writer;
  if (!video.empty()) {
    writer.open(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, strip.size());
    if (!writer.isOpened()) {
      std::fprintf(stderr, "draw_walker: cannot write %s\n", video.c_str());
      return 1;
    }
  }

  const kw::dynamics::WalkerState end = kw::dynamics::drawStrip(strip, sim, controls, start, total_s, snapshots, view);
  if (writer.isOpened()) {
    kw::dynamics::WalkerState state = start;
    for (int f = 0; f <= static_cast<int>(total_s * fps) && !state.fallen; ++f) {
      cv::Mat frame(strip.size(), CV_8UC3, cv::Scalar(255, 255, 255));
      kw::dynamics::drawGround(frame, view);
      kw::dynamics::drawWalker(frame, sim, state, view);
      cv::putText(frame, cv::format("t = %.2f s", static_cast<double>(f) / fps), {20, 30},
                  cv::FONT_HERSHEY_SIMPLEX, 0.8, {0, 0, 0}, 2, cv::LINE_AA);
      writer.write(frame);
      sim.advance(controls, state, 1.0 / fps);
    }
  }
  cv::putText(strip,
              cv::format("McGeer passive gait, %.2f m person, slope %.4f rad: step %.2f m, %.2f s",
                         height_m, controls.ground_slope,
                         gait.stride.step_length * sim.model().legLength(), stride_s),
              {20, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.7, {0, 0, 0}, 2, cv::LINE_AA);
  if (!cv::imwrite(out, strip)) {
    std::fprintf(stderr, "draw_walker: cannot write %s\n", out.c_str());
    return 1;
  }
  std::printf("wrote %s (%d stick figures over %d strides, %.2f s)%s%s\n", out.c_str(), snapshots,
              strides, total_s, video.empty() ? "" : " and ", video.c_str());
  return end.fallen ? 1 : 0;
}

int main(int argc, char** argv) {
  return kneed_walker::tools::runTool("draw_walker", run, argc, argv);
}
