#include "kneed_walker/core/vision/camera_calibration.h"

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace kneed_walker::core::vision {
namespace {

const std::string kPetsCamera = std::string(KNEED_WALKER_SHARED_DIR) + "/data/pets2009/View_001_camera.yml";

std::string temporaryFile(const std::string& name, const std::string& text) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("kneed_walker_calibration_" + std::to_string(::getpid()) + "_" + name)).string();
  std::ofstream(path) << text;
  return path;
}

// Six marks on the PETS lawn and path, spread over the image as a user would choose them: their
// ground positions to the centimetre (a tape) and their pixels to the whole pixel (a click).
std::vector<GroundPointObservation> petsMarks(const Camera& camera) {
  const std::vector<Eigen::Vector2d> spread{{120, 320}, {400, 260}, {690, 300},
                                            {140, 540}, {420, 430}, {700, 530}};
  std::vector<GroundPointObservation> marks;
  for (const Eigen::Vector2d& pixel : spread) {
    const Eigen::Vector3d ground = *camera.groundPoint(pixel);
    const Eigen::Vector2d measured((ground.head<2>() * 100).array().round() / 100);
    const Eigen::Vector2d seen = *camera.project(Eigen::Vector3d(measured.x(), measured.y(), 0));
    marks.push_back({measured, seen.array().round()});
  }
  return marks;
}

TEST(CameraCalibration, RecoversThePetsCameraFromSixGroundPoints) {
  const Camera truth = Camera::load(kPetsCamera, 0.001);
  const CameraIntrinsics intrinsics = loadCameraIntrinsics(kPetsCamera);
  const GroundPoseFit fit = solveGroundPose(intrinsics, petsMarks(truth));
  const double position_error_m = (fit.camera.centre() - truth.centre()).norm();
  std::printf("reprojection rms %.3f px, max %.3f px; camera %.3f m from the truth, %.2f m up\n", fit.rms_px,
              fit.max_px, position_error_m, fit.camera.centre().z());
  ASSERT_EQ(fit.residuals_px.size(), 6u);
  EXPECT_LE(fit.max_px, 2.0);
  EXPECT_LE(position_error_m, 0.05);
  // The rotation is the truth's within a few hundredths of a degree.
  const double angle = Eigen::AngleAxisd(fit.camera.rotation() * truth.rotation().transpose()).angle();
  EXPECT_LT(angle, 0.002);
}

// Seven marks seen by a robot's camera 1.35 m up, one clicked 50 px off: least squares with it
// puts the camera tens of centimetres too high; left out in turn, the marks name it, and the
// pose from the others is the truth's.
TEST(CameraCalibration, NamesTheMarkThatDoesNotAgreeWithTheOthers) {
  CameraIntrinsics intrinsics;
  intrinsics.matrix << 525, 0, 320, 0, 525, 240, 0, 0, 1;
  intrinsics.width_px = 640;
  intrinsics.height_px = 480;
  // Looking along +Y, pitched 8° down, from (0, 0, 1.35).
  const double pitch = 8 * M_PI / 180;
  Eigen::Matrix3d rotation;
  rotation << 1, 0, 0, 0, -std::sin(pitch), -std::cos(pitch), 0, std::cos(pitch), -std::sin(pitch);
  const Eigen::Vector3d centre(0, 0, 1.35);
  const Camera truth(intrinsics.matrix, {}, rotation, -rotation * centre, 640, 480);
  std::vector<GroundPointObservation> marks;
  for (const Eigen::Vector2d& ground : std::vector<Eigen::Vector2d>{
           {-1.0, 3.0}, {1.0, 3.0}, {-1.5, 5.0}, {1.5, 5.0}, {0.0, 4.0}, {-2.0, 7.0}, {2.0, 7.0}})
    marks.push_back({ground, truth.project(Eigen::Vector3d(ground.x(), ground.y(), 0))->array().round()});
  ASSERT_FALSE(findDisagreeingMark(intrinsics, marks)) << "clean marks: none disagrees";
  marks[3].pixel.y() += 50;  // mark 4 mis-clicked
  const GroundPoseFit all = solveGroundPose(intrinsics, marks);
  const std::optional<DisagreeingMark> bad = findDisagreeingMark(intrinsics, marks);
  ASSERT_TRUE(bad);
  std::printf("with every mark: rms %.1f px, camera %.3f m up; without mark %d: rms %.2f px, %.3f m up; it is "
              "%.1f px off\n", all.rms_px, all.camera.centre().z(), bad->index + 1, bad->without.rms_px,
              bad->without.camera.centre().z(), bad->disagreement_px);
  EXPECT_EQ(bad->index, 3);
  EXPECT_GT(bad->disagreement_px, 40);
  EXPECT_NEAR(bad->without.camera.centre().z(), 1.35, 0.02);
  EXPECT_GT(std::abs(all.camera.centre().z() - 1.35), 0.05) << "the mark bends the fit with it";
}

TEST(CameraCalibration, ReadsIntrinsicsFromACameraInfoYaml) {
  const std::string path = temporaryFile("camera_info.yaml",
                                         "image_width: 640\n"
                                         "image_height: 480\n"
                                         "camera_name: head_camera\n"
                                         "camera_matrix:\n  rows: 3\n  cols: 3\n"
                                         "  data: [525.0, 0.0, 319.5, 0.0, 526.0, 239.5, 0.0, 0.0, 1.0]\n"
                                         "distortion_model: plumb_bob\n"
                                         "distortion_coefficients:\n  rows: 1\n  cols: 5\n"
                                         "  data: [0.1, -0.2, 0.001, 0.002, 0.0]\n"
                                         "rectification_matrix:\n  rows: 3\n  cols: 3\n"
                                         "  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n"
                                         "projection_matrix:\n  rows: 3\n  cols: 4\n"
                                         "  data: [525, 0, 319.5, 0, 0, 526, 239.5, 0, 0, 0, 1, 0]\n");
  const CameraIntrinsics intrinsics = loadCameraIntrinsics(path);
  std::remove(path.c_str());
  EXPECT_EQ(intrinsics.width_px, 640);
  EXPECT_EQ(intrinsics.height_px, 480);
  EXPECT_DOUBLE_EQ(intrinsics.matrix(0, 0), 525.0);
  EXPECT_DOUBLE_EQ(intrinsics.matrix(1, 1), 526.0);
  EXPECT_DOUBLE_EQ(intrinsics.matrix(0, 2), 319.5);
  EXPECT_DOUBLE_EQ(intrinsics.matrix(1, 2), 239.5);
  ASSERT_EQ(intrinsics.distortion.size(), 5u);
  EXPECT_DOUBLE_EQ(intrinsics.distortion[1], -0.2);
}

TEST(CameraCalibration, ReadsIntrinsicsFromAnOpenCvCalibration) {
  const Camera truth = Camera::load(kPetsCamera, 0.001);
  const CameraIntrinsics intrinsics = loadCameraIntrinsics(kPetsCamera);
  EXPECT_EQ(intrinsics.width_px, 768);
  EXPECT_EQ(intrinsics.height_px, 576);
  EXPECT_EQ(intrinsics.matrix, truth.intrinsics());
  EXPECT_EQ(intrinsics.distortion, truth.distortion());
}

TEST(CameraCalibration, RefusesAFisheyeModel) {
  const std::string path = temporaryFile("fisheye.yaml",
                                         "image_width: 640\nimage_height: 480\n"
                                         "camera_matrix: {rows: 3, cols: 3, data: [500, 0, 320, 0, 500, 240, 0, 0, 1]}\n"
                                         "distortion_model: equidistant\n"
                                         "distortion_coefficients: {rows: 1, cols: 4, data: [0.1, 0.0, 0.0, 0.0]}\n");
  try {
    loadCameraIntrinsics(path);
    ADD_FAILURE() << "an equidistant model was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("distortion_model is equidistant"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}

TEST(CameraCalibration, ReadsGroundPointsAndNamesABadLine) {
  const std::string good = temporaryFile("good.csv", "# marks on the floor\nu, v, x, y\n10,20,1.5,2\n\n30,40,-1,0.25\r\n");
  const std::vector<GroundPointObservation> points = loadGroundPoints(good);
  std::remove(good.c_str());
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[1].pixel, Eigen::Vector2d(30, 40));
  EXPECT_EQ(points[1].ground_m, Eigen::Vector2d(-1, 0.25));

  const std::string bad = temporaryFile("bad.csv", "u,v,x,y\n10,20,1.5,2\n30,40,nan,0\n50,60,1\n");
  try {
    loadGroundPoints(bad);
    ADD_FAILURE() << "bad lines were taken";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("line 3"), std::string::npos) << message;
    EXPECT_NE(message.find("line 4"), std::string::npos) << message;
  }
  std::remove(bad.c_str());
}

void expectRefused(const CameraIntrinsics& intrinsics, const std::vector<GroundPointObservation>& points,
                   const std::string& expected) {
  try {
    solveGroundPose(intrinsics, points);
    ADD_FAILURE() << "solved, expected a refusal naming: " << expected;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
  }
}

TEST(CameraCalibration, RefusesPointsThatCannotGiveAPose) {
  const Camera truth = Camera::load(kPetsCamera, 0.001);
  const CameraIntrinsics intrinsics = loadCameraIntrinsics(kPetsCamera);
  const std::vector<GroundPointObservation> marks = petsMarks(truth);
  expectRefused(intrinsics, {marks.begin(), marks.begin() + 3}, "at least 4 ground points, has 3");
  std::vector<GroundPointObservation> changed = marks;
  changed[2].pixel.x() = 900;
  expectRefused(intrinsics, changed, "point 3: pixel (900, ");
  changed = marks;
  changed[4].ground_m = changed[1].ground_m;
  expectRefused(intrinsics, changed, "points 2 and 5 are at the same place");
  changed = marks;
  changed[0].ground_m.y() = std::nan("");
  expectRefused(intrinsics, changed, "point 1 is not finite");
  // Four points on one line.
  std::vector<GroundPointObservation> line;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d ground(i * 2.0, i * 1.0);
    line.push_back({ground, *truth.project(Eigen::Vector3d(ground.x(), ground.y(), 0))});
  }
  expectRefused(intrinsics, line, "on one line");
  // Pixels mirrored top to bottom: no pose keeps the camera above the ground.
  changed = marks;
  for (GroundPointObservation& o : changed) o.pixel.y() = truth.height() - o.pixel.y();
  expectRefused(intrinsics, changed, "above the ground");
}

}  // namespace
}  // namespace kneed_walker::core::vision
