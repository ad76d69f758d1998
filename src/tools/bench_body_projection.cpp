// bench_body_projection: how fast a particle's walker state becomes image regions (the
// likelihood's per-particle front end): the 3D body pose (bodyPose) and the outlines of its
// parts in the image (projectBodyParts), for a batch of walking poses seen by a calibrated
// camera. Prints the median time per particle on one thread and on all cores.
//
//   rosrun kneed_walker bench_body_projection --camera ../shared/data/pets2009/View_001_camera.yml
//          [--table config/prior_gait_table.yaml] [--prior config/prior.yaml]
//          [--walker-model config/walker_model.yaml] [--particles 5000] [--repeats 15]
// (the config files default to the package's).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "median.h"
#include "kneed_walker/core/common/parallel.h"
#include "kneed_walker/core/vision/body_projection.h"
#include "kneed_walker/core/synthetic/synthetic_walk.h"
#include "options.h"
#include "package_files.h"
#include "camera_file.h"

namespace kw = kneed_walker::core;
using kneed_walker::tools::median;

int main(int argc, char** argv) {
  CLI::App app{"Times body pose + part projection per particle."};
  std::string camera_path;
  std::string table_path = kneed_walker::tools::packageFile("config/prior_gait_table.yaml");
  std::string prior_path = kneed_walker::tools::packageFile("config/prior.yaml");
  std::string walker_model = kneed_walker::tools::packageFile("config/walker_model.yaml");
  double camera_unit_m = 0.001;
  int particles = 5000, repeats = 15;
  app.add_option("--camera", camera_path, "calibration (OpenCV YAML)")->required()->check(CLI::ExistingFile);
  app.add_option("--camera-unit", camera_unit_m, "metres per unit of the calibration's t")->capture_default_str()
      ->check(kneed_walker::tools::FiniteRange(1e-6, 1e3));
  app.add_option("--table", table_path, "the prior's gait table")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--prior", prior_path, "prior parameters")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--walker-model", walker_model, "body proportions; the table must be made for them")
      ->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--particles", particles, "poses in the batch")->check(CLI::Range(1, 1000000));
  app.add_option("--repeats", repeats, "timed repeats; the median is reported")->check(CLI::Range(1, 1000));
  CLI11_PARSE(app, argc, argv);
  try {
    const kw::vision::Camera camera = kneed_walker::tools::loadCamera("bench_body_projection", camera_path, camera_unit_m);
    // Walking states and placements from a long synthetic walk in view of the camera.
    kw::synthetic::SyntheticWalkOptions walk_options;
    walk_options.start_m = camera.groundPoint({0.5 * camera.width(), 0.75 * camera.height()})->head<2>();
    walk_options.duration_s = 10;
    walk_options.fps = 30;
    const kw::gait::GaitTable table =
        kw::gait::loadGaitTable(table_path, kw::dynamics::loadBodyProportions(walker_model));
    const kw::synthetic::SyntheticWalk walk =
        kw::synthetic::synthesizeWalk(table, kw::prior::loadPriorOptions(prior_path), walk_options);
    const kw::dynamics::WalkerSimulator sim(kw::dynamics::dimensionlessWalker(table.body));
    const kw::body::BodyShape shape = kw::body::BodyShape::forHeight(walk_options.person_height_m);
    std::vector<const kw::synthetic::SyntheticFrame*> batch(particles);
    for (int i = 0; i < particles; ++i) batch[i] = &walk.frames[i % walk.frames.size()];
    std::vector<kw::vision::BodyOutlines> outlines(particles);

    auto project = [&](int begin, int end) {
      for (int i = begin; i < end; ++i) {
        const kw::body::BodyPose pose = kw::body::bodyPose(sim.map(), batch[i]->walker, walk_options.slope_rad,
                                               batch[i]->placement, shape, walk.leg_length_m);
        kw::vision::projectBodyParts(camera, pose, shape, outlines[i]);
      }
    };
    auto time = [&](int threads) {
      std::vector<double> us;
      for (int r = 0; r < repeats; ++r) {
        const auto start = std::chrono::steady_clock::now();
        kw::common::parallelFor(particles, threads, project);
        us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count() /
                     particles);
      }
      return median(us);
    };
    const int cores = kw::common::resolveThreads(0);
    const double one = time(1), all = time(cores);
    int visible = 0;
    for (const auto& o : outlines) visible += o[kw::body::kTorsoPart].visible;
    std::printf("%d particles, %d repeats; %d of them with the torso in view\n", particles, repeats, visible);
    std::printf("body_projection_us_per_particle=%.2f (1 thread)\n", one);
    std::printf("body_projection_us_per_particle=%.2f (%d threads)\n", all, cores);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_body_projection: %s\n", e.what());
    return 1;
  }
  return 0;
}
