#include "kneed_walker/core/vision/likelihood.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <iostream>
#include <random>

#include "rendered_walk.h"

namespace kneed_walker::core::vision {
namespace {

// A person walking across the PETS camera's view over a textured ground, rendered with sensor
// noise, with a background model learned from noisy frames of the empty scene: a frame and the
// one before it, the true poses, and the evidence of the frame.
struct Scene {
  test::RenderedWalk rendered{1.0, 10, 3};
  const Camera& camera = rendered.camera;
  const synthetic::SyntheticWalk& walk = rendered.walk;
  const body::BodyShape& shape = rendered.shape;
  BackgroundModel background = BackgroundModel::learn(rendered.empty);
  AppearanceModel appearance;
  LikelihoodOptions options;
  int frame = 6;
  const cv::Mat& previous = rendered.frames[frame - 1];
  const cv::Mat& current = rendered.frames[frame];

  Scene() {
    appearance = rendered.appearanceAt(0);  // from the first frame's true outlines
  }

  FrameEvidence evidence(const LikelihoodOptions& o) const {
    cv::Mat previous_grey;
    cv::cvtColor(previous, previous_grey, cv::COLOR_BGR2GRAY);
    FrameEvidence e;
    e.compute(current, previous_grey, cv::Rect(300, 250, 400, 326), background, appearance, o);
    return e;
  }
  BodyImageAxes axes(const body::BodyPose& pose) const {
    BodyOutlines outlines;
    projectBodyParts(camera, pose, shape, outlines);
    return imageAxes(outlines);
  }
  double score(const FrameEvidence& e, const body::BodyPose& pose, const body::BodyPose& before,
               const LikelihoodOptions& o) const {
    BodyOutlines outlines;
    projectBodyParts(camera, pose, shape, outlines);
    const BodyImageAxes previous_axes = axes(before);
    return evaluateLikelihood(e, outlines, &previous_axes, o);
  }
};

const Scene& scene() {
  static const Scene s;
  return s;
}

body::BodyPose moved(body::BodyPose pose, const Eigen::Vector3d& by) {
  for (auto& j : pose.joints) j += by;
  for (auto& f : pose.foot_centres) f += by;
  return pose;
}

body::BodyPose turned(body::BodyPose pose, double angle_rad) {
  const Eigen::Vector3d centre = pose.joints[body::kWaist];
  const Eigen::AngleAxisd turn(angle_rad, Eigen::Vector3d::UnitZ());
  for (auto& j : pose.joints) j = centre + turn * (j - centre);
  for (auto& f : pose.foot_centres) f = centre + turn * (f - centre);
  pose.forward = turn * pose.forward;
  pose.left = turn * pose.left;
  return pose;
}

body::BodyPose legsSwapped(body::BodyPose pose) {
  for (int j : {body::kLeftHip, body::kLeftKnee, body::kLeftAnkle}) {
    // Each leg keeps its own hip: the other leg's hip-relative shape moves over.
    const int other = j + 1;
    std::swap(pose.joints[j], pose.joints[other]);
  }
  std::swap(pose.foot_centres[0], pose.foot_centres[1]);
  const Eigen::Vector3d hip_shift = pose.joints[body::kRightHip] - pose.joints[body::kLeftHip];
  for (int j : {body::kLeftHip, body::kLeftKnee, body::kLeftAnkle}) pose.joints[j] -= hip_shift;
  for (int j : {body::kRightHip, body::kRightKnee, body::kRightAnkle}) pose.joints[j] += hip_shift;
  pose.foot_centres[0] -= hip_shift;
  pose.foot_centres[1] += hip_shift;
  return pose;
}

TEST(Likelihood, TheTruePoseScoresHigherThanPerturbedOnes) {
  const Scene& s = scene();
  const FrameEvidence e = s.evidence(s.options);
  const body::BodyPose& truth = s.walk.frames[s.frame].pose;
  const body::BodyPose& before = s.walk.frames[s.frame - 1].pose;
  const double best = s.score(e, truth, before, s.options);
  const Eigen::Vector3d forward = truth.forward, left = truth.left;
  struct Case {
    const char* name;
    body::BodyPose pose;
  };
  const Case cases[] = {{"5 cm ahead", moved(truth, 0.05 * forward)},   {"5 cm to the left", moved(truth, 0.05 * left)},
                        {"10 cm ahead", moved(truth, 0.10 * forward)},  {"10 cm behind", moved(truth, -0.10 * forward)},
                        {"10 cm to the right", moved(truth, -0.10 * left)}, {"20 cm ahead", moved(truth, 0.20 * forward)},
                        {"20 cm to the left", moved(truth, 0.20 * left)}, {"turned 10 deg", turned(truth, 10 * M_PI / 180)},
                        {"turned -10 deg", turned(truth, -10 * M_PI / 180)}, {"legs swapped", legsSwapped(truth)}};
  for (const Case& c : cases) {
    // The perturbed pose moved the same way from its own previous pose: only the appearance
    // and the position of the flow differ.
    const double other = s.score(e, c.pose, before, s.options);
    std::cout << c.name << ": " << other << " (truth " << best << ")\n";
    EXPECT_GT(best, other) << c.name;
  }
}

TEST(Likelihood, TheFlowTermAlonePrefersTheTrueMotion) {
  const Scene& s = scene();
  LikelihoodOptions flow_only = s.options;
  flow_only.appearance_weight = 0;
  const FrameEvidence e = s.evidence(flow_only);
  ASSERT_TRUE(e.hasFlow());
  const body::BodyPose& truth = s.walk.frames[s.frame].pose;
  const body::BodyPose& before = s.walk.frames[s.frame - 1].pose;
  const Eigen::Vector3d step = truth.joints[body::kWaist] - before.joints[body::kWaist];
  const double true_motion = s.score(e, truth, before, flow_only);
  const double standing = s.score(e, truth, truth, flow_only);
  const double twice = s.score(e, truth, moved(before, -step), flow_only);
  const double backwards = s.score(e, truth, moved(truth, step), flow_only);
  std::cout << "flow term: true motion " << true_motion << ", standing " << standing << ", twice as fast "
            << twice << ", backwards " << backwards << "\n";
  EXPECT_GT(true_motion, standing);
  EXPECT_GT(true_motion, twice);
  EXPECT_GT(true_motion, backwards);
}

// Particles at an image edge, or off it, leave a region a few pixels across: the frame has no
// flow term there (DIS refuses images under 12 px), and the likelihood is still evaluated.
TEST(Likelihood, ARegionTooSmallForFlowHasNoFlowTerm) {
  const Scene& s = scene();
  cv::Mat previous_grey;
  cv::cvtColor(s.previous, previous_grey, cv::COLOR_BGR2GRAY);
  const body::BodyPose& truth = s.walk.frames[s.frame].pose;
  for (const cv::Rect& roi : {cv::Rect(760, 300, 8, 100), cv::Rect(0, 570, 300, 6), cv::Rect(900, 900, 10, 10)}) {
    FrameEvidence e;
    ASSERT_NO_THROW(e.compute(s.current, previous_grey, roi, s.background, s.appearance, s.options)) << roi;
    EXPECT_FALSE(e.hasFlow()) << roi;
    EXPECT_TRUE(std::isfinite(s.score(e, truth, s.walk.frames[s.frame - 1].pose, s.options))) << roi;
  }
  const FrameEvidence whole = s.evidence(s.options);
  EXPECT_TRUE(whole.hasFlow());
}

TEST(Likelihood, HiddenPartsAndOutsidePixelsAreCounted) {
  const Scene& s = scene();
  const FrameEvidence e = s.evidence(s.options);
  const body::BodyPose& truth = s.walk.frames[s.frame].pose;
  BodyOutlines outlines;
  projectBodyParts(s.camera, truth, s.shape, outlines);
  PartScores scores;
  evaluateLikelihood(e, outlines, nullptr, s.options, &scores);
  // The torso is seen whole and scores as foreground; no flow without a previous body.
  EXPECT_GT(scores[body::kTorsoPart].pixels, 200);
  EXPECT_GT(scores[body::kTorsoPart].appearance, 1.0);
  EXPECT_EQ(scores[body::kTorsoPart].flow_points, 0);
  // The body far outside the evidence's region scores every pixel as outside.
  BodyOutlines away;
  projectBodyParts(s.camera, moved(truth, Eigen::Vector3d(0, 0, 0) + 8.0 * truth.left), s.shape, away);
  PartScores outside;
  evaluateLikelihood(e, away, nullptr, s.options, &outside);
  EXPECT_NEAR(outside[body::kTorsoPart].appearance, s.options.outside_ratio, 1e-9);
}

// With reference areas a part's appearance is its sum over the reference area: a torso shrunk
// to half its width inside the person (a body too far away) keeps its average but loses half its
// score; without them (zero) the score is the average over the part's own pixels.
TEST(Likelihood, AReferenceAreaMakesAShrunkPartLoseTheFigureItLeaves) {
  const Scene& s = scene();
  FrameEvidence e = s.evidence(s.options);
  BodyOutlines outlines;
  projectBodyParts(s.camera, s.walk.frames[s.frame].pose, s.shape, outlines);
  const PartAreas areas = partAreas(outlines);
  EXPECT_GT(areas[body::kTorsoPart], 200);
  BodyOutlines shrunk = outlines;
  PartOutline& torso = shrunk[body::kTorsoPart];
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (int i = 0; i < torso.size; ++i) centre += torso.hull[i];
  centre /= torso.size;
  for (int i = 0; i < torso.size; ++i) torso.hull[i].x() = centre.x() + 0.5 * (torso.hull[i].x() - centre.x());
  PartScores whole, half;
  evaluateLikelihood(e, outlines, nullptr, s.options, &whole);
  evaluateLikelihood(e, shrunk, nullptr, s.options, &half);
  const int t = body::kTorsoPart;
  EXPECT_GT(half[t].appearance, 0.8 * whole[t].appearance) << "an average does not mind the shrinking";
  e.setReferenceAreas(areas);
  evaluateLikelihood(e, outlines, nullptr, s.options, &whole);
  evaluateLikelihood(e, shrunk, nullptr, s.options, &half);
  EXPECT_GT(whole[t].appearance, 1.0);
  EXPECT_LT(half[t].appearance, 0.65 * whole[t].appearance) << "a sum over the reference area does";
  EXPECT_NEAR(half[t].pixels, 0.5 * whole[t].pixels, 0.15 * whole[t].pixels);
}

// Occlusion: of two parts with the same outline, the nearer one has the pixels and the farther
// one is hidden behind it, whichever parts they are (the far leg behind the near one, paper §4).
TEST(Likelihood, ANearerPartHidesAFartherOne) {
  const Scene& s = scene();
  const FrameEvidence e = s.evidence(s.options);
  BodyOutlines outlines;
  projectBodyParts(s.camera, s.walk.frames[s.frame].pose, s.shape, outlines);
  for (const bool left_nearer : {true, false}) {
    BodyOutlines overlapping = outlines;
    const int near = left_nearer ? body::kLeftThighPart : body::kRightThighPart;
    const int far = left_nearer ? body::kRightThighPart : body::kLeftThighPart;
    overlapping[far] = overlapping[near];
    overlapping[far].depth_m = overlapping[near].depth_m + 0.5;
    PartScores scores;
    evaluateLikelihood(e, overlapping, nullptr, s.options, &scores);
    EXPECT_GT(scores[near].pixels, 50) << (left_nearer ? "left" : "right") << " thigh nearer";
    EXPECT_EQ(scores[far].pixels, 0) << (left_nearer ? "right" : "left") << " thigh behind it";
  }
}

// rasterize() against the definition: a pixel belongs to an outline when its centre (integer
// coordinates) lies inside or on it. Random convex outlines in any position, in either order
// (clockwise or not), and ones with vertices and level edges exactly on pixel rows.
TEST(Rasterize, CoversExactlyThePixelCentresInsideTheOutline) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-20.0, 60.0);
  auto check = [](const std::vector<cv::Point2f>& corners, const std::string& name, bool clockwise = false) {
    std::vector<cv::Point2f> hull;  // cv::convexHull takes float points
    cv::convexHull(corners, hull, clockwise);
    PartOutline outline;
    outline.visible = true;
    outline.size = static_cast<int>(hull.size());
    for (int i = 0; i < outline.size; ++i) outline.hull[i] = {hull[i].x, hull[i].y};
    RowSpans spans;
    rasterize(outline, spans);
    int inside = 0, wrong = 0;
    for (int y = -40; y < 80; ++y)
      for (int x = -40; x < 80; ++x) {
        const int k = y - spans.first_row;
        const bool in_spans = k >= 0 && k < spans.rows && x >= spans.left[k] && x < spans.right[k];
        const double distance = cv::pointPolygonTest(hull, cv::Point2f(x, y), true);
        if (std::abs(distance) < 1e-4) continue;  // on the outline (to float precision): either way
        inside += distance > 0;
        if (in_spans != (distance > 0) && wrong++ == 0)
          ADD_FAILURE() << name << ": pixel (" << x << ", " << y << ") " << (in_spans ? "in" : "not in")
                        << " the spans, distance " << distance;
      }
    EXPECT_EQ(wrong, 0) << name;
    return inside;
  };
  int covered = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<cv::Point2f> corners(3 + trial % 14);
    for (auto& c : corners) c = cv::Point2d(coordinate(random), coordinate(random));
    covered += check(corners, "random outline " + std::to_string(trial), trial % 2 == 1);
  }
  EXPECT_GT(covered, 100000);
  // Pixels strictly inside: 9 × 5 for the square; 8, 6, 4, 4 and 2 on rows 4 to 8 for the triangle.
  EXPECT_EQ(check({{2, 3}, {12, 3}, {12, 9}, {2, 9}}, "square on pixel rows"), 45);
  EXPECT_EQ(check({{2.5, 3}, {12.5, 3}, {7.5, 9}}, "triangle with a level top edge"), 24);
  check({{0, 0}, {10.5, 4}, {3, 11}, {-6.5, 4}}, "diamond with vertices on rows");
  // Pixels on the outline are its own: the square's spans are rows 3 to 9, columns 2 to 12.
  PartOutline square;
  square.visible = true;
  square.size = 4;
  square.hull[0] = {2, 3}, square.hull[1] = {2, 9}, square.hull[2] = {12, 9}, square.hull[3] = {12, 3};
  RowSpans spans;
  rasterize(square, spans);
  EXPECT_EQ(spans.first_row, 3);
  ASSERT_EQ(spans.rows, 7);
  for (int k = 0; k < spans.rows; ++k) {
    EXPECT_EQ(spans.left[k], 2) << "row " << 3 + k;
    EXPECT_EQ(spans.right[k], 13) << "row " << 3 + k;
  }
}

}  // namespace
}  // namespace kneed_walker::core::vision
