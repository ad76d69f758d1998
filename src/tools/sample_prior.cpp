// sample_prior: how often the stochastic prior (paper §3.4) keeps walking. Samples particles
// on a table gait just after a heel strike, runs the prior's transition frame by frame, and
// counts heel strikes and falls until `--strides` strides have ended either way. With
// `--chain 1` every stride starts from the gait; with `--chain N` a particle walks on for N
// strides, so that errors can build up from stride to stride.
//
//   rosrun kneed_walker sample_prior --table config/prior_gait_table.yaml --prior config/prior.yaml
//          [--speed 4.5] [--step 0.7] [--slope 0] [--strides 1000] [--chain 1] [--fps 30]
//          [--seed 1] [--noise-scale 1]
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>

#include "kneed_walker/core/gait/gait_table.h"
#include "kneed_walker/core/prior/walker_prior.h"
#include "options.h"
#include "package_files.h"

namespace kw = kneed_walker::core;

int main(int argc, char** argv) {
  CLI::App app{"Measures how often the walking prior's sampled strides keep walking."};
  std::string table_path = kneed_walker::tools::packageFile("config/prior_gait_table.yaml");
  std::string prior_path = kneed_walker::tools::packageFile("config/prior.yaml");
  double speed_kmh = 4.5, step_m = 0.7, slope = 0.0, fps = 30, noise_scale = 1.0;
  int strides = 1000, chain = 1;
  unsigned seed = 1;
  app.add_option("--table", table_path, "gait table (YAML)")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--prior", prior_path, "prior parameters (YAML)")->check(CLI::ExistingFile)->capture_default_str();
  std::string walker_model = kneed_walker::tools::packageFile("config/walker_model.yaml");
  app.add_option("--walker-model", walker_model, "body proportions (YAML); the table must be made for them")
      ->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--speed", speed_kmh, "gait speed, km/h")->check(kneed_walker::tools::FiniteRange(0.1, 20));
  app.add_option("--step", step_m, "gait step length, m")->check(kneed_walker::tools::FiniteRange(0.1, 3));
  app.add_option("--slope", slope, "ground slope, rad")->check(kneed_walker::tools::FiniteRange(-0.5, 0.5));
  app.add_option("--strides", strides, "strides to sample")->check(CLI::Range(1, 1000000));
  app.add_option("--chain", chain, "strides a particle walks on before a fresh one starts")->check(CLI::Range(1, 1000000));
  app.add_option("--fps", fps, "frame rate of the transitions, for the reference person")->check(kneed_walker::tools::FiniteRange(1.0, 1000.0));
  app.add_option("--seed", seed, "random seed");
  app.add_option("--noise-scale", noise_scale, "factor on the torque noise scales s_j of eq. 11")->check(kneed_walker::tools::FiniteRange(0.0, 100.0));
  CLI11_PARSE(app, argc, argv);
  try {
    const kw::gait::GaitTable table =
        kw::gait::loadGaitTable(table_path, kw::dynamics::loadBodyProportions(walker_model));
    const kw::dynamics::WalkerSimulator sim(kw::dynamics::dimensionlessWalker(table.body));
    kw::gait::InterpolationNote note;
    kw::gait::Gait gait = kw::gait::interpolateGait(table, speed_kmh, step_m, slope, &note);
    if (!note.exact()) std::fprintf(stderr, "sample_prior: %s\n", note.describe(table.grid).c_str());
    gait.stride_duration = sim.stride(gait.controls, gait.start).duration;
    kw::prior::PriorOptions options = kw::prior::loadPriorOptions(prior_path);
    kw::prior::requirePriorTable(table, options);
    for (double& s : options.noise_scale) s *= noise_scale;
    const kw::prior::WalkerPrior prior(sim, gait, options);
    kw::common::Random random(seed);
    const double dt = (1.0 / fps) / std::sqrt(table.grid.referenceLegLength() / table.grid.gravity);
    const kw::prior::WalkingFraction count = kw::prior::sampleStrides(prior, strides, chain, dt, random);
    std::printf("gait %.1f km/h, %.2f m, slope %.3f rad; %d strides in chains of %d at %.0f fps, noise x%g, seed %u\n",
                speed_kmh, step_m, slope, count.walked + count.fell, chain, fps, noise_scale, seed);
    std::printf("walking_fraction=%.4f (%d strides ended in a heel strike, %d in a fall)\n",
                count.fraction(), count.walked, count.fell);
    std::printf("pulling_landing_falls=%d (of the %d falls, at a heel strike that needed the ground to pull)\n",
                count.pulling, count.fell);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sample_prior: %s\n", e.what());
    return 1;
  }
  return 0;
}
