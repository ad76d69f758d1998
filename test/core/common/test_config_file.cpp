#include "kneed_walker/core/common/config_file.h"

#include <gtest/gtest.h>

#include <fstream>
#include <stdexcept>
#include <string>

namespace kneed_walker::core::common {
namespace {

std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/kneed_walker_config_" + name + ".yaml";
  std::ofstream(path) << "%YAML:1.0\n---\n" << text;
  return path;
}

// The message of the std::invalid_argument that `read` throws, or "" when it does not.
template <class Read>
std::string problems(const std::string& path, Read read) {
  try {
    ConfigFile file(path, "test settings");
    read(file);
    file.finish();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// Other programs' YAML (ROS's camera_info files) has no "%YAML:1.0" line, which OpenCV's
// reader needs: it is read all the same.
TEST(ConfigFile, ReadsYamlWithoutTheDirective) {
  const std::string path = ::testing::TempDir() + "/kneed_walker_config_plain.yaml";
  std::ofstream(path) << "image_width: 640\ncamera_matrix:\n  rows: 3\n  data: [1, 2, 3]\n";
  int width = 0;
  std::vector<double> data;
  EXPECT_EQ(problems(path, [&](ConfigFile& file) {
              file.read("image_width", width, Need::kRequired);
              ConfigNode matrix = file.map("camera_matrix");
              int rows = 0;
              matrix.read("rows", rows);
              matrix.read("data", data, Need::kRequired, 3);
            }),
            "");
  EXPECT_EQ(width, 640);
  EXPECT_EQ(data, (std::vector<double>{1, 2, 3}));
}

TEST(ConfigFile, ReadsTypedValuesAndKeepsDefaultsOfAbsentKeys) {
  const std::string path = writeFile("good",
      "rate: 2.5\ncount: 3\nflag: 1\nname: \"walker\"\nlist: [1, 2.5, 3]\n"
      "torso:\n  mass: 0.5\ngaits:\n  - { q: [1, 2] }\n  - { q: [3, 4] }\n");
  double rate = 0, absent = 7;
  int count = 0;
  bool flag = false;
  std::string name;
  std::array<double, 3> list{};
  double mass = 0;
  std::vector<std::vector<double>> qs;
  EXPECT_EQ(problems(path, [&](ConfigFile& f) {
              f.read("rate", rate);
              f.read("absent", absent);
              f.read("count", count);
              f.read("flag", flag);
              f.read("name", name);
              f.read("list", list);
              f.map("torso").read("mass", mass);
              for (ConfigNode& gait : f.maps("gaits")) {
                std::vector<double> q;
                gait.read("q", q, Need::kRequired, 2);
                qs.push_back(q);
              }
            }),
            "");
  EXPECT_EQ(rate, 2.5);
  EXPECT_EQ(absent, 7);
  EXPECT_EQ(count, 3);
  EXPECT_TRUE(flag);
  EXPECT_EQ(name, "walker");
  EXPECT_EQ(list[1], 2.5);
  EXPECT_EQ(mass, 0.5);
  ASSERT_EQ(qs.size(), 2u);
  EXPECT_EQ(qs[1][1], 4);
}

TEST(ConfigFile, ReportsEveryProblemAtOnceNamingFileAndKey) {
  const std::string path = writeFile("bad",
      "rate: \"fast\"\ncount: 2.5\nflag: 2\nlist: [1, 2]\nspeling: 1\n"
      "torso:\n  mass: .nan\n  colour: 3\ngaits:\n  - { q: [1] }\n");
  double rate = 0, mass = 0;
  int count = 0;
  bool flag = false;
  std::array<double, 3> list{};
  const std::string message = problems(path, [&](ConfigFile& f) {
    f.read("rate", rate);
    f.read("count", count);
    f.read("flag", flag);
    f.read("list", list);
    f.read("required", rate, Need::kRequired);
    f.map("torso").read("mass", mass);
    for (ConfigNode& gait : f.maps("gaits")) {
      std::vector<double> q;
      gait.read("q", q, Need::kRequired, 2);
    }
  });
  EXPECT_NE(message.find(path + ": invalid test settings:"), std::string::npos) << message;
  for (const char* expected :
       {"rate must be a number", "count must be an integer", "flag must be 0 or 1",
        "list must list 3 numbers", "required is missing", "torso.mass must be finite",
        "gaits[0].q must list 2 numbers", "speling is not a known key",
        "torso.colour is not a known key"})
    EXPECT_NE(message.find(expected), std::string::npos) << expected << " in\n" << message;
  EXPECT_EQ(rate, 0) << "a bad value leaves the default";
}

TEST(ConfigFile, AddsValidationProblemsAndCanAllowOtherKeys) {
  const std::string path = writeFile("other", "rate: 1\nextra: 2\n");
  double rate = 0;
  try {
    ConfigFile file(path, "test settings");
    file.read("rate", rate);
    file.finish({"rate = 1 must be > 2"}, true);
    FAIL() << "validation problems must throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("rate = 1 must be > 2"), std::string::npos);
    EXPECT_EQ(std::string(e.what()).find("extra"), std::string::npos) << e.what();
  }
}

TEST(ConfigFile, RefusesMissingAndUnreadableFiles) {
  EXPECT_THROW(ConfigFile("/nonexistent/kneed_walker.yaml", "test settings"), std::invalid_argument);
  const std::string path = ::testing::TempDir() + "/kneed_walker_config_corrupt.yaml";
  std::ofstream(path) << "%YAML:1.0\n---\nrate: [1, 2\n  : :\n";
  EXPECT_THROW(ConfigFile(path, "test settings"), std::invalid_argument);
}

}  // namespace
}  // namespace kneed_walker::core::common
