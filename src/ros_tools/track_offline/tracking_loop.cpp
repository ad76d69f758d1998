#include "tracking_loop.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "kneed_walker/core/vision/overlay.h"
#include "interrupt.h"
#include "median.h"

namespace kneed_walker::tools::track_offline {

namespace kw = kneed_walker::core;


TrackingLoop::TrackingLoop(const Options& options, Input& input, kw::tracking::TrackingSession& session,
                           const PersonStart& start, Outputs& outputs)
    : options_(options), input_(input), session_(session), start_(start), outputs_(outputs) {}

RunSummary TrackingLoop::run() {
  const int first_frame = options_.input.first_frame, max_frames = options_.input.max_frames;
  Frame frame;
  int index = 0;
  std::optional<double> last_stamp_s;
  for (; input_.frames->next(frame); ++index) {
    if (const int signal = stopSignal(); signal != 0) {
      summary_.interrupted_by = signal;
      std::fprintf(stderr, "\ntrack_offline: %s at frame %d: the outputs hold the frames before it\n",
                   stopSignalName(signal), index);
      break;
    }
    if (index < first_frame) continue;
    if (max_frames > 0 && session_.framesFed() >= max_frames) break;
    // A frame the tracker cannot use is skipped and counted by reason, as the nodelet skips it.
    if (frame.problem.empty() && last_stamp_s && !(frame.stamp_s > *last_stamp_s))
      frame.problem = "its stamp is not after the previous frame's";
    if (!frame.problem.empty()) {
      skip(index, frame.problem);
      continue;
    }
    if (lost_at_px_ && start_.restarts()) restartLostTrack(index);
    std::vector<kw::tracking::SessionAnswer> answers;
    try {
      answers = session_.feed(frame.bgr, frame.stamp_s);
    } catch (const std::invalid_argument& e) {
      skip(index, e.what());  // another size, no ground under the box
      continue;
    }
    last_stamp_s = frame.stamp_s;
    source_index_.push_back(index);
    if (outputs_.drawing()) unanswered_[session_.framesFed() - 1] = frame.bgr.clone();
    for (size_t i = 0; i < answers.size(); ++i) answer(answers[i], i + 1 == answers.size());
    recordTiming(answers);
    printProgress();
  }
  progress_.finish();
  if (index <= first_frame && summary_.interrupted_by == 0)
    throw std::runtime_error("--first-frame " + std::to_string(first_frame) + ": the input has " + std::to_string(index) +
                             " frames");
  const std::vector<kw::tracking::SessionAnswer> rest = session_.flushHeld();  // an input shorter than the samples
  for (size_t i = 0; i < rest.size(); ++i) answer(rest[i], i + 1 == rest.size());
  for (const kw::tracking::PersonAnswer& person : session_.finish()) {
    for (const kw::tracking::MapFrame& m : person.map_frames)
      if (options_.output.estimate != WrittenEstimate::kFiltered) writePose(m.input, m.stamp_s, m.pose, person.body, m.track);
    writeGroundTrack(person, -1);
  }
  if (summary_.tracked == 0 && summary_.interrupted_by == 0)
    throw std::runtime_error("no frame was tracked (nobody was found walking; give --init-box)");
  return summary_;
}

void TrackingLoop::skip(int frame, const std::string& problem) {
  ++summary_.skipped;
  if (summary_.skipped_by_reason[problem]++ == 0)
    std::fprintf(stderr, "\ntrack_offline: frame %d skipped: %s (the frames skipped for it are counted)\n", frame,
                 problem.c_str());
}

// A lost track starts again from the box nearest to where the person was last seen.
void TrackingLoop::restartLostTrack(int frame) {
  if (const std::optional<kw::tracking::InitialGuess> again = start_.restartNear(frame, *lost_at_px_)) {
    session_.startFrom(*again);
    lost_at_px_.reset();
  }
}

void TrackingLoop::writePose(int input, double stamp_s, const kw::body::BodyPose& pose, int body, int track) {
  outputs_.writePose(source_index_.at(input), stamp_s, pose, body, track,
                     outputs_.writesBoxes() ? session_.tracker(body).imageBox(pose) : cv::Rect2d());
}

void TrackingLoop::writeGroundTrack(const kw::tracking::PersonAnswer& person, int input) {
  if (!outputs_.writesGroundTrack()) return;
  // A track with its whole path gives its ground track smoothed when it ends; else each frame's.
  if (person.ground_track && !session_.tracker(person.body).keepsWholePath())
    outputs_.writeGroundTrack(source_index_.at(input), person.body, *person.ground_track);
  for (const auto& [input, estimate] : person.ground_track_smoothed)
    outputs_.writeGroundTrack(source_index_.at(input), person.body, estimate);
}

void TrackingLoop::answer(const kw::tracking::SessionAnswer& a, bool latest) {
  ++summary_.answered;
  if (a.start_failed) std::fprintf(stderr, "\ntrack_offline: frame %d: %s\n", source_index_.at(a.input), a.message.c_str());
  const bool filtered = options_.output.estimate == WrittenEstimate::kFiltered;
  int people_now = 0;
  for (const kw::tracking::PersonAnswer& person : a.people) {
    if (!filtered)
      for (const kw::tracking::MapFrame& m : person.map_frames) writePose(m.input, m.stamp_s, m.pose, person.body, m.track);
    writeGroundTrack(person, a.input);
    if (!person.estimate) continue;
    const kw::tracking::TrackEstimate& estimate = *person.estimate;
    ++people_now;
    summary_.bodies_used.insert(person.body);
    summary_.tracks_started += person.started;
    summary_.lost += estimate.lost;
    summary_.resampled += estimate.resampled;
    if (filtered) writePose(a.input, a.stamp_s, estimate.pose, person.body, person.track);
    if (estimate.lost)
      if (const auto px = input_.camera.project(estimate.pose.joints[kw::body::kWaist]))
        lost_at_px_ = cv::Point2d(px->x(), px->y());
  }
  summary_.tracked += people_now > 0;
  summary_.most_people = std::max(summary_.most_people, people_now);
  if (outputs_.drawing()) drawAnswer(a, latest, people_now);
}

void TrackingLoop::drawAnswer(const kw::tracking::SessionAnswer& a, bool latest, int people_now) {
  cv::Mat picture = unanswered_.at(a.input);
  unanswered_.erase(a.input);
  const bool many = options_.session.max_people > 1;
  std::optional<cv::Rect2d> bodies_box;
  for (const kw::tracking::PersonAnswer& person : a.people) {
    if (!person.estimate) continue;
    const kw::body::BodyPose& pose = person.estimate->pose;
    const kw::tracking::Tracker& tracker = session_.tracker(person.body);
    std::vector<Eigen::Vector2f> cloud;
    if (latest && tracker.started())
      for (const auto& p : tracker.particles())
        if (const auto px = input_.camera.project(p.joints[kw::body::kWaist].cast<double>()))
          cloud.push_back(px->cast<float>());
    kw::vision::BodyOutlines outlines;
    tracker.project(pose, outlines);
    kw::vision::drawOverlay(picture, input_.camera, pose, outlines, cloud);
    const cv::Rect2d box = tracker.imageBox(pose);
    if (box.empty()) continue;
    if (many)
      cv::putText(picture, std::to_string(person.body), cv::Point(cvRound(box.x), cvRound(box.y) - 3),
                  cv::FONT_HERSHEY_SIMPLEX, 0.5, {255, 255, 255}, 1, cv::LINE_AA);
    bodies_box = bodies_box ? (*bodies_box | box) : box;
  }
  const int frame = source_index_.at(a.input);
  const kw::tracking::PersonAnswer* first = a.people.empty() ? nullptr : &a.people.front();
  std::string caption = cv::format("frame %d  %s", frame, kw::tracking::stateName(a.state));
  if (many)
    caption += cv::format("  %d people", people_now);
  else if (first && first->estimate)
    caption += cv::format("  N_eff %.0f  %.1f km/h", first->estimate->effective_sample_size, first->estimate->speed_kmh);
  cv::putText(picture, caption, {10, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {255, 255, 255}, 1, cv::LINE_AA);
  outputs_.writeOverlay(picture, frame, bodies_box);
}

// The frame's whole tracking (all people, the search for new ones) and the trackers' parts, for
// a frame answered as it came (not frames held and tracked together: the background's, a
// starting track's).
void TrackingLoop::recordTiming(const std::vector<kw::tracking::SessionAnswer>& answers) {
  if (answers.size() != 1 || answers.back().people.empty() || summary_.answered <= 1) return;
  double precompute = 0, particles = 0;
  for (const kw::tracking::PersonAnswer& person : answers.back().people) {
    const kw::tracking::TrackerTiming& timing = session_.tracker(person.body).timing();
    precompute += timing.precompute_ms;
    particles += timing.particles_ms;
  }
  summary_.total_ms.push_back(session_.lastFrameMs());
  summary_.precompute_ms.push_back(precompute);
  summary_.particles_ms.push_back(particles);
}

void TrackingLoop::printProgress() {
  const int total = input_.frames->count(), first_frame = options_.input.first_frame;
  const int max_frames = options_.input.max_frames;
  const int todo = max_frames > 0 ? std::min(max_frames, total - first_frame) : total - first_frame;
  progress_.update(session_.framesFed(), todo, std::string("frames, ") + kw::tracking::stateName(session_.state()));
}

void printSummary(const RunSummary& s, const Options& options) {
  const int bodies = static_cast<int>(s.bodies_used.size());
  std::printf("frames=%d tracked_frames=%d skipped_frames=%d lost_frames_reported=%d restarts=%d resampled_frames=%d "
              "particles=%d\n",
              s.answered, s.tracked, s.skipped, s.lost, std::max(0, s.tracks_started - bodies), s.resampled,
              options.tracker.filter.num_particles);
  for (const auto& [reason, count] : s.skipped_by_reason) std::printf("skipped %d frames: %s\n", count, reason.c_str());
  if (options.session.max_people > 1)
    std::printf("tracks_started=%d bodies_used=%d most_people_at_once=%d\n", s.tracks_started, bodies, s.most_people);
  if (s.interrupted_by != 0) std::printf("interrupted_by_signal=%d (the outputs are partial)\n", s.interrupted_by);
  std::printf("tracker_ms_per_frame=%.1f precompute_ms=%.1f particles_ms=%.1f (medians)\n", median(s.total_ms),
              median(s.precompute_ms), median(s.particles_ms));
}

}  // namespace kneed_walker::tools::track_offline
