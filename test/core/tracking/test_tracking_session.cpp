#include "kneed_walker/core/tracking/tracking_session.h"

#include <gtest/gtest.h>

#include <iostream>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <map>
#include <set>

#include "rendered_walk.h"

namespace kneed_walker::core::tracking {
namespace {

const test::RenderedWalk& scene() {
  static const test::RenderedWalk walk(2.5, 10, 4);
  return walk;
}

TrackerFactory makeTracker(int particles, bool keep_whole_path = false, double lost_likelihood_fraction = 0) {
  const test::RenderedWalk& s = scene();
  TrackerOptions options;
  options.filter.num_particles = particles;
  options.lost_likelihood_fraction = lost_likelihood_fraction;
  options.filter.keep_paths = keep_whole_path;
  return trackerFactory(s.camera, s.walk.ground,
                        gait::loadGaitTable(test::configFile("prior_gait_table.yaml"), test::shippedWalkerModel()),
                        prior::loadPriorOptions(test::configFile("prior.yaml")), options);
}

// Body 1's estimate at a frame, or nullptr.
const TrackEstimate* estimateOf(const SessionAnswer& a) {
  const PersonAnswer* p = a.person(1);
  return p && p->estimate ? &*p->estimate : nullptr;
}

// Body 1's MAP frames given at a frame, or at the end.
std::vector<MapFrame> mapFramesOf(const std::vector<PersonAnswer>& people) {
  std::vector<MapFrame> frames;
  for (const PersonAnswer& p : people)
    if (p.body == 1) frames.insert(frames.end(), p.map_frames.begin(), p.map_frames.end());
  return frames;
}

// Holding `frames` to learn the background from; the person's height the tracker's (the
// rendered person's, 1.75 m), not measured.
SessionOptions holding(int frames) {
  SessionOptions options;
  options.background_frames = frames;
  options.estimate_person_height = false;
  return options;
}

// Feeds the whole walk; returns every answer (flushing those held at the end).
std::vector<SessionAnswer> run(TrackingSession& session) {
  const test::RenderedWalk& s = scene();
  std::vector<SessionAnswer> answers;
  for (size_t f = 0; f < s.frames.size(); ++f)
    for (SessionAnswer& a : session.feed(s.frames[f], 0.1 * f)) answers.push_back(std::move(a));
  for (SessionAnswer& a : session.flushHeld()) answers.push_back(std::move(a));
  return answers;
}

TEST(TrackingSession, HoldsFramesToLearnTheBackgroundThenAnswersEachOnceInOrder) {
  const test::RenderedWalk& s = scene();
  SessionOptions options = holding(8);
  options.find_people = false;  // no track starts (whose frames would be held too)
  TrackingSession session(makeTracker(200), options);
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
    if (a.started() && started_at < 0) started_at = a.input;
    if (a.state != SessionState::kTracking) continue;
    error_m += (estimateOf(a)->pose.joints[body::kWaist] - s.walk.frames[a.input].pose.joints[body::kWaist]).norm();
    ++tracked;
  }
  // The person is found once her blob has been seen heading_frames apart.
  EXPECT_EQ(started_at, options.heading_frames);
  for (int f = 0; f < started_at; ++f) EXPECT_EQ(answers[f].state, SessionState::kWaitingForPerson);
  ASSERT_GT(tracked, 10);
  std::cout << "found at frame " << started_at << "; mean waist error " << 1000 * error_m / tracked << " mm over "
            << tracked << " frames\n";
  // Measured 181 mm (2026-12-01); loose on purpose, as Tracker.FollowsASyntheticWalk's bound.
  EXPECT_LT(error_m / tracked, 0.35);
}

// The person's box in a frame, from the truth's joints.
cv::Rect2d truthBox(int frame = 0) {
  const test::RenderedWalk& s = scene();
  cv::Rect2d box;
  for (const Eigen::Vector3d& joint : s.walk.frames[frame].pose.joints) {
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
    if (estimateOf(a)) estimated.push_back(a.input);
    for (const MapFrame& m : mapFramesOf(a.people)) mapped.push_back(m.input);
  }
  for (const MapFrame& m : mapFramesOf(session.finish())) mapped.push_back(m.input);
  ASSERT_FALSE(estimated.empty());
  EXPECT_EQ(estimated.front(), 0);  // started at once from the box
  std::sort(mapped.begin(), mapped.end());
  EXPECT_EQ(mapped, estimated);
  EXPECT_FALSE(session.tracker().started());
}

// Median slip of the planted foot between frames (as evaluate's footskate, per pair of frames):
// a foot on the ground in both frames moves only by rolling (−R Δφ along the walk) unless it
// slips. The median, not the mean: a pair of frames around a brisk heel strike can find the old
// stance foot already lifted and the landing foot, still swinging, within the contact margin
// in both frames: one pair scores the swing (240 mm in one frame of a 0.6 mm path).
double medianSlipM(const std::vector<MapFrame>& frames) {
  const body::FootGeometry foot = body::FootGeometry::of(test::shippedWalkerModel(), 1.75);
  std::vector<double> slips;
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
    if (least >= 0) slips.push_back(least);
  }
  if (slips.empty()) return 0.0;
  std::nth_element(slips.begin(), slips.begin() + slips.size() / 2, slips.end());
  return slips[slips.size() / 2];
}

// Keeping the whole path, the session gives the track's MAP frames all at its end: one per
// tracked frame, in order, and one particle's path, whose planted foot rolls without slipping
// as the prior moves it; the frame-by-frame lagged output of the same run switches between
// particles' ancestries when another weighs far more, and its feet slip more. The track must hold for that: with 500
// particles it held on 7 of the seeds 1-8 (2026-12-02, the outlines from the camera's
// derivative: median slip 0.39-1.01 mm whole, 1.6-12 mm lagged; before them 0.49-0.86 and
// 1.7-40 on all 8).
TEST(TrackingSession, KeepingTheWholePathGivesOneParticlesPathAtTheEnd) {
  TrackingSession whole(makeTracker(500, true), holding(10)), lagged(makeTracker(500), holding(10));
  whole.startFromBox(truthBox());
  lagged.startFromBox(truthBox());
  std::vector<int> estimated;
  for (const SessionAnswer& a : run(whole)) {
    if (estimateOf(a)) estimated.push_back(a.input);
    EXPECT_TRUE(mapFramesOf(a.people).empty()) << "frame " << a.input << ": MAP frames before the track ended";
  }
  const std::vector<MapFrame> path = mapFramesOf(whole.finish());
  std::vector<int> mapped;
  for (const MapFrame& m : path) mapped.push_back(m.input);
  EXPECT_EQ(mapped, estimated);
  ASSERT_GT(path.size(), 10u);
  // Same seed and frames: the filter ran identically; only which states are output differs.
  std::vector<MapFrame> lagged_path;
  for (const SessionAnswer& a : run(lagged))
    for (const MapFrame& m : mapFramesOf(a.people)) lagged_path.push_back(m);
  for (const MapFrame& m : mapFramesOf(lagged.finish())) lagged_path.push_back(m);
  ASSERT_EQ(lagged_path.size(), path.size());
  EXPECT_EQ(path.back().input, lagged_path.back().input);
  std::cout << "median slip of the planted foot: whole path " << 1e3 * medianSlipM(path) << " mm, lagged "
            << 1e3 * medianSlipM(lagged_path) << " mm\n";
  EXPECT_LT(medianSlipM(path), 0.002);  // measured 0.64 mm; 1.06 mm lagged
  EXPECT_GT(medianSlipM(lagged_path), medianSlipM(path));
}

// A box starts a track from its person's ground track a second later (start_window_s): the
// frames meanwhile are held, their answers too, then all answered at once, tracked from the
// box's frame; the particles start walking the way the ground track saw the person go.
TEST(TrackingSession, ABoxStartsFromItsGroundTrackAfterTheWindowAndAnswersEveryFrame) {
  const test::RenderedWalk& s = scene();
  TrackingSession session(makeTracker(300), holding(4));
  session.startFromBox(truthBox());
  std::vector<SessionAnswer> answers;
  for (int f = 0; f <= 10; ++f) {
    std::vector<SessionAnswer> now = session.feed(s.frames[f], 0.1 * f);
    if (f < 10) {
      EXPECT_TRUE(now.empty()) << "frame " << f;
      if (f >= 3) EXPECT_EQ(session.state(), SessionState::kStartingTrack) << "frame " << f;
    }
    for (SessionAnswer& a : now) answers.push_back(std::move(a));
  }
  ASSERT_EQ(answers.size(), 11u);
  for (int f = 0; f <= 10; ++f) {
    EXPECT_EQ(answers[f].input, f);
    ASSERT_NE(estimateOf(answers[f]), nullptr) << "frame " << f;
    EXPECT_EQ(answers[f].state, SessionState::kTracking);
    EXPECT_EQ(answers[f].person(1)->started, f == 0);
  }
  const std::string& message = answers[0].person(1)->message;
  std::cout << message << "\n";
  EXPECT_NE(message.find("from its ground track"), std::string::npos) << message;
  EXPECT_EQ(message.find("heading unknown"), std::string::npos) << message;
  const Eigen::Vector2d walked =
      (s.walk.frames[10].pose.joints[body::kWaist] - s.walk.frames[0].pose.joints[body::kWaist]).head<2>();
  const double heading_error =
      std::remainder(estimateOf(answers[10])->heading_rad - std::atan2(walked.y(), walked.x()), 2 * M_PI);
  std::cout << "heading error at frame 10: " << heading_error * 180 / M_PI << " deg\n";
  EXPECT_LT(std::abs(heading_error), 0.25);
  EXPECT_EQ(session.state(), SessionState::kTracking);
  EXPECT_EQ(session.feed(s.frames[11], 1.1).size(), 1u);
}

// Each tracked frame carries its person's ground track (filtered); with the whole path kept,
// each track's end (a loss, the input's end) gives it smoothed, one per tracked frame, near the
// true waist.
TEST(TrackingSession, ATrackCarriesItsPersonsGroundTrack) {
  const test::RenderedWalk& s = scene();
  TrackingSession session(makeTracker(300, true), holding(10));
  session.startFromBox(truthBox());
  std::vector<int> tracked, smoothed_inputs;
  std::vector<double> errors;
  const auto collect = [&](const PersonAnswer& person) {
    for (const auto& [input, estimate] : person.ground_track_smoothed) {
      smoothed_inputs.push_back(input);
      errors.push_back((estimate.position() - s.walk.frames[input].pose.joints[body::kWaist].head<2>()).norm());
    }
  };
  for (const SessionAnswer& a : run(session)) {
    const PersonAnswer* person = a.person(1);
    if (!person) continue;
    collect(*person);
    if (!person->estimate) continue;
    tracked.push_back(a.input);
    ASSERT_TRUE(person->ground_track) << "frame " << a.input;
  }
  for (const PersonAnswer& person : session.finish()) collect(person);
  std::sort(smoothed_inputs.begin(), smoothed_inputs.end());
  EXPECT_EQ(smoothed_inputs, tracked);
  ASSERT_FALSE(errors.empty());
  std::sort(errors.begin(), errors.end());
  std::cout << "ground track, smoothed: median waist error " << 1e3 * errors[errors.size() / 2] << " mm\n";
  EXPECT_LT(errors[errors.size() / 2], 0.15);  // measured 83 mm
}

// Without a height given, a track's person height is the stature their ground track measures at
// its first frame; given (estimate_person_height false), person_height_m. The options' default
// here (1.50 m) is not the rendered person's (1.75 m).
TEST(TrackingSession, APersonsHeightIsMeasuredUnlessGiven) {
  const test::RenderedWalk& s = scene();
  TrackerOptions options;
  options.filter.num_particles = 200;
  options.person_height_m = 1.50;
  const TrackerFactory factory = trackerFactory(
      s.camera, s.walk.ground, gait::loadGaitTable(test::configFile("prior_gait_table.yaml"), test::shippedWalkerModel()),
      prior::loadPriorOptions(test::configFile("prior.yaml")), options);
  for (const bool estimate : {true, false}) {
    SessionOptions session_options = holding(10);
    session_options.estimate_person_height = estimate;
    TrackingSession session(factory, session_options);
    session.startFromBox(truthBox());
    std::string started;
    for (size_t f = 0; f < 12 && started.empty(); ++f)
      for (const SessionAnswer& a : session.feed(s.frames[f], 0.1 * f))
        if (const PersonAnswer* person = a.person(1); person && person->started && started.empty()) started = person->message;
    ASSERT_FALSE(started.empty()) << "no track started";
    const double height_m = session.tracker(1).personHeightM();
    std::cout << (estimate ? "measured: " : "given: ") << started << "\n";
    if (estimate) {
      EXPECT_NEAR(height_m, 1.75, 0.05) << started;
      EXPECT_NE(started.find("(measured)"), std::string::npos) << started;
    } else {
      EXPECT_EQ(height_m, 1.50) << started;
      EXPECT_EQ(started.find("(measured)"), std::string::npos) << started;
    }
  }
}

// A box around no person cannot start a track: when its start is due (the end of its ground
// track's window: 1 s, frame 10) the frame is answered (waiting, saying why), frames keep their
// numbers, and the session looks for the person instead.
TEST(TrackingSession, ABoxAroundNobodyIsAnsweredAndThePersonFoundInstead) {
  TrackingSession session(makeTracker(100), holding(10));
  session.startFromBox(cv::Rect2d(0, 300, 10, 5));  // an empty corner of the ground
  const std::vector<SessionAnswer> answers = run(session);
  ASSERT_EQ(answers.size(), scene().frames.size());
  for (size_t f = 0; f < answers.size(); ++f) EXPECT_EQ(answers[f].input, static_cast<int>(f));
  const auto failed = std::find_if(answers.begin(), answers.end(), [](const SessionAnswer& a) { return a.start_failed; });
  ASSERT_NE(failed, answers.end());
  EXPECT_EQ(failed->input, 10);
  EXPECT_EQ(failed->state, SessionState::kWaitingForPerson);
  EXPECT_NE(failed->message.find("could not start"), std::string::npos) << failed->message;
  for (auto a = answers.begin(); a != failed; ++a) EXPECT_EQ(a->state, SessionState::kWaitingForPerson) << a->input;
  EXPECT_TRUE(std::any_of(answers.begin(), answers.end(), [](const SessionAnswer& a) { return a.started(); }));
}

TEST(TrackingSession, SameFramesAndSeedGiveTheSameAnswers) {
  TrackingSession a(makeTracker(200), holding(10)), b(makeTracker(200), holding(10));
  const std::vector<SessionAnswer> first = run(a), second = run(b);
  ASSERT_EQ(first.size(), second.size());
  for (size_t f = 0; f < first.size(); ++f) {
    ASSERT_EQ(first[f].state, second[f].state);
    if (estimateOf(first[f]))
      for (int j = 0; j < body::kNumBodyJoints; ++j)
        EXPECT_EQ(estimateOf(first[f])->pose.joints[j], estimateOf(second[f])->pose.joints[j]);
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
      if (a.started() && !checked) {
        EXPECT_EQ(estimateOf(a)->speed_kmh, 4.5) << (from_box ? "from a box" : "found");
        checked = true;
      }
    EXPECT_TRUE(checked) << (from_box ? "from a box" : "found") << ": no track started";
  }
}

const test::RenderedWalk& twoPeople() {
  static const test::RenderedWalk walk(2.5, 10, 4, true);
  return walk;
}

// What a session made of two people walking the other way from each other, 7 m apart, with up
// to three tracks: a frame below 0.9 of a track's recent median log-likelihood ratio counts
// towards its loss (lost_likelihood_fraction), so that tracks are lost while their people are in
// view. After input `skip_after` the video skips `skipped` frames (the stamps do not: a camera
// that dropped them), so that the people jump on.
struct TwoPeopleRun {
  std::array<int, 2> followed{0, 0};       // inputs from which a track is within 0.5 m of the person
  std::array<double, 2> error_m{0, 0};     // the mean waist error over those
  size_t bodies = 0;
  int most_tracks = 0, lost = 0, found_again = 0;
};
TwoPeopleRun runTwoPeople(size_t skip_after, size_t skipped) {
  const test::RenderedWalk& s = twoPeople();
  SessionOptions options = holding(10);
  options.max_people = 3;
  TrackingSession session(makeTracker(400, false, 0.9), options);
  TwoPeopleRun run;
  std::set<int> bodies;
  std::set<std::pair<int, int>> lost;  // (input, body)
  std::map<int, int> last_track;       // body: the track of its last estimate
  auto shown = [&](size_t input) { return input <= skip_after ? input : input + skipped; };  // the walk's frame
  for (size_t i = 0; shown(i) < s.frames.size(); ++i)
    for (const SessionAnswer& a : session.feed(s.frames[shown(i)], 0.1 * i)) {
      for (const PersonAnswer& p : a.people) {
        if (p.ended && p.estimate && p.estimate->lost) lost.insert({a.input, p.body});
        if (p.started && p.message.find("found again where lost") != std::string::npos) {
          EXPECT_TRUE(lost.count({a.input - 1, p.body})) << "input " << a.input << ": body " << p.body << " " << p.message;
          EXPECT_GE(p.track, 2) << "a track started again is a new track of its body";
          ++run.found_again;
        }
        // Each body's tracks are numbered from 1, a new one at each start; MAP frames carry
        // theirs (at a start, the ended track's last ones).
        if (!p.estimate) continue;
        EXPECT_EQ(p.track, last_track[p.body] + (p.started ? 1 : 0)) << "input " << a.input << ": body " << p.body;
        last_track[p.body] = p.track;
        for (const MapFrame& f : p.map_frames)
          EXPECT_TRUE(f.track == p.track || (p.started && f.track == p.track - 1))
              << "input " << a.input << ": body " << p.body << " track " << p.track << ", MAP frame's " << f.track;
      }
      int tracks = 0;
      // Each person's nearest track (followed when within 0.5 m).
      std::array<double, 2> nearest{0.5, 0.5};
      for (const PersonAnswer& p : a.people) {
        if (!p.estimate || p.ended) continue;
        ++tracks;
        bodies.insert(p.body);
        const Eigen::Vector3d waist = p.estimate->pose.joints[body::kWaist];
        nearest[0] = std::min(nearest[0], (waist - s.walk.frames[shown(a.input)].pose.joints[body::kWaist]).norm());
        nearest[1] = std::min(nearest[1], (waist - s.second->frames[shown(a.input)].pose.joints[body::kWaist]).norm());
      }
      run.most_tracks = std::max(run.most_tracks, tracks);
      for (int person : {0, 1})
        if (nearest[person] < 0.5) run.error_m[person] += nearest[person], ++run.followed[person];
    }
  for (int person : {0, 1}) run.error_m[person] /= std::max(1, run.followed[person]);
  run.bodies = bodies.size();
  run.lost = static_cast<int>(lost.size());
  std::cout << "bodies used " << run.bodies << ", at most " << run.most_tracks << " tracks at once; person 1 followed on "
            << run.followed[0] << " inputs (mean waist error " << 1000 * run.error_m[0] << " mm), person 2 on "
            << run.followed[1] << " (" << 1000 * run.error_m[1] << " mm); " << run.lost << " tracks lost, "
            << run.found_again << " found again where lost\n";
  return run;
}

// The session finds both people by itself and follows each with a track of its own, and starts
// no third. Both are found at frame 5 (heading_frames); of the 21 frames from there each is within
// 0.5 m of a track on 21 and 18, 90 and 113 mm off on average, since the particles' target
// gaits random-walk (2026-12-02; one track lost where nobody was found near, and started afresh,
// so this run no longer shows a track found again: the next test does). Before, 19 and 21, 104 and 47 mm, one track
// found again where lost (each track's first frame searched with 32 times the particles; with the
// loss rule's fraction at 0, no track lost: 21 and 21 frames, 201 and 47 mm); before that search,
// at 0, the farther person's track was lost at frame 15 and started again at 16.
TEST(TrackingSession, FindsTwoPeopleAndFollowsEachWithItsOwnTrack) {
  const TwoPeopleRun run = runTwoPeople(1000, 0);
  EXPECT_EQ(run.most_tracks, 2);
  EXPECT_GE(run.bodies, 2u);
  for (int person : {0, 1}) {
    EXPECT_GE(run.followed[person], 12) << "person " << person + 1;
    EXPECT_LT(run.error_m[person], 0.3) << "person " << person + 1;
  }
}

// A track that loses its person while they are in view starts again in its slot at the next
// frame, where they are ("found again where lost"). The video skips 4 frames after frame 13:
// both people jump about half a metre on. Measured (2026-12-02): two tracks lost, one of them
// found again at the next input; 16 and 9 inputs followed.
TEST(TrackingSession, ATrackLostWhileItsPersonIsInViewStartsAgainWhereTheyAre) {
  const TwoPeopleRun run = runTwoPeople(13, 4);
  EXPECT_GE(run.lost, 1);
  EXPECT_GE(run.found_again, 1);
  EXPECT_LE(run.most_tracks, 3);
}

// A second track started on the person one track already follows merges into it: the newer
// (from a box at frame 12, its particles started from its ground track at frame 22 and tracked
// from 12) ends within a few frames, saying so, and gives its MAP frames; the older goes on. Both tracks
// must follow the person for that: with 500 particles they merged on 7 of the seeds 1-8 (at
// frame 13 or 15), with 200 on 5 of 7 since the prior's table holds brisk walks (2026-12-02).
TEST(TrackingSession, ASecondTrackOnThePersonMergesIntoTheFirst) {
  const test::RenderedWalk& s = scene();
  SessionOptions options = holding(10);
  options.max_people = 2;
  options.find_people = false;
  TrackingSession session(makeTracker(500), options);
  session.startFromBox(truthBox());
  int merged_at = -1;
  for (size_t f = 0; f < s.frames.size() && merged_at < 0; ++f) {
    if (f == 12) session.startFromBox(truthBox(12));
    for (const SessionAnswer& a : session.feed(s.frames[f], 0.1 * f)) {
      if (a.input == 12) {
        ASSERT_NE(a.person(2), nullptr);
        EXPECT_TRUE(a.person(2)->started);
      }
      const PersonAnswer* second = a.person(2);
      if (a.input > 12 && second && second->ended) {
        merged_at = a.input;
        EXPECT_NE(second->message.find("merged with body 1"), std::string::npos) << second->message;
        EXPECT_FALSE(second->map_frames.empty());
        ASSERT_NE(a.person(1), nullptr);
        EXPECT_FALSE(a.person(1)->ended);
      }
    }
  }
  std::cout << "the second track merged at frame " << merged_at << "\n";
  EXPECT_GT(merged_at, 12);
  EXPECT_LE(merged_at, 30);
  EXPECT_EQ(session.trackCount(), 1);
}

TEST(TrackingSession, RefusesBadOptionsNamingThem) {
  SessionOptions options;
  options.background_frames = 0;
  options.min_start_speed_kmh = 5;
  options.max_start_speed_kmh = 4;
  options.min_walk_m = std::nan("");
  options.max_people = 0;
  options.merge_distance_m = std::numeric_limits<double>::infinity();
  options.reacquire_distance_m = -1;
  try {
    TrackingSession session(makeTracker(10), options);
    FAIL() << "accepted bad options";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("background_frames"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("min_walk_m"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("min_start_speed_kmh = 5"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("max_people"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("merge_distance_m"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("reacquire_distance_m"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace kneed_walker::core::tracking
