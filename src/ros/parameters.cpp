#include "kneed_walker/ros/parameters.h"

#include <XmlRpcValue.h>
#include <ros/param.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace kneed_walker::ros_glue {
namespace {

// Reads typed parameters under one namespace and collects every problem instead of stopping
// at the first, so a user fixes a launch file in one go.
class ParameterReader {
 public:
  explicit ParameterReader(const ros::NodeHandle& nh) : nh_(nh) {}

  void read(const std::string& name, int& value) {
    XmlRpc::XmlRpcValue raw;
    if (!fetch(name, raw)) return;
    if (raw.getType() != XmlRpc::XmlRpcValue::TypeInt) return wrongType(name, "an integer");
    value = static_cast<int>(raw);
  }
  void read(const std::string& name, double& value) {
    XmlRpc::XmlRpcValue raw;
    if (!fetch(name, raw)) return;
    if (raw.getType() == XmlRpc::XmlRpcValue::TypeInt) {
      value = static_cast<int>(raw);
    } else if (raw.getType() == XmlRpc::XmlRpcValue::TypeDouble) {
      value = static_cast<double>(raw);
    } else {
      wrongType(name, "a number");
    }
  }
  void read(const std::string& name, bool& value) {
    XmlRpc::XmlRpcValue raw;
    if (!fetch(name, raw)) return;
    if (raw.getType() != XmlRpc::XmlRpcValue::TypeBoolean) return wrongType(name, "true or false");
    value = static_cast<bool>(raw);
  }
  void read(const std::string& name, std::string& value) {
    XmlRpc::XmlRpcValue raw;
    if (!fetch(name, raw)) return;
    if (raw.getType() != XmlRpc::XmlRpcValue::TypeString) return wrongType(name, "a string");
    value = static_cast<std::string>(raw);
  }
  // A list of numbers (integers allowed).
  void read(const std::string& name, std::vector<double>& value) {
    XmlRpc::XmlRpcValue raw;
    if (!fetch(name, raw)) return;
    if (raw.getType() != XmlRpc::XmlRpcValue::TypeArray) return wrongType(name, "a list of numbers");
    std::vector<double> numbers;
    for (int i = 0; i < raw.size(); ++i) {
      if (raw[i].getType() == XmlRpc::XmlRpcValue::TypeInt) {
        numbers.push_back(static_cast<int>(raw[i]));
      } else if (raw[i].getType() == XmlRpc::XmlRpcValue::TypeDouble) {
        numbers.push_back(static_cast<double>(raw[i]));
      } else {
        return wrongType(name, "a list of numbers");
      }
    }
    value = numbers;
  }
  void read(const std::string& name, std::uint64_t& value) {
    int as_int = static_cast<int>(value);
    read(name, as_int);
    if (as_int < 0) {
      problems_.push_back(qualified(name) + " = " + std::to_string(as_int) + " must be >= 0");
      return;
    }
    value = static_cast<std::uint64_t>(as_int);
  }

  // Parameters present under the namespace that no read() asked for: most often typos.
  void reportUnknown() {
    std::vector<std::string> all;
    if (!ros::param::getParamNames(all)) return;
    const std::string prefix = nh_.getNamespace() + "/";
    for (const auto& full : all) {
      if (full.compare(0, prefix.size(), prefix) != 0) continue;
      const std::string name = full.substr(prefix.size());
      if (known_.count(name) == 0) {
        std::string list;
        for (const auto& k : known_) list += (list.empty() ? "" : ", ") + k;
        problems_.push_back(qualified(name) + " is not a parameter of this node (known: " +
                            list + ")");
      }
    }
  }

  void addProblem(const std::string& problem) { problems_.push_back(problem); }
  const std::vector<std::string>& problems() const { return problems_; }
  // "/nodelet_name/<text>": the fully qualified parameter a message is about.
  std::string qualified(const std::string& text) const { return nh_.getNamespace() + "/" + text; }

 private:
  bool fetch(const std::string& name, XmlRpc::XmlRpcValue& raw) {
    known_.insert(name);
    return nh_.getParam(name, raw);
  }
  void wrongType(const std::string& name, const char* expected) {
    problems_.push_back(qualified(name) + " must be " + expected);
  }

  const ros::NodeHandle& nh_;
  std::set<std::string> known_;
  std::vector<std::string> problems_;
};

}  // namespace

TrackerNodeConfig loadTrackerNodeConfig(const ros::NodeHandle& private_nh) {
  TrackerNodeConfig config;
  ParameterReader reader(private_nh);

  core::tracking::TrackerOptions& t = config.tracker;
  reader.read("num_particles", t.num_particles);
  // Unset, the threshold follows the particle count (the paper's 500 of 5000).
  t.resample_ess_threshold = t.num_particles / 10.0;
  reader.read("resample_ess_threshold", t.resample_ess_threshold);
  reader.read("resample_lag_frames", t.resample_lag_frames);
  reader.read("resample_mixing", t.resample_mixing);
  reader.read("initial_oversampling", t.initial_oversampling);
  reader.read("num_threads", t.num_threads);
  reader.read("seed", t.seed);
  reader.read("person_height_m", t.person_height_m);
  reader.read("person_mass_kg", t.person_mass_kg);
  reader.read("ground_slope_rad", t.ground_slope_rad);
  reader.read("min_gait_speed_kmh", t.min_gait_speed_kmh);
  reader.read("min_gait_step_m", t.min_gait_step_m);
  reader.read("person_breadth_scale", t.person_breadth_scale);
  reader.read("gait_speed_sd_kmh", t.gait_speed_sd_kmh);
  reader.read("gait_step_sd_m", t.gait_step_sd_m);
  reader.read("gait_change_persistence", t.gait_change_persistence);
  reader.read("lost_likelihood_fraction", t.lost_likelihood_fraction);
  reader.read("gait_slope_change_probability", t.gait_slope_change_probability);
  std::string hill_gaits = t.hill_gaits == core::tracking::HillGaits::kNearest ? "nearest" : "level_to_nearest";
  reader.read("hill_gaits", hill_gaits);
  if (hill_gaits == "nearest")
    t.hill_gaits = core::tracking::HillGaits::kNearest;
  else if (hill_gaits == "level_to_nearest")
    t.hill_gaits = core::tracking::HillGaits::kLevelToNearest;
  else
    reader.addProblem(reader.qualified("hill_gaits") + " = '" + hill_gaits + "' must be nearest or level_to_nearest");
  reader.read("default_frame_interval_s", t.default_frame_interval_s);
  reader.read("max_frame_gap_s", t.max_frame_gap_s);
  reader.read("use_optical_flow", config.likelihood.use_flow);

  RosInterfaceOptions& r = config.ros;
  reader.read("world_frame", r.world_frame);
  reader.read("image_queue_size", r.image_queue_size);
  reader.read("image_transport", r.image_transport);
  reader.read("publish_particle_cloud", r.publish_particle_cloud);
  reader.read("publish_tf", r.publish_tf);
  reader.read("particle_cloud_interval_s", r.particle_cloud_interval_s);
  reader.read("publish_overlay", r.publish_overlay);
  // dynamic_reconfigure's button (cfg/Tracker.cfg) sits beside the parameters it starts from;
  // it means nothing at start.
  bool restart = false;
  reader.read("restart", restart);
  reader.read("camera_file", r.camera_file);
  reader.read("camera_file_unit_m", r.camera_file_unit_m);
  reader.read("init_box", r.init_box);
  reader.read("gait_table", r.gait_table);
  reader.read("prior_config", r.prior_config);
  reader.read("walker_model", r.walker_model);
  reader.read("prior_noise_scale", r.prior_noise_scale);

  core::tracking::SessionOptions& session = config.session;
  reader.read("background_frames", session.background_frames);
  reader.read("heading_frames", session.heading_frames);
  reader.read("find_people", session.find_people);
  reader.read("min_start_speed_kmh", session.min_start_speed_kmh);
  reader.read("max_start_speed_kmh", session.max_start_speed_kmh);
  reader.read("max_people", session.max_people);
  reader.read("merge_distance_m", session.merge_distance_m);
  reader.read("reacquire_distance_m", session.reacquire_distance_m);
  reader.read("estimate_person_height", session.estimate_person_height);
  reader.read("min_person_height_m", session.min_person_height_m);
  reader.read("max_person_height_m", session.max_person_height_m);
  for (const auto& problem : validate(session)) reader.addProblem(reader.qualified(problem));
  if (!(std::isfinite(r.particle_cloud_interval_s) && r.particle_cloud_interval_s >= 0 && r.particle_cloud_interval_s <= 3600))
    reader.addProblem(reader.qualified("particle_cloud_interval_s") + " = " + std::to_string(r.particle_cloud_interval_s) +
                      " is outside [0, 3600]");
  if (!(std::isfinite(r.prior_noise_scale) && r.prior_noise_scale >= 0 && r.prior_noise_scale <= 100))
    reader.addProblem(reader.qualified("prior_noise_scale") + " = " + std::to_string(r.prior_noise_scale) +
                      " is outside [0, 100]");
  if (!(std::isfinite(r.camera_file_unit_m) && r.camera_file_unit_m >= 1e-6 && r.camera_file_unit_m <= 1e3))
    reader.addProblem(reader.qualified("camera_file_unit_m") + " = " + std::to_string(r.camera_file_unit_m) +
                      " is outside [1e-06, 1000]");
  if (r.image_transport != "raw" && r.image_transport != "compressed" && r.image_transport != "theora")
    reader.addProblem(reader.qualified("image_transport") + " = '" + r.image_transport +
                      "' must be raw, compressed or theora");
  if (!r.init_box.empty()) {
    const auto& b = r.init_box;
    const bool finite = std::all_of(b.begin(), b.end(), [](double v) { return std::isfinite(v); });
    if (b.size() != 4 || !finite || !(b[2] > b[0] && b[3] > b[1]))
      reader.addProblem(reader.qualified("init_box") + " must be [x1, y1, x2, y2] in pixels, finite, with x2 > x1 and y2 > y1");
  }
  for (const auto& [name, path] : {std::pair<const char*, const std::string*>{"camera_file", &r.camera_file},
                                   {"gait_table", &r.gait_table}, {"prior_config", &r.prior_config},
                                   {"walker_model", &r.walker_model}})
    if (!path->empty() && !std::ifstream(*path))
      reader.addProblem(reader.qualified(name) + " = '" + *path + "': cannot read the file");

  for (const auto& problem : validate(t)) reader.addProblem(reader.qualified(problem));
  if (r.world_frame.empty() || r.world_frame.front() == '/')
    reader.addProblem(reader.qualified("world_frame") + " = '" + r.world_frame +
                      "' must be a non-empty tf2 frame id without a leading '/'");
  if (r.image_queue_size < 1 || r.image_queue_size > 100)
    reader.addProblem(reader.qualified("image_queue_size") + " = " +
                      std::to_string(r.image_queue_size) + " is outside [1, 100]");
  reader.reportUnknown();

  if (!reader.problems().empty()) {
    std::ostringstream message;
    message << "invalid parameters:";
    for (const auto& problem : reader.problems()) message << "\n  " << problem;
    throw std::invalid_argument(message.str());
  }
  return config;
}

}  // namespace kneed_walker::ros_glue
