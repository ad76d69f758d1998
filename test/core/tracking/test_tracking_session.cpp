#include "kneed_walker/core/tracking/tracking_session.h"

#include <gtest/gtest.h>

#include <iostream>

#include <algorithm>
#include <cmath>
#include <memory>

#include "rendered_walk.h"

namespace kneed_walker::core::tracking {
namespace {

const test::RenderedWalk& scene() {
  static const test::RenderedWalk walk(2.5, 10, 4);
  return walk;
}

std::unique_ptr<Tracker> makeTracker(int particles, bool keep_whole_path = false) {
  const test::RenderedWalk& s = scene();
  TrackerOptions options;
  options.num_particles = particles;
  options.keep_whole_path = keep_whole_path;
  options.resample_ess_threshold = particles / 10.0;
  return std::make_unique<Tracker>(
      s.camera, s.walk.ground, gait::loadGaitTable(test::configFile("prior_gait_table.yaml"), test::shippedWalkerModel()),
      prior::loadPriorOptions(test::configFile("prior.yaml")), options);
}

SessionOptions holding(int frames) {
  SessionOptions options;
  options.background_frames = frames;
  return options;
}

// Feeds the whole walk; returns every answer.
std::vector<SessionAnswer> run(TrackingSession& session) {
  const test::RenderedWalk& s = scene();
  std::vector<SessionAnswer> answers;
  for (size_t f = 0; f < s.frames.size(); ++f)
    for (SessionAnswer& a : session.feed(s.frames[f], 0.1 * f)) answers.push_back(std::move(a));
  return answers;
}

TEST(TrackingSession, HoldsFramesToLearnTheBackgroundThenAnswersEachOnceInOrder) {
  const test::RenderedWalk& s = scene();
  TrackingSession session(makeTracker(200), holding(8));
  for (int f = 0; f < 7; ++f) {
    EXPECT_TRUE(session.feed(s.frames[f], 0.1 * f).empty());
    EXPECT_EQ(session.state(), SessionState::kLearningBackground);
  }
  const std::vector<SessionAnswer> answers = session.feed(s.frames[7], 0.7);
  ASSERT_EQ(answers.size(), 8u);
  for (int f = 0; f < 8; ++f) {
    EXPECT_EQ(answers[f].input, f);
    EXPECT_DOUBLE_EQ(answers[f].stamp_s, 0.1 * f);
  }
  EXPECT_FALSE(session.tracker().background().empty());
  EXPECT_EQ(session.feed(s.frames[8], 0.8).size(), 1u);
}

TEST(TrackingSession, FindsTheWalkerByItselfAndFollowsHer) {
  const test::RenderedWalk& s = scene();
  SessionOptions options = holding(10);
  TrackingSession session(makeTracker(600), options);
  const std::vector<SessionAnswer> answers = run(session);
  ASSERT_EQ(answers.size(), s.frames.size());
  int started_at = -1;
  double error_m = 0;
  int tracked = 0;
  for (const SessionAnswer& a : answers) {
    if (a.started && started_at < 0) started_at = a.input;
    if (a.state != SessionState::kTracking) continue;
    error_m += (a.estimate->pose.joints[body::kWaist] - s.walk.frames[a.input].pose.joints[body::kWaist]).norm();
    ++tracked;
  }
  // The person is found once her blob has been seen heading_frames apart.
  EXPECT_EQ(started_at, options.heading_frames);
  for (int f = 0; f < started_at; ++f) EXPECT_EQ(answers[f].state, SessionState::kWaitingForPerson);
  ASSERT_GT(tracked, 10);
  std::cout << "found at frame " << started_at << "; mean waist error " << 1000 * error_m / tracked << " mm over "
            << tracked << " frames\n";
  EXPECT_LT(error_m / tracked, 0.35);
}

// The person's box in the first frame, from the truth's joints.
cv::Rect2d truthBox() {
  const test::RenderedWalk& s = scene();
  cv::Rect2d box;
  for (const Eigen::Vector3d& joint : s.walk.frames[0].pose.joints) {
    const Eigen::Vector2d px = *s.camera.project(joint);
    box = box.area() == 0 ? cv::Rect2d(px.x(), px.y(), 1, 1) : box | cv::Rect2d(px.x(), px.y(), 1, 1);
  }
  return box;
}

TEST(TrackingSession, GivesEveryTrackedFrameOneMapFrame) {
  TrackingSession session(makeTracker(200), holding(10));
  session.startFromBox(truthBox());
  std::vector<int> estimated, mapped;
  for (const SessionAnswer& a : run(session)) {
    if (a.estimate) estimated.push_back(a.input);
    for (const MapFrame& m : a.map_frames) mapped.push_back(m.input);
  }
  for (const MapFrame& m : session.finish()) mapped.push_back(m.input);
  ASSERT_FALSE(estimated.empty());
  EXPECT_EQ(estimated.front(), 0);  // started at once from the box
  std::sort(mapped.begin(), mapped.end());
  EXPECT_EQ(mapped, estimated);
  EXPECT_FALSE(session.tracker().started());
}

// Mean slip of the planted foot between frames (as evaluate's footskate): a foot on the ground
// in both frames moves only by rolling (−R Δφ along the walk) unless it slips.
double meanSlipM(const std::vector<MapFrame>& frames) {
  const body::FootGeometry foot = body::FootGeometry::of(test::shippedWalkerModel(), 1.75);
  double sum = 0;
  int pairs = 0;
  for (size_t i = 1; i < frames.size(); ++i) {
    const body::BodyPose &a = frames[i - 1].pose, &b = frames[i].pose;
    double least = -1;
    for (int side : {0, 1}) {
      const body::RollingFoot fa = body::rollingFoot(a.joints[body::kLeftKnee + side], a.joints[body::kLeftAnkle + side], a.forward, a.up, foot);
      const body::RollingFoot fb = body::rollingFoot(b.joints[body::kLeftKnee + side], b.joints[body::kLeftAnkle + side], b.forward, b.up, foot);
      if (fa.centre_m.z() - foot.radius_m > 0.005 || fb.centre_m.z() - foot.radius_m > 0.005) continue;  // level ground Z = 0
      Eigen::Vector3d slip = fb.centre_m - fa.centre_m + foot.radius_m * (fb.roll_rad - fa.roll_rad) * b.forward;
      slip.z() = 0;
      if (least < 0 || slip.norm() < least) least = slip.norm();
    }
    if (least >= 0) sum += least, ++pairs;
  }
  return pairs ? sum / pairs : 0.0;
}

// Keeping the whole path, the session gives the track's MAP frames all at its end: one per
// tracked frame, in order, and one particle's path, whose planted foot rolls without slipping
// as the prior moves it; the frame-by-frame lagged output of the same run switches between
// particles' ancestries, and its feet slip.
TEST(TrackingSession, KeepingTheWholePathGivesOneParticlesPathAtTheEnd) {
  TrackingSession whole(makeTracker(200, true), holding(10)), lagged(makeTracker(200), holding(10));
  whole.startFromBox(truthBox());
  lagged.startFromBox(truthBox());
  std::vector<int> estimated;
  for (const SessionAnswer& a : run(whole)) {
    if (a.estimate) estimated.push_back(a.input);
    EXPECT_TRUE(a.map_frames.empty()) << "frame " << a.input << ": MAP frames before the track ended";
  }
  const std::vector<MapFrame> path = whole.finish();
  std::vector<int> mapped;
  for (const MapFrame& m : path) mapped.push_back(m.input);
  EXPECT_EQ(mapped, estimated);
  ASSERT_GT(path.size(), 10u);
  // Same seed and frames: the filter ran identically; only which states are output differs.
  std::vector<MapFrame> lagged_path;
  for (const SessionAnswer& a : run(lagged))
    for (const MapFrame& m : a.map_frames) lagged_path.push_back(m);
  for (const MapFrame& m : lagged.finish()) lagged_path.push_back(m);
  ASSERT_EQ(lagged_path.size(), path.size());
  EXPECT_EQ(path.back().pose.joints[body::kWaist], lagged_path.back().pose.joints[body::kWaist]);
  std::cout << "mean slip of the planted foot: whole path " << 1e3 * meanSlipM(path) << " mm, lagged "
            << 1e3 * meanSlipM(lagged_path) << " mm\n";
  EXPECT_LT(meanSlipM(path), 0.002);
  EXPECT_GT(meanSlipM(lagged_path), 2 * meanSlipM(path));
}

// A box around no person cannot start a track: the frame is answered (waiting, saying why),
// frames keep their numbers, and the session looks for the person instead.
TEST(TrackingSession, ABoxAroundNobodyIsAnsweredAndThePersonFoundInstead) {
  TrackingSession session(makeTracker(100), holding(10));
  session.startFromBox(cv::Rect2d(0, 300, 10, 5));  // an empty corner of the ground
  const std::vector<SessionAnswer> answers = run(session);
  ASSERT_EQ(answers.size(), scene().frames.size());
  for (size_t f = 0; f < answers.size(); ++f) EXPECT_EQ(answers[f].input, static_cast<int>(f));
  EXPECT_TRUE(answers[0].start_failed);
  EXPECT_EQ(answers[0].state, SessionState::kWaitingForPerson);
  EXPECT_NE(answers[0].message.find("could not start"), std::string::npos) << answers[0].message;
  EXPECT_TRUE(std::any_of(answers.begin(), answers.end(), [](const SessionAnswer& a) { return a.started; }));
}

TEST(TrackingSession, SameFramesAndSeedGiveTheSameAnswers) {
  TrackingSession a(makeTracker(200), holding(10)), b(makeTracker(200), holding(10));
  const std::vector<SessionAnswer> first = run(a), second = run(b);
  ASSERT_EQ(first.size(), second.size());
  for (size_t f = 0; f < first.size(); ++f) {
    ASSERT_EQ(first[f].state, second[f].state);
    if (first[f].estimate)
      for (int j = 0; j < body::kNumBodyJoints; ++j)
        EXPECT_EQ(first[f].estimate->pose.joints[j], second[f].estimate->pose.joints[j]);
  }
}

TEST(TrackingSession, ResetStartsOverAndRefusesAFrameOfAnotherSize) {
  const test::RenderedWalk& s = scene();
  TrackingSession session(makeTracker(100), holding(3));
  for (int f = 0; f < 5; ++f) session.feed(s.frames[f], 0.1 * f);
  EXPECT_THROW(session.feed(cv::Mat(10, 10, CV_8UC3), 0.5), std::invalid_argument);
  EXPECT_THROW(session.feed(s.frames[5], std::nan("")), std::invalid_argument);
  EXPECT_EQ(session.framesFed(), 5);
  session.reset();  // a bag looped
  EXPECT_EQ(session.framesFed(), 0);
  EXPECT_EQ(session.state(), SessionState::kLearningBackground);
  EXPECT_TRUE(session.feed(s.frames[0], 0.0).empty());
}

// A track started from a box, or from a person the session finds, starts on the gaits of the
// options' speed range: at 4.5-4.5 km/h the first answer's MAP gait walks 4.5 km/h, whichever way
// it was started.
TEST(TrackingSession, StartsOnTheOptionsSpeedRange) {
  for (const bool from_box : {true, false}) {
    SessionOptions options = holding(10);
    options.min_start_speed_kmh = options.max_start_speed_kmh = 4.5;
    TrackingSession session(makeTracker(100), options);
    if (from_box) session.startFromBox(truthBox());
    bool checked = false;
    for (const SessionAnswer& a : run(session))
      if (a.started && !checked) {
        EXPECT_EQ(a.estimate->speed_kmh, 4.5) << (from_box ? "from a box" : "found");
        checked = true;
      }
    EXPECT_TRUE(checked) << (from_box ? "from a box" : "found") << ": no track started";
  }
}

TEST(TrackingSession, RefusesBadOptionsNamingThem) {
  SessionOptions options;
  options.background_frames = 0;
  options.min_start_speed_kmh = 5;
  options.max_start_speed_kmh = 4;
  options.min_walk_m = std::nan("");
  try {
    TrackingSession session(makeTracker(10), options);
    FAIL() << "accepted bad options";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("background_frames"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("min_walk_m"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("min_start_speed_kmh and max_start_speed_kmh"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace kneed_walker::core::tracking
