// draw_gaits: optimal gaits from the gait table as stick figures, like the paper's Fig. 2:
// one stride each uphill, on the level and downhill, stacked, for one speed and step length.
//
//   rosrun kneed_walker draw_gaits --table config/gait_table.yaml --out gaits.png
//          [--speed 4.5] [--step 0.7] [--snapshots 8]
#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>

#include "kneed_walker/core/gait/gait_table.h"
#include "kneed_walker/core/dynamics/walker_drawing.h"
#include "options.h"
#include "package_files.h"

namespace kw = kneed_walker::core;

int main(int argc, char** argv) {
  CLI::App app{"Draws optimal gaits uphill, level and downhill (the paper's Fig. 2)."};
  std::string table_path = kneed_walker::tools::packageFile("config/gait_table.yaml"), out;
  double speed_kmh = 4.5, step_m = 0.7;
  int snapshots = 8, width = 1200;
  app.add_option("--table", table_path, "gait table (YAML)")->check(CLI::ExistingFile)->capture_default_str();
  std::string walker_model = kneed_walker::tools::packageFile("config/walker_model.yaml");
  app.add_option("--walker-model", walker_model, "body proportions (YAML); the table must be made for them")
      ->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--out", out, "PNG to write")->required();
  app.add_option("--speed", speed_kmh, "walking speed, km/h")->capture_default_str()
      ->check(kneed_walker::tools::FiniteRange(0.1, 20));
  app.add_option("--step", step_m, "step length, m")->capture_default_str()->check(kneed_walker::tools::FiniteRange(0.1, 3));
  app.add_option("--snapshots", snapshots, "stick figures per stride")->check(CLI::Range(2, 50));
  app.add_option("--width", width, "image width, px")->check(CLI::Range(300, 8000));
  CLI11_PARSE(app, argc, argv);

  try {
    const kw::gait::GaitTable table =
        kw::gait::loadGaitTable(table_path, kw::dynamics::loadBodyProportions(walker_model));
    const kw::dynamics::WalkerSimulator sim(kw::dynamics::dimensionlessWalker(table.body));
    const double slope = table.grid.slopes_rad.back();
    const double slopes[3] = {slope, 0.0, -slope};
    const char* names[3] = {"uphill", "level", "downhill"};
    const double pixels_per_leg = (width - 80) / 2.6;  // a stride and a body width per row
    const int row_height = static_cast<int>(pixels_per_leg * 2.2);
    cv::Mat figure(3 * row_height, width, CV_8UC3, cv::Scalar(255, 255, 255));
    for (int row = 0; row < 3; ++row) {
      kw::gait::InterpolationNote note;
      const kw::gait::Gait gait = kw::gait::interpolateGait(table, speed_kmh, step_m, slopes[row], &note);
      if (!note.exact()) std::fprintf(stderr, "draw_gaits: %s: %s\n", names[row], note.describe(table.grid).c_str());
      kw::dynamics::SideView view;
      view.ground_slope = slopes[row];
      view.pixels_per_unit = pixels_per_leg;
      view.origin_px = {40 + 0.6 * pixels_per_leg, (row + 1) * row_height - 0.25 * pixels_per_leg};
      kw::dynamics::drawGround(figure, view);
      const kw::dynamics::StrideResult stride = sim.stride(gait.controls, gait.start);
      kw::dynamics::drawStrip(figure, sim, gait.controls, gait.start, stride.duration, snapshots, view);
      cv::putText(figure,
                  cv::format("%s %.1f deg: %.1f km/h, %.2f m steps (1.75 m person); stride %s",
                             names[row], slopes[row] * 180 / M_PI, speed_kmh, step_m,
                             stride.completed ? "periodic" : "FELL"),
                  {20, row * row_height + 30}, cv::FONT_HERSHEY_SIMPLEX, 0.7, {0, 0, 0}, 2,
                  cv::LINE_AA);
    }
    if (!cv::imwrite(out, figure)) throw std::runtime_error("cannot write " + out);
    std::printf("wrote %s\n", out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "draw_gaits: %s\n", e.what());
    return 1;
  }
  return 0;
}
