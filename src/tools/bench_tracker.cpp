// bench_tracker: how fast the tracker runs. Renders a synthetic walk in memory (the prior's
// walker over a textured ground seen by the given camera, 768×576 for the PETS calibration,
// `--fps` frames per second, starting on the ground under `--start-pixel`: the person's image
// height there is printed as person_px=, since the likelihood's cost grows with the rows a body
// covers), learns its background, then tracks it from a coarse start with
// `--particles` particles on 1 thread and on all cores, held to the person's ground track as a
// session holds them (person/ground_track.h, updated each frame). Prints medians over the
// tracked frames:
//   tracker_ms_per_frame=       wall time per frame, the ground track's update included
//   ground_track_ms=            of which the ground track's update (per person, not per particle)
//   per_frame_precompute_ms=    the frame's shared evidence (ratio maps, prefix sums, flow)
//   dynamics_ms= likelihood_ms= thread time per frame in the prior's transitions and in pose +
//                               projection + likelihood, summed over threads
//   resample_ms=                wall time of resampling (with its re-propagation), per frame
//   likelihood_us_per_particle= dynamics_us_per_particle=  per particle step
//   resampled_frames=           frames that resampled, of those tracked: each costs Δs more
//                               propagations (the paper's resampling from t − Δs); mean_ms= is
//                               the mean wall time per frame, resampling frames included, and
//                               p95_ms= its 95th percentile
//   start_ms=                   wall time of the first frame's search (initial_oversampling × N
//                               candidates drawn and weighed)
//
//   rosrun kneed_walker bench_tracker --camera ../shared/data/pets2009/View_001_camera.yml
//          [--particles 5000] [--frames 40] [--fps 30] [--start-pixel X Y]
//   (a robot's camera with a person ~200 px tall: --camera test/sequences/robot_eye_camera.yml
//    --start-pixel 330 330)
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <numeric>
#include <vector>

#include "kneed_walker/core/common/parallel.h"
#include "kneed_walker/core/person/ground_track.h"
#include "kneed_walker/core/synthetic/synthetic_scene.h"
#include "kneed_walker/core/tracking/tracker.h"
#include "median.h"
#include "options.h"
#include "package_files.h"
#include "camera_file.h"

namespace kw = kneed_walker::core;
using kneed_walker::tools::FiniteRange;
using kneed_walker::tools::median;
using kneed_walker::tools::percentile;

int main(int argc, char** argv) {
  CLI::App app{"Times the tracker per frame, split by stage."};
  std::string camera_path;
  std::string table_path = kneed_walker::tools::packageFile("config/prior_gait_table.yaml");
  std::string prior_path = kneed_walker::tools::packageFile("config/prior.yaml");
  std::string walker_model = kneed_walker::tools::packageFile("config/walker_model.yaml");
  double camera_unit_m = 0.001, fps = 30;
  int particles = 5000, frames = 40;
  app.add_option("--camera", camera_path, "calibration (OpenCV YAML)")->required()->check(CLI::ExistingFile);
  app.add_option("--camera-unit", camera_unit_m, "metres per unit of the calibration's t")->capture_default_str()
      ->check(FiniteRange(1e-6, 1e3));
  app.add_option("--particles", particles, "particles")->capture_default_str()->check(CLI::Range(10, 1000000));
  app.add_option("--frames", frames, "frames tracked per run")->capture_default_str()->check(CLI::Range(3, 10000));
  app.add_option("--fps", fps, "frame rate of the walk")->capture_default_str()->check(FiniteRange(1.0, 240.0));
  app.add_option("--table", table_path, "the prior's gait table")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--prior", prior_path, "prior parameters")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--walker-model", walker_model, "body proportions")->check(CLI::ExistingFile)->capture_default_str();
  std::vector<double> start_px;
  app.add_option("--start-pixel", start_px, "the image point over the walk's start on the ground, px (default: 70 % "
                 "across, 80 % down)")->expected(2)->check(FiniteRange(0, 1e5));
  CLI11_PARSE(app, argc, argv);
  try {
    const kw::vision::Camera camera = kneed_walker::tools::loadCamera("bench_tracker", camera_path, camera_unit_m);
    const kw::gait::GaitTable table = kw::gait::loadGaitTable(table_path, kw::dynamics::loadBodyProportions(walker_model));
    const kw::prior::PriorOptions prior = kw::prior::loadPriorOptions(prior_path);
    kw::synthetic::SyntheticWalkOptions walk_options;
    const Eigen::Vector2d start_pixel = start_px.empty() ? Eigen::Vector2d(0.7 * camera.width(), 0.8 * camera.height())
                                                         : Eigen::Vector2d(start_px[0], start_px[1]);
    const auto start = camera.groundPoint(start_pixel);
    if (!start) {
      char text[128];
      std::snprintf(text, sizeof text, "--start-pixel %g %g: the camera does not see the ground there", start_pixel.x(),
                    start_pixel.y());
      throw std::runtime_error(text);
    }
    walk_options.start_m = start->head<2>();
    walk_options.heading_rad = 2.1;
    walk_options.fps = fps;
    walk_options.duration_s = frames / fps;
    const kw::synthetic::SyntheticWalk walk = kw::synthetic::synthesizeWalk(table, prior, walk_options);
    const cv::Mat ground = kw::synthetic::texturedGround(camera, walk.ground, 1);
    std::vector<cv::Mat> empty, images;
    for (int i = 0; i < 5; ++i) {
      empty.push_back(ground.clone());
      kw::synthetic::addSensorNoise(empty.back(), 3.0, 10 + i);
    }
    const kw::body::BodyShape shape = kw::body::BodyShape::forHeight(walk_options.person_height_m);
    for (size_t i = 0; i < walk.frames.size(); ++i) {
      images.push_back(ground.clone());
      kw::synthetic::drawPerson(images.back(), camera, walk.frames[i].pose, shape, kw::synthetic::PersonAppearance{});
      kw::synthetic::addSensorNoise(images.back(), 3.0, 100 + i);
    }
    const kw::vision::BackgroundModel background = kw::vision::BackgroundModel::learn(empty);
    kw::tracking::InitialGuess guess;
    guess.position_m = walk_options.start_m;
    guess.heading_rad = walk_options.heading_rad;
    guess.stance_leg = walk.frames[0].walker.stance_leg;

    double top_px = 1e9, bottom_px = -1e9;  // the person's first pose, head to feet
    for (const Eigen::Vector3d& joint : walk.frames[0].pose.joints)
      if (const auto px = camera.project(joint)) top_px = std::min(top_px, px->y()), bottom_px = std::max(bottom_px, px->y());
    std::printf("%d particles, %zu frames of %dx%d at %.0f fps, person_px=%.0f (head centre to ankles)\n", particles,
                images.size(), camera.width(), camera.height(), fps, bottom_px - top_px);
    const int cores = kw::common::resolveThreads(0);
    for (int threads : {1, cores}) {
      kw::tracking::TrackerOptions options;
      options.filter.num_particles = particles;
      options.filter.num_threads = threads;
      kw::tracking::Tracker tracker(camera, walk.ground, table, prior, options);
      tracker.setBackground(background);
      kw::person::GroundTracker ground_track(camera, walk.ground, {}, false);
      ground_track.start(guess.position_m, std::nullopt, 0.0);
      std::vector<double> total, ground_ms, precompute, dynamics, likelihood, resample, per_particle, dynamics_per_particle;
      int resampled = 0;
      tracker.start(images[0], 0.0, guess, &ground_track.update(images[0], background, 0.0));
      const double start_ms = tracker.timing().total_ms;
      for (size_t i = 1; i < images.size(); ++i) {
        const auto ground_start = std::chrono::steady_clock::now();
        const kw::person::GroundTrackEstimate& ground = ground_track.update(images[i], background, i / fps);
        ground_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - ground_start).count());
        resampled += tracker.track(images[i], i / fps, &ground).resampled;
        const kw::tracking::TrackerTiming& t = tracker.timing();
        total.push_back(ground_ms.back() + t.total_ms);
        precompute.push_back(t.precompute_ms);
        dynamics.push_back(t.dynamics_cpu_ms);
        likelihood.push_back(t.likelihood_cpu_ms);
        resample.push_back(t.resample_ms);
        per_particle.push_back(1e3 * t.likelihood_cpu_ms / std::max(1, t.particle_steps));
        dynamics_per_particle.push_back(1e3 * t.dynamics_cpu_ms / std::max(1, t.particle_steps));
      }
      std::printf("threads=%d tracker_ms_per_frame=%.1f ground_track_ms=%.2f per_frame_precompute_ms=%.1f dynamics_ms=%.1f "
                  "likelihood_ms=%.1f resample_ms=%.1f likelihood_us_per_particle=%.2f "
                  "dynamics_us_per_particle=%.2f resampled_frames=%d/%zu mean_ms=%.1f p95_ms=%.1f start_ms=%.0f\n",
                  threads, median(total), median(ground_ms), median(precompute), median(dynamics), median(likelihood), median(resample),
                  median(per_particle), median(dynamics_per_particle), resampled, total.size(),
                  std::accumulate(total.begin(), total.end(), 0.0) / total.size(), percentile(total, 95), start_ms);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_tracker: %s\n", e.what());
    return 1;
  }
  return 0;
}
