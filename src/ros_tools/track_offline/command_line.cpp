#include "command_line.h"

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <set>
#include <utility>

#include "options.h"  // src/tools: addTableOptions, FiniteRange
#include "package_files.h"

namespace kneed_walker::tools::track_offline {

namespace kw = kneed_walker::core;

namespace {

void addInputOptions(CLI::App& app, InputOptions& input) {
  auto* source = app.add_option_group("input", "one of --bag, --video");
  source->add_option("--bag", input.bag_path, "rosbag with image and camera_info topics")->check(CLI::ExistingFile);
  source->add_option("--video", input.video_path, "video file (with --camera)")->check(CLI::ExistingFile);
  source->require_option(1);
  app.add_option("--camera", input.camera_path,
                 "calibration (OpenCV YAML; may hold the ground plane); a bag's camera_info + /tf_static otherwise")
      ->check(CLI::ExistingFile);
  app.add_option("--camera-unit", input.camera_unit_m, "metres per unit of the calibration's t")->capture_default_str()
      ->check(FiniteRange(1e-6, 1e3));
  app.add_option("--image-topic", input.image_topic, "the bag's image topic")->capture_default_str();
  app.add_option("--info-topic", input.info_topic, "the bag's camera_info topic")->capture_default_str();
  app.add_option("--fps", input.fps, "video frame rate (default: the container's)")->check(FiniteRange(0.1, 1000));
  app.add_option("--first-frame", input.first_frame, "start tracking at this frame")->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--frames", input.max_frames, "track at most this many frames (0: all)")->check(CLI::NonNegativeNumber);
  app.add_option("--background", input.background_path, "an image of the empty scene instead")->check(CLI::ExistingFile);
  app.add_option("--background-samples", input.background_samples,
                 "frames spread over the whole input that the background is learned from")
      ->capture_default_str()->check(CLI::Range(1, 500));
  app.add_flag("--background-from-start", input.background_from_start,
               "learn the background from the first --background-frames frames, as the nodelet does, "
               "instead of frames spread over the whole input");
}

void addStartOptions(CLI::App& app, StartOptions& start, std::string& stance) {
  app.add_option("--init-box", start.init_box, "the person's box in the first frame: x1 y1 x2 y2 (px)")->expected(4)
      ->check(FiniteRange(-1e5, 1e5));
  app.add_option("--boxes", start.boxes_path,
                 "boxes CSV (frame,x1,y1,x2,y2,score,...): the first frame's best box, and a lost track's "
                 "restart from the box nearest where it was lost")
      ->check(CLI::ExistingFile);
  app.add_option("--init-position", start.init_position, "ground position X Y (m) instead of a box")->expected(2)
      ->check(FiniteRange(-1e5, 1e5));
  app.add_option("--init-position-sd", start.guess.position_sd_m, "spread of the initial position, m")
      ->capture_default_str()->check(FiniteRange(0.0, 10.0));
  app.add_option("--init-heading", start.guess.heading_rad, "walking direction, rad from +X towards +Y (default: unknown)")
      ->check(FiniteRange(-100, 100))->each([&start](const std::string&) { start.heading_given = true; });
  app.add_option("--init-heading-sd", start.guess.heading_sd_rad, "spread of the heading, rad (≥ π: any direction)")
      ->capture_default_str()->check(FiniteRange(0.0, 10.0));
  app.add_option("--init-stance", stance, "the leg on the ground in the first frame: left or right (default: unknown)")
      ->check(CLI::IsMember({"left", "right"}));
}

void addOutputOptions(CLI::App& app, OutputOptions& output, bool& filtered, bool& lagged) {
  app.add_option("--out-csv", output.csv_path, "MAP joints per frame and body (frame,stamp,joint,x,y,z,body,track)")->required();
  app.add_option("--overlay", output.overlay_path, "overlay video (MJPG .avi)");
  app.add_option("--strip", output.strip_path,
                 "a picture of the overlay at --strip-frames, each cropped around the tracked body, side by side (PNG)");
  app.add_option("--strip-frames", output.strip_frames, "frames for --strip, comma-separated")
      ->delimiter(',')->check(CLI::NonNegativeNumber);
  app.add_option("--out-boxes", output.boxes_path,
                 "the MAP body's image box per frame and body, as written to --out-csv (frame,x1,y1,x2,y2,body; px): "
                 "the bounding box of the projected parts' outlines");
  app.add_option("--out-ground-track", output.ground_track_path,
                 "each person's ground track per frame and body (frame,stamp,body,x,y,vx,vy,stature,var_x,cov_xy,"
                 "var_y,var_vx,var_vy,var_stature,measured; m, m/s, m^2): where they stand and go on the floor from "
                 "their silhouette alone; smoothed over each track with the whole MAP sequence, else filtered");
  auto* filtered_flag = app.add_flag("--filtered", filtered,
                                     "write each frame's best particle as it comes, instead of each track's whole MAP "
                                     "state sequence (one particle's path, written when the track ends)");
  app.add_flag("--lagged", lagged,
               "write each frame's MAP state Δs frames later, as the nodelet publishes it (the best particle's "
               "ancestry through the buffer, kept to one lineage while it weighs nearly as much; consecutive "
               "frames may come from different particles), instead of each track's whole MAP state sequence")
      ->excludes(filtered_flag);
}

bool sameFile(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  return fs::weakly_canonical(fs::absolute(a)) == fs::weakly_canonical(fs::absolute(b));
}

// What the tables' ranges cannot say: options that relate to each other. Each problem names
// the option as the user typed it.
std::vector<std::string> problems(const Options& options) {
  std::vector<std::string> found;
  for (const std::vector<std::string>& table_problems :
       {validate(options.tracker), validate(options.session), validate(options.likelihood)})
    for (const std::string& problem : table_problems) {
      const std::size_t name_end = problem.find(' ');  // each problem starts with the option's name
      found.push_back("--" + kw::common::kebabCase(problem.substr(0, name_end)) + problem.substr(name_end));
    }
  if (!options.input.camera_path.empty() && options.tracker.ground_slope_rad != 0)
    found.push_back(cv::format("--ground-slope-rad %g: the calibration --camera %s gives the ground (its "
                               "ground_slope_rad, level when it has none); leave --ground-slope-rad out",
                               options.tracker.ground_slope_rad, options.input.camera_path.c_str()));
  if (!options.input.bag_path.empty() && options.input.fps > 0)
    found.push_back("--fps: a bag's frames carry their own stamps; --fps is for --video");
  const OutputOptions& output = options.output;
  if (!output.strip_path.empty() && output.strip_frames.empty()) found.push_back("--strip needs --strip-frames");
  if (!output.strip_path.empty() && !cv::haveImageWriter(output.strip_path))
    found.push_back("--strip " + output.strip_path + ": not a picture file OpenCV can write (.png, .jpg)");
  // Two outputs on one file: one of them would be lost.
  const std::vector<std::pair<const char*, std::string>> outputs = {{"--out-csv", output.csv_path},
                                                                    {"--out-boxes", output.boxes_path},
                                                                    {"--out-ground-track", output.ground_track_path},
                                                                    {"--overlay", output.overlay_path},
                                                                    {"--strip", output.strip_path}};
  for (size_t i = 0; i < outputs.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (!outputs[i].second.empty() && !outputs[j].second.empty() &&
          sameFile(outputs[i].second, outputs[j].second))
        found.push_back(std::string(outputs[i].first) + " " + outputs[i].second + ": the same file as " +
                        outputs[j].first + "; give each output its own file");
  return found;
}

// Options renamed when the command line took the ROS parameters' names (2026-12-06): the old
// name is taken for a while, with a warning naming the new one. `value`: the value a renamed
// flag stands for.
struct RenamedOption {
  const char* old_name;
  const char* new_name;
  const char* value = nullptr;
};
constexpr RenamedOption kRenamedOptions[] = {
    {"--particles", "--num-particles"},
    {"--threads", "--num-threads"},
    {"--resample-lag", "--resample-lag-frames"},
    {"--height", "--person-height-m"},
    {"--breadth", "--person-breadth-scale"},
    {"--min-speed", "--min-start-speed-kmh"},
    {"--max-speed", "--max-start-speed-kmh"},
    {"--min-gait-speed", "--min-gait-speed-kmh"},
    {"--min-gait-step", "--min-gait-step-m"},
    {"--gait-speed-sd", "--gait-speed-sd-kmh"},
    {"--gait-step-sd", "--gait-step-sd-m"},
    {"--gait-slope-change", "--gait-slope-change-probability"},
    {"--lost-fraction", "--lost-likelihood-fraction"},
    {"--flow-min-sd", "--flow-min-sd-px"},
    {"--no-flow", "--use-optical-flow", "false"},
};
// Options removed then, each with what to give instead.
constexpr std::pair<const char*, const char*> kRemovedOptions[] = {
    {"--ess-threshold", "give --resample-ess-fraction, the threshold as a fraction of --num-particles"},
    {"--estimate-height", "each person's height is measured unless --person-height-m gives it"},
    {"--hill-gaits", "the particles walk the nearest slope's gaits and those between it and the level"},
    {"--contact-weight", "the ground contact term was removed"},
};

// The arguments with each old option name replaced by its new one (a warning says so); empty,
// with the problem printed, when one names a removed option.
std::optional<std::vector<std::string>> withCurrentOptionNames(int argc, char** argv) {
  std::vector<std::string> arguments{argv[0]};
  std::set<std::string> warned;
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    const std::size_t equals = argument.find('=');
    const std::string name = argument.substr(0, equals);
    for (const auto& [removed, instead] : kRemovedOptions)
      if (name == removed) {
        std::fprintf(stderr, "track_offline: %s was removed: %s\n", removed, instead);
        return std::nullopt;
      }
    const auto renamed = std::find_if(std::begin(kRenamedOptions), std::end(kRenamedOptions),
                                      [&](const RenamedOption& r) { return name == r.old_name; });
    if (renamed == std::end(kRenamedOptions)) {
      arguments.push_back(argument);
      continue;
    }
    if (warned.insert(name).second)
      std::fprintf(stderr, "track_offline: warning: %s is an old name, taken for now: it is %s%s%s\n", name.c_str(),
                   renamed->new_name, renamed->value ? " " : "", renamed->value ? renamed->value : "");
    arguments.push_back(renamed->new_name + (equals == std::string::npos ? "" : argument.substr(equals)));
    if (renamed->value) arguments.push_back(renamed->value);
  }
  return arguments;
}

}  // namespace

std::optional<Options> parseOptions(int argc, char** argv, int& exit_code) {
  CLI::App app{"Tracks a walking person in a bag or video with the Kneed Walker; writes the MAP joints as CSV."};
  Options options;
  options.gait_table_path = packageFile("config/prior_gait_table.yaml");
  options.prior_path = packageFile("config/prior.yaml");
  options.walker_model_path = packageFile("config/walker_model.yaml");
  std::string stance;
  bool filtered = false, lagged = false;
  addInputOptions(app, options.input);
  addStartOptions(app, options.start, stance);
  addTableOptions(app, kw::tracking::trackerOptionTable(), options.tracker);
  addTableOptions(app, kw::tracking::sessionOptionTable(), options.session);
  addTableOptions(app, kw::vision::likelihoodOptionTable(), options.likelihood);
  app.add_option("--table", options.gait_table_path, "the prior's gait table")->check(CLI::ExistingFile)
      ->capture_default_str();
  app.add_option("--prior", options.prior_path, "prior parameters")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--walker-model", options.walker_model_path, "body proportions")->check(CLI::ExistingFile)
      ->capture_default_str();
  addOutputOptions(app, options.output, filtered, lagged);
  if (!refuseEmptyArguments("track_offline", argc, argv)) {
    exit_code = 1;
    return std::nullopt;
  }
  std::optional<std::vector<std::string>> arguments = withCurrentOptionNames(argc, argv);
  if (!arguments) {
    exit_code = 1;
    return std::nullopt;
  }
  std::vector<char*> pointers;
  for (std::string& argument : *arguments) pointers.push_back(argument.data());
  try {
    app.parse(static_cast<int>(pointers.size()), pointers.data());
  } catch (const CLI::ParseError& e) {
    exit_code = app.exit(e);
    return std::nullopt;
  }
  // A height given is everyone's; else each person's is measured (SessionOptions).
  options.session.estimate_person_height = app.count("--person-height-m") == 0;
  options.output.estimate = filtered ? WrittenEstimate::kFiltered
                            : lagged ? WrittenEstimate::kLagged
                                     : WrittenEstimate::kMapSequence;
  options.tracker.filter.keep_paths = options.output.estimate == WrittenEstimate::kMapSequence;
  if (!stance.empty()) options.start.guess.stance_leg = stance == "left" ? kw::dynamics::Leg::kLeft : kw::dynamics::Leg::kRight;
  // A track started from a box or a position starts on the same speeds as a person found.
  options.start.guess.min_speed_kmh = options.session.min_start_speed_kmh;
  options.start.guess.max_speed_kmh = options.session.max_start_speed_kmh;
  const std::vector<std::string> found = problems(options);
  for (const std::string& problem : found) std::fprintf(stderr, "track_offline: %s\n", problem.c_str());
  if (found.empty()) return options;
  exit_code = 1;
  return std::nullopt;
}

}  // namespace kneed_walker::tools::track_offline
