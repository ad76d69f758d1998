// compare_gait_norms: a table gait's sagittal joint angles over one gait cycle against the
// free-speed norms of Schwartz, Rozumalski & Trost (J. Biomech. 2008), with the RMS
// difference per joint, as numbers and as a plot.
//
//   rosrun kneed_walker compare_gait_norms --table config/gait_table.yaml
//          --norms ../shared/data/gait/Schwartz2008_Joint_Rotations.csv --out norms.png
//          [--speed 4.5] [--step 0.7] [--speed-class Free]
//
// The cycle runs from one heel strike of the left leg to the next (two steps). Angles, in the
// norms' conventions: trunk tilt = forward lean of the torso from the vertical; hip flexion =
// thigh against the torso; knee flexion = thigh against shank. The walker has no ankle joint.
#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <array>
#include <cmath>
#include <cstdio>

#include "kneed_walker/core/gait/gait_norms.h"
#include "kneed_walker/core/gait/gait_table.h"
#include "options.h"
#include "package_files.h"

namespace kw = kneed_walker::core;

namespace {

constexpr double kDegrees = 180.0 / M_PI;
const std::array<const char*, 3> kJoints = {"Trunk Ant/Posterior Tilt", "Hip Flex/Extension",
                                            "Knee Flex/Extension"};
const std::array<const char*, 3> kShortNames = {"trunk_tilt", "hip_flexion", "knee_flexion"};

// The left leg's joint angles (degrees) at a state, in the norms' conventions.
std::array<double, 3> leftLegAngles(const kw::dynamics::WalkerState& s, double slope) {
  const bool stance = s.stance_leg == kw::dynamics::Leg::kLeft;
  const double thigh = s.q[stance ? kw::dynamics::kStanceThigh : kw::dynamics::kSwingThigh];
  const double shank = s.q[stance ? kw::dynamics::kStanceShank : kw::dynamics::kSwingShank];
  const double torso_world = s.q[kw::dynamics::kTorso] + slope;  // from the vertical, CCW
  return {-torso_world * kDegrees, (thigh - s.q[kw::dynamics::kTorso]) * kDegrees, (thigh - shank) * kDegrees};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Compares a gait's joint angles with the Schwartz 2008 norms."};
  std::string table_path = kneed_walker::tools::packageFile("config/gait_table.yaml"), norms_path, out;
  std::string speed_class = "Free";
  double speed_kmh = 4.5, step_m = 0.7;
  app.add_option("--table", table_path, "gait table (YAML)")->check(CLI::ExistingFile)->capture_default_str();
  std::string walker_model = kneed_walker::tools::packageFile("config/walker_model.yaml");
  app.add_option("--walker-model", walker_model, "body proportions (YAML); the table must be made for them")
      ->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--norms", norms_path, "Schwartz2008_Joint_Rotations.csv")->required()->check(CLI::ExistingFile);
  app.add_option("--out", out, "plot to write (PNG)")->required();
  app.add_option("--speed", speed_kmh, "walking speed of the gait, km/h")->capture_default_str()
      ->check(kneed_walker::tools::FiniteRange(0.1, 20));
  app.add_option("--step", step_m, "step length of the gait, m")->capture_default_str()
      ->check(kneed_walker::tools::FiniteRange(0.1, 3));
  app.add_option("--speed-class", speed_class, "norms' speed class (Very Slow, Slow, Free, Fast, Very Fast)");
  CLI11_PARSE(app, argc, argv);

  try {
    const kw::gait::GaitNorms all_norms = kw::gait::loadGaitNorms(norms_path);
    const kw::gait::NormSpeedClass& norms = all_norms.speedClass(speed_class);
    const kw::gait::GaitTable table =
        kw::gait::loadGaitTable(table_path, kw::dynamics::loadBodyProportions(walker_model));
    kw::gait::InterpolationNote note;
    const kw::gait::Gait gait = kw::gait::interpolateGait(table, speed_kmh, step_m, 0.0, &note);
    if (!note.exact()) std::fprintf(stderr, "compare_gait_norms: %s\n", note.describe(table.grid).c_str());
    const kw::dynamics::WalkerSimulator sim(kw::dynamics::dimensionlessWalker(table.body));
    if (gait.start.stance_leg != kw::dynamics::Leg::kLeft) throw std::runtime_error("expected a left stance start");

    // Two steps from the left heel strike (their durations by the stride function), sampled at
    // the norms' cycle points by walking on from sample to sample.
    double cycle_time = 0;
    kw::dynamics::WalkerState s = gait.start;
    for (int step = 0; step < 2; ++step) {
      const kw::dynamics::StrideResult stride = sim.stride(gait.controls, s);
      if (!stride.completed) throw std::runtime_error("the gait falls within a cycle");
      cycle_time += stride.duration;
      s = stride.end;
    }
    const kw::gait::NormCurve& reference = norms.curve(kJoints[0]);
    std::vector<std::array<double, 3>> model(reference.cycle.size());
    s = gait.start;
    double walked = 0;
    for (size_t i = 0; i < reference.cycle.size(); ++i) {
      const double at = reference.cycle[i] * cycle_time;
      sim.advance(gait.controls, s, at - walked);
      walked = at;
      model[i] = leftLegAngles(s, 0.0);
    }

    // RMS per joint, and the plot: one panel per joint, norm band grey, model red.
    const int panel_w = 420, panel_h = 300, margin = 40;
    cv::Mat plot(panel_h + 2 * margin, 3 * panel_w + 4 * margin / 2, CV_8UC3, cv::Scalar(255, 255, 255));
    std::printf("gait %.1f km/h, %.2f m steps, level; cycle %.3f s (1.75 m person); norms '%s'\n",
                speed_kmh, step_m,
                cycle_time * std::sqrt(table.grid.referenceLegLength() / table.grid.gravity),
                speed_class.c_str());
    for (int j = 0; j < 3; ++j) {
      const kw::gait::NormCurve& n = norms.curve(kJoints[j]);
      double sum = 0, lo = 1e9, hi = -1e9, model_peak = -1e9, norm_peak = -1e9;
      for (size_t i = 0; i < n.cycle.size(); ++i) {
        const double d = model[i][j] - n.mean[i];
        sum += d * d;
        lo = std::min({lo, n.low[i], model[i][j]});
        hi = std::max({hi, n.high[i], model[i][j]});
        model_peak = std::max(model_peak, model[i][j]);
        norm_peak = std::max(norm_peak, n.mean[i]);
      }
      const double rms = std::sqrt(sum / n.cycle.size());
      std::printf("rms_deg_%s=%.1f\n", kShortNames[j], rms);
      // The largest value over the cycle (for the knee, the swing knee's peak flexion).
      std::printf("peak_deg_%s=%.1f (norms' mean %.1f)\n", kShortNames[j], model_peak, norm_peak);
      const cv::Point2d corner(margin / 2 + j * (panel_w + margin / 2), margin);
      auto px = [&](double cycle, double value) {
        return cv::Point(static_cast<int>(corner.x + cycle * panel_w),
                         static_cast<int>(corner.y + (hi - value) / (hi - lo + 1e-9) * panel_h));
      };
      std::vector<cv::Point> band;
      for (size_t i = 0; i < n.cycle.size(); ++i) band.push_back(px(n.cycle[i], n.high[i]));
      for (size_t i = n.cycle.size(); i-- > 0;) band.push_back(px(n.cycle[i], n.low[i]));
      cv::fillPoly(plot, std::vector<std::vector<cv::Point>>{band}, cv::Scalar(220, 220, 220));
      std::vector<cv::Point> mean_line, model_line;
      for (size_t i = 0; i < n.cycle.size(); ++i) {
        mean_line.push_back(px(n.cycle[i], n.mean[i]));
        model_line.push_back(px(n.cycle[i], model[i][j]));
      }
      cv::polylines(plot, mean_line, false, cv::Scalar(90, 90, 90), 2, cv::LINE_AA);
      cv::polylines(plot, model_line, false, cv::Scalar(40, 40, 210), 2, cv::LINE_AA);
      cv::rectangle(plot, px(0, hi), px(1, lo), cv::Scalar(0, 0, 0), 1);
      cv::putText(plot, cv::format("%s (deg): RMS %.1f", kShortNames[j], rms),
                  corner + cv::Point2d(0, -10), cv::FONT_HERSHEY_SIMPLEX, 0.55, {0, 0, 0}, 1, cv::LINE_AA);
      cv::putText(plot, cv::format("%.0f", hi), px(0, hi) + cv::Point(2, 14), cv::FONT_HERSHEY_SIMPLEX, 0.4, {0, 0, 0});
      cv::putText(plot, cv::format("%.0f", lo), px(0, lo) + cv::Point(2, -4), cv::FONT_HERSHEY_SIMPLEX, 0.4, {0, 0, 0});
    }
    cv::putText(plot, "grey: Schwartz 2008 mean +/- 1 sd; red: walker; x: gait cycle from left heel strike",
                {margin / 2, panel_h + margin + 28}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0}, 1, cv::LINE_AA);
    if (!cv::imwrite(out, plot)) throw std::runtime_error("cannot write " + out);
    std::printf("wrote %s\n", out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "compare_gait_norms: %s\n", e.what());
    return 1;
  }
  return 0;
}
