#include "kneed_walker/core/gait/gait_norms.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

namespace kneed_walker::core::gait {
namespace {

const std::string kNorms = std::string(KNEED_WALKER_SHARED_DIR) + "/data/gait/Schwartz2008_Joint_Rotations.csv";

std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

// The published table: five classes, 51 samples of each angle; the free-speed knee peaks near
// 60 degrees in swing and the very slow one lower (the study's figures).
TEST(GaitNorms, ReadsTheSchwartzTable) {
  const GaitNorms norms = loadGaitNorms(kNorms);
  ASSERT_EQ(norms.classes.size(), 5u);
  EXPECT_EQ(norms.classes.front().name, "Very Slow");
  EXPECT_EQ(norms.classes.back().name, "Very Fast");
  const NormCurve& knee = norms.speedClass("Free").curve("Knee Flex/Extension");
  ASSERT_EQ(knee.cycle.size(), 51u);
  EXPECT_DOUBLE_EQ(knee.cycle[1], 0.02);
  const double free_peak = *std::max_element(knee.mean.begin(), knee.mean.end());
  const NormCurve& slow_knee = norms.speedClass("Very Slow").curve("Knee Flex/Extension");
  EXPECT_NEAR(free_peak, 59.1, 0.1);
  EXPECT_LT(*std::max_element(slow_knee.mean.begin(), slow_knee.mean.end()), free_peak - 10);
  for (std::size_t i = 0; i < knee.cycle.size(); ++i) EXPECT_LE(knee.low[i], knee.high[i]);
}

// meanAt interpolates linearly between samples and repeats with the cycle.
TEST(GaitNorms, MeanAtInterpolatesAndRepeats) {
  const NormCurve& hip = loadGaitNorms(kNorms).speedClass("Free").curve("Hip Flex/Extension");
  EXPECT_DOUBLE_EQ(hip.meanAt(0.04), hip.mean[2]);
  EXPECT_NEAR(hip.meanAt(0.05), 0.5 * (hip.mean[2] + hip.mean[3]), 1e-12);
  EXPECT_NEAR(hip.meanAt(1.05), hip.meanAt(0.05), 1e-12);
  EXPECT_NEAR(hip.meanAt(-0.95), hip.meanAt(0.05), 1e-12);
  EXPECT_NEAR(hip.meanAt(0.999999), hip.mean.back(), 1e-3);
}

TEST(GaitNorms, NamesWhatIsMissingOrMalformed) {
  const GaitNorms norms = loadGaitNorms(kNorms);
  EXPECT_THROW(norms.speedClass("Brisk"), std::out_of_range);
  EXPECT_THROW(norms.speedClass("Free").curve("Elbow"), std::out_of_range);
  try {
    norms.speedClass("Brisk");
  } catch (const std::out_of_range& e) {
    EXPECT_NE(std::string(e.what()).find("'Free'"), std::string::npos) << e.what();
  }
  const std::string header = "Angle,% Gait Cycle,Slow,,,Fast,,\n,,-1sd,mean,+1sd,-1sd,mean,+1sd\n";
  auto message = [](const std::string& path) {
    try {
      loadGaitNorms(path);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("/nonexistent/norms.csv").find("cannot read"), std::string::npos);
  EXPECT_NE(message(writeFile("empty.csv", "")).find("no header"), std::string::npos);
  EXPECT_NE(message(writeFile("bad_number.csv", header + "Knee,0.0,1,2,3,4,x5,6\nKnee,1.0,1,2,3,4,5,6\n"))
                .find("row 3: 'x5'"),
            std::string::npos);
  EXPECT_NE(message(writeFile("short.csv", header + "Knee,0.0,1,2,3\n")).find("row 3: 5 columns, expected 8"),
            std::string::npos);
  EXPECT_NE(message(writeFile("order.csv", header + "Knee,0.5,1,2,3,4,5,6\nKnee,0.2,1,2,3,4,5,6\n"))
                .find("must increase"),
            std::string::npos);
  EXPECT_NE(message(writeFile("partial.csv", header + "Knee,0.0,1,2,3,4,5,6\nKnee,0.5,1,2,3,4,5,6\n"))
                .find("'Knee' must run from cycle 0 to 1"),
            std::string::npos);
  const GaitNorms tiny = loadGaitNorms(writeFile("tiny.csv", header + "Knee,0.0,1,2,3,4,5,6\nKnee,1.0,1,4,5,4,7,8\n"));
  EXPECT_DOUBLE_EQ(tiny.speedClass("Fast").curve("Knee").meanAt(0.5), 6.0);
}

}  // namespace
}  // namespace kneed_walker::core::gait
