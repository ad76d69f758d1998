// sample_prior: how often the stochastic prior (paper §3.4) keeps walking. Samples particles
// on a table gait just after a heel strike, runs the prior's transition frame by frame, and
// counts heel strikes and falls until `--strides` strides have ended either way. With
// `--chain 1` every stride starts from the gait; with `--chain N` a particle walks on for N
// strides, so that errors can build up from stride to stride. With `--end-speed` and/or
// `--end-step` the gait changes along each chain, stride by stride, linearly from the start's to
// the end's (a person slowing down or speeding up: issue 13's 7 -> 3 km/h profile). With
// `--every-gait` it samples every feasible gait of the table instead (`--strides` each) and
// counts, per slope and on the paper's grid, the gaits whose strides walk at least
// `--min-fraction` of the time: the grid points the prior can use.
//
//   rosrun kneed_walker sample_prior --table config/prior_gait_table.yaml --prior config/prior.yaml
//          [--speed 4.5] [--step 0.7] [--slope 0] [--end-speed V] [--end-step L] [--strides 1000]
//          [--chain 1] [--fps 30] [--seed 1] [--noise-scale 1]
//   rosrun kneed_walker sample_prior --every-gait [--strides 300] [--chain 1] [--min-fraction 0.99] [--threads 0]
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <stdexcept>
#include <vector>

#include "kneed_walker/core/gait/gait_table.h"
#include "kneed_walker/core/prior/walker_prior.h"
#include "options.h"
#include "package_files.h"

namespace kw = kneed_walker::core;

// With a change of gait, one prior per stride of a chain is built and held (about 10 kB each).
constexpr int kMaxChangingChain = 1000;

// --every-gait: per slope, how many of the table's feasible gaits keep walking.
int everyGait(const kw::gait::GaitTable& table, const kw::prior::PriorOptions& options, int strides, int chain,
              double fps, unsigned seed, int threads, double min_fraction) {
  const kw::gait::GaitGrid& grid = table.grid;
  const kw::dynamics::WalkerSimulator sim(kw::dynamics::dimensionlessWalker(table.body));
  const double dt = (1.0 / fps) / std::sqrt(grid.referenceLegLength() / grid.gravity);
  const auto fractions = kw::prior::tableWalkingFractions(table, sim, options, strides, chain, dt, seed, threads);
  const kw::gait::GaitGrid paper = kw::gait::GaitGrid::paper();
  auto member = [](const std::vector<double>& axis, double value) {
    return std::any_of(axis.begin(), axis.end(), [&](double a) { return std::abs(a - value) < 1e-9; });
  };
  struct Count { int points = 0, feasible = 0, walking = 0, paper_points = 0, paper_walking = 0; };
  std::map<int, Count> per_slope;
  for (int i = 0; i < grid.size(); ++i) {
    const auto cell = grid.cell(i);
    Count& c = per_slope[cell[2]];
    const bool on_paper = member(paper.speeds_kmh, grid.speeds_kmh[cell[0]]) &&
                          member(paper.step_lengths_m, grid.step_lengths_m[cell[1]]) &&
                          member(paper.slopes_rad, grid.slopes_rad[cell[2]]);
    const auto& f = fractions[i];
    const bool walks = f && (chain > 1 ? f->chainFraction() : f->fraction()) >= min_fraction;
    ++c.points;
    c.feasible += table.entries[i].feasible;
    c.walking += walks;
    c.paper_points += on_paper;
    c.paper_walking += on_paper && walks;
  }
  std::printf("every feasible gait: %d strides each in chains of %d at %.0f fps, seed %u; a gait walks when %s >= %g\n",
              strides, chain, fps, seed, chain > 1 ? "the fraction of whole chains" : "the fraction of strides",
              min_fraction);
  Count total;
  for (const auto& [slope, c] : per_slope) {
    std::printf("slope %+6.2f deg: %d of %d feasible gaits walk (%d grid points)", grid.slopes_rad[slope] * 180 / M_PI,
                c.walking, c.feasible, c.points);
    if (c.paper_points > 0) std::printf("; on the paper's grid %d of %d points", c.paper_walking, c.paper_points);
    std::printf("\n");
    total.points += c.points, total.feasible += c.feasible, total.walking += c.walking;
    total.paper_points += c.paper_points, total.paper_walking += c.paper_walking;
  }
  std::printf("walking_gaits=%d (of %d feasible, %d grid points)\n", total.walking, total.feasible, total.points);
  std::printf("walking_paper_grid_points=%d (of %d)\n", total.paper_walking, total.paper_points);
  return 0;
}

int main(int argc, char** argv) {
  CLI::App app{"Measures how often the walking prior's sampled strides keep walking."};
  std::string table_path = kneed_walker::tools::packageFile("config/prior_gait_table.yaml");
  std::string prior_path = kneed_walker::tools::packageFile("config/prior.yaml");
  double speed_kmh = 4.5, step_m = 0.7, slope = 0.0, fps = 30, noise_scale = 1.0;
  double end_speed_kmh = 0, end_step_m = 0;  // 0: as at the start
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
  app.add_option("--end-speed", end_speed_kmh, "with --chain N >= 2: the gait speed of a chain's last stride, km/h; "
                 "the speed changes linearly from --speed over the chain's strides (default: --speed)")
      ->check(kneed_walker::tools::FiniteRange(0.1, 20));
  app.add_option("--end-step", end_step_m, "with --chain N >= 2: the step length of a chain's last stride, m "
                 "(default: --step)")->check(kneed_walker::tools::FiniteRange(0.1, 3));
  app.add_option("--strides", strides, "strides to sample")->check(CLI::Range(1, 1000000));
  app.add_option("--chain", chain, "strides a particle walks on before a fresh one starts")->check(CLI::Range(1, 1000000));
  app.add_option("--fps", fps, "frame rate of the transitions, for the reference person")->check(kneed_walker::tools::FiniteRange(1.0, 1000.0));
  app.add_option("--seed", seed, "random seed");
  app.add_option("--noise-scale", noise_scale, "factor on the torque noise scales s_j of eq. 11")->check(kneed_walker::tools::FiniteRange(0.0, 100.0));
  bool every_gait = false;
  double min_fraction = 0.99;
  int threads = 0;
  auto* every = app.add_flag("--every-gait", every_gait,
                             "sample every feasible gait of the table (--strides each) and count those that walk");
  app.add_option("--min-fraction", min_fraction, "with --every-gait: the walking fraction (of strides, or with --chain "
                 "N >= 2 of whole chains) a gait must reach to count")->check(kneed_walker::tools::FiniteRange(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--threads", threads, "with --every-gait: worker threads; 0 = all cores")->check(CLI::Range(0, 256));
  for (const char* excluded : {"--speed", "--step", "--slope", "--end-speed", "--end-step"})
    every->excludes(app.get_option(excluded));
  CLI11_PARSE(app, argc, argv);
  const bool changing = end_speed_kmh > 0 || end_step_m > 0;
  if (changing && (chain < 2 || chain > kMaxChangingChain)) {
    std::fprintf(stderr, "sample_prior: --end-speed and --end-step change the gait along a chain, a prior per stride: "
                 "give --chain from 2 to %d\n", kMaxChangingChain);
    return 2;
  }
  if (end_speed_kmh <= 0) end_speed_kmh = speed_kmh;
  if (end_step_m <= 0) end_step_m = step_m;
  try {
    const kw::gait::GaitTable table =
        kw::gait::loadGaitTable(table_path, kw::dynamics::loadBodyProportions(walker_model));
    const kw::dynamics::WalkerSimulator sim(kw::dynamics::dimensionlessWalker(table.body));
    kw::prior::PriorOptions options = kw::prior::loadPriorOptions(prior_path);
    kw::prior::requirePriorTable(table, options);
    for (double& s : options.noise_scale) s *= noise_scale;
    if (every_gait) return everyGait(table, options, strides, chain, fps, seed, threads, min_fraction);
    // One prior per stride of a chain: the gait at its place along the speed and step change.
    std::vector<kw::prior::WalkerPrior> stride_priors;
    std::set<std::string> notes;
    if (changing) {  // the change's end inside the table, said in the options' terms before the strides
      try {
        kw::gait::interpolateGait(table, end_speed_kmh, end_step_m, slope);
      } catch (const std::out_of_range& e) {
        std::fprintf(stderr, "sample_prior: --end-speed %g / --end-step %g: %s\n", end_speed_kmh, end_step_m, e.what());
        return 2;
      }
    }
    for (int k = 0, n = changing ? chain : 1; k < n; ++k) {
      const double f = n > 1 ? static_cast<double>(k) / (n - 1) : 0.0;
      kw::gait::InterpolationNote note;
      stride_priors.emplace_back(sim,
                                 kw::prior::priorGait(table, sim, (1 - f) * speed_kmh + f * end_speed_kmh,
                                                      (1 - f) * step_m + f * end_step_m, slope, &note),
                                 options);
      if (!note.exact()) notes.insert(note.describe(table.grid));
    }
    for (const std::string& note : notes) std::fprintf(stderr, "sample_prior: %s\n", note.c_str());
    kw::common::Random random(seed);
    const double dt = (1.0 / fps) / std::sqrt(table.grid.referenceLegLength() / table.grid.gravity);
    const kw::prior::WalkingFraction count = kw::prior::sampleStrides(stride_priors, strides, chain, dt, random);
    if (changing)
      std::printf("gait %.1f to %.1f km/h, %.2f to %.2f m, slope %.3f rad; %d strides in chains of %d at %.0f fps, "
                  "noise x%g, seed %u\n",
                  speed_kmh, end_speed_kmh, step_m, end_step_m, slope, count.walked + count.fell, chain, fps,
                  noise_scale, seed);
    else
      std::printf("gait %.1f km/h, %.2f m, slope %.3f rad; %d strides in chains of %d at %.0f fps, noise x%g, seed %u\n",
                  speed_kmh, step_m, slope, count.walked + count.fell, chain, fps, noise_scale, seed);
    std::printf("walking_fraction=%.4f (%d strides ended in a heel strike, %d in a fall)\n",
                count.fraction(), count.walked, count.fell);
    std::printf("chains_walked_fraction=%.4f (%d chains of %d strides walked to the end, %d fell)\n",
                count.chainFraction(), count.chains_walked, chain, count.chains_fell);
    std::printf("pulling_landing_falls=%d (of the %d falls, at a heel strike that needed the ground to pull)\n",
                count.pulling, count.fell);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sample_prior: %s\n", e.what());
    return 1;
  }
  return 0;
}
