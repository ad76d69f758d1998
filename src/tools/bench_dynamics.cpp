// bench_dynamics: how fast the Kneed Walker advances particles (issue: 5000 particles in
// real time). Advances a batch of walkers, spread along a walking gait, by one video frame
// (1/30 s by default), many times, and prints the median time per particle-frame on one
// thread and on all cores, plus the accuracy that the RK4 step buys.
//
//   rosrun kneed_walker bench_dynamics [--particles 5000] [--frames 30] [--fps 30]
//                                      [--repeats 7] [--max-step 0.02] [--seed 1]
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <vector>

#include "median.h"
#include "options.h"
#include "tool_main.h"
#include "kneed_walker/core/common/parallel.h"
#include "kneed_walker/core/optimizer/periodic_gait.h"

namespace kw = kneed_walker::core;
using kneed_walker::tools::median;

namespace {

// Walkers spread over one stride of McGeer's passive gait, scaled to the simulator's
// person (McGeer's proportions: the torso mass at the hip), each slightly perturbed.
std::vector<kw::dynamics::WalkerState> gaitBatch(const kw::dynamics::WalkerSimulator& sim,
                                       const kw::dynamics::WalkerControls& controls, int count,
                                       unsigned seed) {
  const kw::optimizer::PeriodicGait gait = kw::optimizer::mcGeerPassiveGait();
  const kw::dynamics::WalkerState start = kw::optimizer::fromDimensionless(gait.start, sim);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> phase(0, gait.stride.duration * sim.naturalTime());
  std::normal_distribution<double> noise(0, 0.01);
  std::vector<kw::dynamics::WalkerState> batch(count);
  for (auto& s : batch) {
    s = start;
    sim.advance(controls, s, phase(rng));
    for (int j = 0; j < kw::dynamics::kNumCoordinates; ++j) s.qdot[j] += noise(rng);
  }
  return batch;
}

}  // namespace

int run(int argc, char** argv) {
  CLI::App app{"Times the Kneed Walker dynamics on a batch of particles."};
  int particles = 5000, frames = 30, repeats = 7;
  double fps = 30, max_step = kw::dynamics::SimulationOptions{}.max_step;
  unsigned seed = 1;
  app.add_option("--particles", particles, "walkers in the batch")->check(CLI::Range(1, 1000000));
  app.add_option("--frames", frames, "frames advanced per repeat")->check(CLI::Range(1, 10000));
  app.add_option("--fps", fps, "frame rate: each frame advances 1/fps s")->check(kneed_walker::tools::FiniteRange(1.0, 1000.0));
  app.add_option("--repeats", repeats, "timed repeats; the median is reported")->check(CLI::Range(1, 1000));
  app.add_option("--max-step", max_step, "RK4 step, natural time units √(L/g)")->check(kneed_walker::tools::FiniteRange(1e-4, 0.2));
  app.add_option("--seed", seed, "random seed of the batch");
  CLI11_PARSE(app, argc, argv);

  const kw::dynamics::WalkerModel person = kw::dynamics::scaleToPerson(kw::dynamics::mcGeerProportions(), 1.75, 70);
  kw::dynamics::SimulationOptions options;
  options.max_step = max_step;
  const kw::dynamics::WalkerSimulator sim(person, options);
  kw::dynamics::WalkerControls controls;
  controls.ground_slope = kw::optimizer::kMcGeerSlope;
  const double frame_s = 1.0 / fps;
  const std::vector<kw::dynamics::WalkerState> initial = gaitBatch(sim, controls, particles, seed);

  auto timeRun = [&](int threads) {
    std::vector<double> per_particle_frame_us;
    for (int r = 0; r < repeats; ++r) {
      std::vector<kw::dynamics::WalkerState> batch = initial;
      for (int f = 0; f < frames; ++f) {
        const auto t0 = std::chrono::steady_clock::now();
        kw::common::parallelFor(particles, threads, [&](int begin, int end) {
          for (int i = begin; i < end; ++i) sim.advance(controls, batch[i], frame_s);
        });
        const double us =
            std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
        per_particle_frame_us.push_back(us / particles);
      }
    }
    return median(per_particle_frame_us);
  };

  // Accuracy: joint angles after `frames` frames against a 20x finer step.
  kw::dynamics::SimulationOptions fine_options = options;
  fine_options.max_step = max_step / 20;
  const kw::dynamics::WalkerSimulator fine(person, fine_options);
  double max_error = 0;
  for (int i = 0; i < std::min(particles, 200); ++i) {
    kw::dynamics::WalkerState a = initial[i], b = initial[i];
    for (int f = 0; f < frames; ++f) {
      sim.advance(controls, a, frame_s);
      fine.advance(controls, b, frame_s);
    }
    if (a.heel_strikes == b.heel_strikes && !a.fallen && !b.fallen)
      max_error = std::max(max_error, (a.q - b.q).lpNorm<Eigen::Infinity>());
  }

  const int cores = kw::common::resolveThreads(0);
  const double single = timeRun(1);
  const double all = timeRun(cores);
  std::printf("particles=%d frame_s=%.5f frames=%d repeats=%d max_step_natural=%g (%.2f ms)\n",
              particles, frame_s, frames, repeats, max_step, 1e3 * max_step * sim.naturalTime());
  std::printf("dynamics_us_per_particle_frame=%.3f\n", single);
  std::printf("dynamics_us_per_particle_frame_threads_%d=%.3f\n", cores, all);
  std::printf("batch_ms_per_frame=%.2f (1 thread) %.2f (%d threads); speed-up %.2f\n",
              single * particles / 1e3, all * particles / 1e3, cores, single / all);
  std::printf("max_angle_error_rad_vs_step_over_20=%.2e after %.2f s\n", max_error, frames * frame_s);
  return 0;
}

int main(int argc, char** argv) {
  return kneed_walker::tools::runTool("bench_dynamics", run, argc, argv);
}
