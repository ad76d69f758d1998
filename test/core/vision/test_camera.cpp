#include "kneed_walker/core/vision/camera.h"

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

namespace kneed_walker::core::vision {
namespace {

const std::string kPets = std::string(KNEED_WALKER_SHARED_DIR) + "/data/pets2009";

Camera petsCamera() { return Camera::load(kPets + "/View_001_camera.yml", 0.001); }

// cv::projectPoints of one world point, as the reference.
Eigen::Vector2d openCvProjection(const Camera& camera, const Eigen::Vector3d& world) {
  cv::Mat r, k;
  cv::eigen2cv(Eigen::Matrix3d(camera.rotation()), r);
  cv::eigen2cv(Eigen::Matrix3d(camera.intrinsics()), k);
  cv::Mat rvec;
  cv::Rodrigues(r, rvec);
  const cv::Vec3d tvec(camera.translation().x(), camera.translation().y(), camera.translation().z());
  std::vector<cv::Point3d> in{{world.x(), world.y(), world.z()}};
  std::vector<cv::Point2d> out;
  cv::projectPoints(in, rvec, tvec, k, cv::Mat(camera.distortion()), out);
  return {out[0].x, out[0].y};
}

void expectAgreesWithOpenCv(const Camera& camera, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-15, 15), y(-15, 15), z(0, 2.5);
  int visible = 0;
  double worst = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d p(x(rng), y(rng), z(rng));
    const auto pixel = camera.project(p);
    if (!pixel) continue;
    const Eigen::Vector2d reference = openCvProjection(camera, p);
    if (reference.x() < -200 || reference.x() > camera.width() + 200 || reference.y() < -200 ||
        reference.y() > camera.height() + 200)
      continue;  // far outside the image the polynomial is not a lens any more
    ++visible;
    worst = std::max(worst, (*pixel - reference).norm());
  }
  std::cout << visible << " points in view, worst difference " << worst << " px\n";
  EXPECT_GT(visible, 200);
  // Measured 4.9e-13 and 5.1e-13 px (the two calibrations): the same formula as OpenCV's,
  // evaluated in another order; 1e-10 leaves room for other libm and compiler builds.
  EXPECT_LT(worst, 1e-10);
}

TEST(Camera, ProjectionAgreesWithOpenCvOnThePetsCalibration) {
  const Camera camera = petsCamera();
  EXPECT_EQ(camera.width(), 768);
  EXPECT_EQ(camera.height(), 576);
  EXPECT_GT(camera.centre().z(), 5.0) << "the PETS camera is about 6.7 m up";
  EXPECT_LT(camera.centre().z(), 9.0);
  expectAgreesWithOpenCv(camera, 1);
}

TEST(Camera, ProjectionAgreesWithOpenCvForTheRationalModel) {
  const Camera pets = petsCamera();
  const Camera rational(pets.intrinsics(), {-0.2, 0.05, 0.001, -0.002, 0.01, 0.02, -0.01, 0.003},
                        pets.rotation(), pets.translation(), 768, 576);
  expectAgreesWithOpenCv(rational, 2);
}

// projectFromCamera's derivative against central differences of the projection, at random
// points in view.
void expectJacobianMatchesDifferences(const Camera& camera, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-15, 15), y(-15, 15), z(0, 2.5);
  int checked = 0;
  double worst = 0;
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d c = camera.toCamera({x(rng), y(rng), z(rng)});
    Eigen::Vector2d pixel;
    Eigen::Matrix<double, 2, 3> jacobian;
    if (!camera.projectFromCamera(c, pixel, jacobian)) continue;
    if (pixel.x() < 0 || pixel.x() > camera.width() || pixel.y() < 0 || pixel.y() > camera.height()) continue;
    EXPECT_LT((pixel - *camera.projectFromCamera(c)).norm(), 1e-12);
    constexpr double h = 1e-5;  // metres
    for (int axis = 0; axis < 3; ++axis) {
      const Eigen::Vector3d step = h * Eigen::Vector3d::Unit(axis);
      const Eigen::Vector2d difference = (*camera.projectFromCamera(c + step) - *camera.projectFromCamera(c - step)) / (2 * h);
      worst = std::max(worst, (difference - jacobian.col(axis)).norm() / std::max(1.0, difference.norm()));
    }
    ++checked;
  }
  std::cout << checked << " points in view, worst relative difference " << worst << "\n";
  EXPECT_GT(checked, 100);
  EXPECT_LT(worst, 1e-6);
}

TEST(Camera, ProjectionDerivativeMatchesDifferences) {
  const Camera pets = petsCamera();
  expectJacobianMatchesDifferences(pets, 3);
  const Camera rational(pets.intrinsics(), {-0.2, 0.05, 0.001, -0.002, 0.01, 0.02, -0.01, 0.003},
                        pets.rotation(), pets.translation(), 768, 576);
  expectJacobianMatchesDifferences(rational, 4);
}

TEST(Camera, GroundPointInvertsProjection) {
  const Camera camera = petsCamera();
  for (const Eigen::Vector2d pixel : {Eigen::Vector2d(100, 500), Eigen::Vector2d(400, 300),
                                      Eigen::Vector2d(700, 450)}) {
    const auto ground = camera.groundPoint(pixel);
    ASSERT_TRUE(ground) << pixel.transpose();
    EXPECT_NEAR(ground->z(), 0.0, 1e-9);
    const auto back = camera.project(*ground);
    ASSERT_TRUE(back);
    EXPECT_LT((*back - pixel).norm(), 1e-6) << pixel.transpose();
  }
  EXPECT_FALSE(camera.project(camera.centre() - 5 * camera.rotation().row(2).transpose()))
      << "a point behind the camera has no pixel";
}

// The calibration's units and pose, checked on the data: a 1.75 m pole standing at the foot
// of a detected person (bottom centre of the box) spans about the box's height.
TEST(Camera, PersonBoxesHaveHumanHeightsOnTheGround) {
  const Camera camera = petsCamera();
  std::ifstream boxes(kPets + "/View_001_person_boxes.csv");
  ASSERT_TRUE(boxes) << "missing " << kPets << "/View_001_person_boxes.csv";
  std::string line;
  std::getline(boxes, line);
  std::vector<double> ratios;
  while (std::getline(boxes, line)) {
    std::stringstream row(line);
    double v[8];
    char comma;
    row >> v[0];
    for (int i = 1; i < 8; ++i) row >> comma >> v[i];
    const double frame = v[0], x1 = v[1], y1 = v[2], x2 = v[3], y2 = v[4], score = v[5];
    if (frame < 600 || frame > 640 || score < 0.95 || y2 > 570) continue;  // the largest walker
    const auto foot = camera.groundPoint({0.5 * (x1 + x2), y2});
    if (!foot) continue;
    const auto head = camera.project(*foot + Eigen::Vector3d(0, 0, 1.75));
    if (!head) continue;
    ratios.push_back((y2 - head->y()) / (y2 - y1));
  }
  ASSERT_GT(ratios.size(), 20u);
  std::sort(ratios.begin(), ratios.end());
  const double median = ratios[ratios.size() / 2];
  std::cout << ratios.size() << " boxes: median projected-pole / box height " << median << "\n";
  EXPECT_GT(median, 0.85);
  EXPECT_LT(median, 1.2);
}

// save() then load() gives the same camera, in any file unit.
TEST(Camera, SavedCalibrationLoadsBack) {
  const Camera pets = petsCamera();
  const std::string path = ::testing::TempDir() + "/kneed_walker_saved_camera.yml";
  pets.save(path, 0.001);
  const Camera loaded = Camera::load(path, 0.001);
  EXPECT_EQ(loaded.intrinsics(), pets.intrinsics());
  EXPECT_EQ(loaded.distortion(), pets.distortion());
  EXPECT_EQ(loaded.rotation(), pets.rotation());
  EXPECT_LT((loaded.translation() - pets.translation()).norm(), 1e-12);
  EXPECT_EQ(loaded.width(), 768);
  EXPECT_EQ(loaded.height(), 576);
  std::remove(path.c_str());
}

// Batched rays agree with projection: a point along a pixel's ray projects to that pixel.
TEST(Camera, RaysInvertProjection) {
  const Camera pets = petsCamera();
  const std::vector<Eigen::Vector2d> pixels{{10, 20}, {384, 288}, {700, 550}};
  const std::vector<Eigen::Vector3d> rays = pets.rays(pixels);
  ASSERT_EQ(rays.size(), pixels.size());
  for (size_t i = 0; i < pixels.size(); ++i) {
    const auto back = pets.project(pets.centre() + 20.0 * rays[i].normalized());
    ASSERT_TRUE(back.has_value());
    EXPECT_LT((*back - pixels[i]).norm(), 1e-6);
  }
}

// The PETS calibration with its R rounded to `decimals`, written to a file.
std::string petsWithRoundedRotation(int decimals) {
  const Camera pets = petsCamera();
  const std::string path = ::testing::TempDir() + "/kneed_walker_rounded_" + std::to_string(decimals) + ".yml";
  pets.save(path, 0.001);
  cv::FileStorage file(path, cv::FileStorage::APPEND);
  const double scale = std::pow(10.0, decimals);
  Eigen::Matrix3d rounded = pets.rotation();
  for (int i = 0; i < 9; ++i) rounded(i) = std::round(rounded(i) * scale) / scale;
  cv::Mat r;
  cv::eigen2cv(rounded, r);
  file.release();
  // FileStorage cannot replace a key: the file is written again with the rounded R.
  cv::FileStorage in(path, cv::FileStorage::READ), out(path + ".rounded.yml", cv::FileStorage::WRITE);
  for (const char* key : {"camera_matrix", "distortion_coefficients", "t"}) {
    cv::Mat m;
    in[key] >> m;
    out << key << m;
  }
  out << "R" << r << "image_width" << static_cast<int>(in["image_width"]) << "image_height"
      << static_cast<int>(in["image_height"]);
  return path + ".rounded.yml";
}

// Real calibrations write R to a few decimals: to 5 (|RᵀR − I| about 1e-5) it is taken as the
// nearest rotation, with a warning that gives the error; to 2 it is refused with the error.
TEST(Camera, RoundedRotationsAreTakenOrRefusedBySize) {
  std::string warning;
  const Camera five = Camera::load(petsWithRoundedRotation(5), 0.001, &warning);
  EXPECT_NE(warning.find("|R^T R - I| = "), std::string::npos) << warning;
  EXPECT_LT((five.rotation().transpose() * five.rotation() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_LT((five.rotation() - petsCamera().rotation()).norm(), 1e-4);
  try {
    Camera::load(petsWithRoundedRotation(2), 0.001);
    FAIL() << "an R rounded to 2 decimals was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("R is not a rotation: |R^T R - I| = "), std::string::npos) << e.what();
  }
  warning.clear();
  Camera::load(kPets + "/View_001_camera.yml", 0.001, &warning);
  EXPECT_EQ(warning, "") << "the PETS file's R is a rotation to 1e-9";
}

TEST(Camera, BadCalibrationsAreRefusedWithTheReason) {
  const Camera pets = petsCamera();
  EXPECT_THROW(Camera(pets.intrinsics(), {0.1, 0.2, 0.3}, pets.rotation(), pets.translation(), 768,
                      576),
               std::invalid_argument);
  Eigen::Matrix3d not_rotation = pets.rotation();
  not_rotation(0, 0) += 0.1;
  EXPECT_THROW(Camera(pets.intrinsics(), {}, not_rotation, pets.translation(), 768, 576),
               std::invalid_argument);
  Eigen::Matrix3d skewed = pets.intrinsics();
  skewed(0, 1) = 2;
  try {
    Camera(skewed, {}, pets.rotation(), pets.translation(), 768, 576);
    FAIL() << "skew accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no skew"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Camera::load(kPets + "/missing.yml", 0.001), std::invalid_argument);
}

}  // namespace
}  // namespace kneed_walker::core::vision
