#include "kneed_walker/ros/parameters.h"

#include <XmlRpcValue.h>
#include <ros/param.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <variant>
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

// Reads every option of a table by its name.
template <class Options>
void readTable(ParameterReader& reader, const core::common::OptionTable<Options>& table, Options& options) {
  for (const auto& spec : table) std::visit([&](auto* value) { reader.read(spec.name, *value); }, spec.field(options));
}

}  // namespace

const core::common::OptionTable<RosInterfaceOptions>& rosInterfaceOptionTable() {
  using core::common::OptionField;
  using O = RosInterfaceOptions;
  static const core::common::OptionTable<RosInterfaceOptions> table{
      {"image_queue_size", [](O& o) -> OptionField { return &o.image_queue_size; }, 1, 1000, "frames",
       "frames that wait while one is tracked (150: 5 s at 30 fps, through a track's first-frame search; 140 MB of VGA images); a frame arriving at a full queue pushes out the oldest (dropped)"},
      {"frame_budget_fraction", [](O& o) -> OptionField { return &o.frame_budget_fraction; }, 0, 1, "",
       "each frame's tracking fits into this fraction of the frame interval (from the stamps): the particle count adapts at resamplings within [min_particles, num_particles]; 0: always num_particles"},
      {"min_particles", [](O& o) -> OptionField { return &o.min_particles; }, 1, 1e6, "",
       "the fewest particles per person a frame budget may bring the count to (a smaller num_particles is the count)"},
      {"publish_particle_cloud", [](O& o) -> OptionField { return &o.publish_particle_cloud; }, 0, 0, "",
       "publish ~particle_cloud"},
      {"particle_cloud_interval_s", [](O& o) -> OptionField { return &o.particle_cloud_interval_s; }, 0, 3600, "s",
       "at most one ~particle_cloud per this interval"},
      {"publish_tf", [](O& o) -> OptionField { return &o.publish_tf; }, 0, 0, "",
       "broadcast body_<id> and its joint frames on /tf"},
      {"publish_overlay", [](O& o) -> OptionField { return &o.publish_overlay; }, 0, 0, "",
       "publish ~overlay while someone subscribes"},
      {"camera_file_unit_m", [](O& o) -> OptionField { return &o.camera_file_unit_m; }, 1e-6, 1e3, "m",
       "metres per unit of the camera file's translation"},
      {"prior_noise_scale", [](O& o) -> OptionField { return &o.prior_noise_scale; }, 0, 100, "",
       "factor on the prior's torque noise scales s_j (eq. 11)"},
  };
  return table;
}

namespace {

template <class Options>
void markdownRows(const core::common::OptionTable<Options>& table, std::ostringstream& out) {
  Options defaults;
  for (const auto& spec : table) {
    const core::common::OptionField field = spec.field(defaults);
    out << "| `" << spec.name << "` | " << core::common::valueText(field) << " | " << spec.unit << " | ";
    if (!std::holds_alternative<bool*>(field)) {
      double min = spec.min, max = spec.max;
      out << "[" << core::common::valueText(&min) << ", " << core::common::valueText(&max) << "]";
    }
    out << " | " << spec.help << " |\n";
  }
}

}  // namespace

std::string parameterTableMarkdown() {
  std::ostringstream out;
  out << "| parameter | default | unit | range | meaning |\n|---|---|---|---|---|\n";
  markdownRows(core::tracking::trackerOptionTable(), out);
  markdownRows(core::vision::likelihoodOptionTable(), out);
  markdownRows(core::tracking::sessionOptionTable(), out);
  markdownRows(rosInterfaceOptionTable(), out);
  return out.str();
}

TrackerNodeConfig loadTrackerNodeConfig(const ros::NodeHandle& private_nh) {
  TrackerNodeConfig config;
  ParameterReader reader(private_nh);
  readTable(reader, core::tracking::trackerOptionTable(), config.tracker);
  readTable(reader, core::vision::likelihoodOptionTable(), config.likelihood);
  readTable(reader, core::tracking::sessionOptionTable(), config.session);
  // A height given is everyone's; else each person's is measured (SessionOptions).
  config.session.estimate_person_height = !private_nh.hasParam("person_height_m");
  RosInterfaceOptions& r = config.ros;
  readTable(reader, rosInterfaceOptionTable(), r);
  config.tracker.frame_budget_fraction = r.frame_budget_fraction;
  // A num_particles below min_particles is the count: the budget has nothing to fit.
  config.tracker.min_particles = std::min(r.min_particles, std::max(1, config.tracker.filter.num_particles));
  reader.read("world_frame", r.world_frame);
  reader.read("image_transport", r.image_transport);
  reader.read("camera_file", r.camera_file);
  reader.read("init_box", r.init_box);
  reader.read("gait_table", r.gait_table);
  reader.read("prior_config", r.prior_config);
  reader.read("walker_model", r.walker_model);
  // dynamic_reconfigure's button (cfg/Tracker.cfg) sits beside the parameters it starts from;
  // it means nothing at start.
  bool restart = false;
  reader.read("restart", restart);

  for (const auto& problem : validate(config.tracker)) reader.addProblem(reader.qualified(problem));
  for (const auto& problem : validate(config.likelihood)) reader.addProblem(reader.qualified(problem));
  for (const auto& problem : validate(config.session)) reader.addProblem(reader.qualified(problem));
  for (const auto& problem : core::common::rangeProblems(r, rosInterfaceOptionTable()))
    reader.addProblem(reader.qualified(problem));
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

  if (!r.camera_file.empty() && config.tracker.ground_slope_rad != 0)
    reader.addProblem(reader.qualified("ground_slope_rad") + " = " + std::to_string(config.tracker.ground_slope_rad) +
                      " with camera_file: the calibration gives the ground (its ground_slope_rad, level when it has "
                      "none); leave ground_slope_rad at 0");
  if (r.world_frame.empty() || r.world_frame.front() == '/')
    reader.addProblem(reader.qualified("world_frame") + " = '" + r.world_frame +
                      "' must be a non-empty tf2 frame id without a leading '/'");
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
