// config/tracker.yaml and cfg/Tracker.cfg say what the option tables say: every parameter the
// nodelet reads from a table is in tracker.yaml with the table's default (the struct's member
// initialiser: the one place a default is written in the code), tracker.yaml names no parameter
// the nodelet does not read, and every parameter dynamic_reconfigure may change has the
// table's default and range in Tracker.cfg.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "kneed_walker/core/tracking/tracking_session.h"
#include "kneed_walker/core/vision/likelihood.h"
#include "kneed_walker/ros/parameters.h"

namespace kneed_walker::ros_glue {
namespace {

struct Option {
  std::string default_text;  // common::valueText of the struct's default
  double min = 0, max = 0;
  bool flag = false;
};

template <class Options>
void collect(const core::common::OptionTable<Options>& table, std::map<std::string, Option>& options) {
  Options defaults;
  for (const auto& spec : table) {
    const core::common::OptionField field = spec.field(defaults);
    EXPECT_TRUE(options
                    .emplace(spec.name, Option{core::common::valueText(field), spec.min, spec.max,
                                               std::holds_alternative<bool*>(field)})
                    .second)
        << spec.name << " is in two tables";
  }
}

std::map<std::string, Option> tableOptions() {
  std::map<std::string, Option> options;
  collect(core::tracking::trackerOptionTable(), options);
  collect(core::vision::likelihoodOptionTable(), options);
  collect(core::tracking::sessionOptionTable(), options);
  collect(rosInterfaceOptionTable(), options);
  return options;
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The number's value as the table writes it ("0.10" and "0.1" are the same).
std::string numberText(double value) {
  return core::common::valueText(core::common::OptionField(&value));
}

TEST(ParameterFiles, TrackerYamlHoldsEveryTableOptionWithItsDefault) {
  const std::map<std::string, Option> options = tableOptions();
  // Parameters the nodelet reads beside the tables: strings, lists and files.
  const std::set<std::string> others{"world_frame", "image_transport", "camera_file", "init_box",
                                     "gait_table",  "prior_config",    "walker_model"};
  // The file is flat: `name: value  # comment`, one a line (rosparam reads it as YAML).
  std::istringstream yaml(readText(std::string(KNEED_WALKER_SOURCE_DIR) + "/config/tracker.yaml"));
  const std::regex entry(R"re(^(\w+):\s*([^#]*?)\s*(#.*)?$)re");
  std::set<std::string> seen;
  std::smatch match;
  for (std::string line; std::getline(yaml, line);) {
    if (!std::regex_match(line, match, entry)) continue;
    const std::string name = match[1], value = match[2];
    EXPECT_TRUE(seen.insert(name).second) << "config/tracker.yaml: " << name << " twice";
    if (others.count(name)) continue;
    const auto option = options.find(name);
    if (option == options.end()) {
      ADD_FAILURE() << "config/tracker.yaml: " << name << " is not a parameter of the nodelet";
      continue;
    }
    const std::string text = option->second.flag ? value : numberText(std::stod(value));
    EXPECT_EQ(text, option->second.default_text) << "config/tracker.yaml: " << name << " is not the default";
  }
  // Parameters whose absence means something (person_height_m: each person's measured) are
  // there as a comment, `# name: value`.
  const std::set<std::string> unset{"person_height_m"};
  const std::string text = readText(std::string(KNEED_WALKER_SOURCE_DIR) + "/config/tracker.yaml");
  for (const std::string& name : unset) {
    EXPECT_FALSE(seen.count(name)) << "config/tracker.yaml sets " << name << ": unset means something";
    EXPECT_NE(text.find("\n# " + name + ": "), std::string::npos) << "config/tracker.yaml lacks the comment # " << name << ":";
  }
  for (const auto& [name, option] : options)
    EXPECT_TRUE(seen.count(name) || unset.count(name)) << "config/tracker.yaml lacks " << name;
  for (const std::string& name : others) EXPECT_TRUE(seen.count(name)) << "config/tracker.yaml lacks " << name;
}

TEST(ParameterFiles, TrackerCfgHasTheTablesDefaultsAndRanges) {
  const std::map<std::string, Option> options = tableOptions();
  const std::string cfg = readText(std::string(KNEED_WALKER_SOURCE_DIR) + "/cfg/Tracker.cfg");
  // gen.add("name", type, level, "help", default[, min, max])
  const std::regex add(R"re(gen\.add\("(\w+)",\s*(\w+),\s*\d+,\s*((?:"[^"]*"\s*)+),\s*([^,\)]+)(?:,\s*([^,\)]+),\s*([^,\)]+))?\))re");
  int checked = 0;
  for (std::sregex_iterator it(cfg.begin(), cfg.end(), add), end; it != end; ++it) {
    const std::string name = (*it)[1];
    if (name == "restart") continue;  // a button, not a parameter
    const auto option = options.find(name);
    if (option == options.end()) {
      ADD_FAILURE() << "cfg/Tracker.cfg: " << name << " is not a parameter of the nodelet";
      continue;
    }
    ++checked;
    const std::string default_text = (*it)[4];
    if (option->second.flag) {
      EXPECT_EQ(default_text == "True" ? "true" : "false", option->second.default_text) << name;
      continue;
    }
    EXPECT_EQ(numberText(std::stod(default_text)), option->second.default_text) << "cfg/Tracker.cfg: " << name;
    ASSERT_TRUE((*it)[5].matched) << "cfg/Tracker.cfg: " << name << " has no range";
    EXPECT_EQ(std::stod((*it)[5]), option->second.min) << "cfg/Tracker.cfg: " << name << "'s minimum";
    EXPECT_EQ(std::stod((*it)[6]), option->second.max) << "cfg/Tracker.cfg: " << name << "'s maximum";
  }
  EXPECT_EQ(checked, 6);  // num_particles, prior_noise_scale, the three publishing switches and the interval
}

// The README's table of parameters is the tables' own (parameterTableMarkdown): on a mismatch,
// paste the table printed here into the README.
TEST(ParameterFiles, TheReadmesParameterTableIsTheTables) {
  const std::string readme = readText(std::string(KNEED_WALKER_SOURCE_DIR) + "/README.md");
  const std::string table = parameterTableMarkdown();
  EXPECT_NE(readme.find(table), std::string::npos) << "README.md should hold this table:\n" << table;
}

}  // namespace
}  // namespace kneed_walker::ros_glue
