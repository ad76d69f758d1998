// Finding people who walk, without being told where they are: a person-sized blob
// (vision::findPeople) seen again `heading_frames` later within half a body of where it was,
// having moved at least `min_walk_m` on the ground, is someone walking. It gives where they are
// and which way they went; the session then watches them with their ground track
// (person/ground_track.h) before their track starts.
#pragma once

#include <Eigen/Core>

#include <deque>
#include <optional>
#include <vector>

#include "kneed_walker/core/vision/person_detector.h"

namespace kneed_walker::core::person {

struct FoundWalker {
  vision::PersonCandidate person;  // as seen at the last frame
  double heading_rad = 0;          // of the ground point's move over heading_frames, from +X towards +Y
};

class WalkerFinder {
 public:
  // `heading_frames` ≥ 1; `min_walk_m` ≥ 0 (the session's options validate them).
  WalkerFinder(int heading_frames, double min_walk_m);

  // The people seen at frame `input` (frames counted in order; a frame that is not fed counts as
  // one where nobody was seen). Returns those seen walking: each person now whose blob was
  // seen heading_frames before within half its height (px) and whose ground point moved
  // min_walk_m since; nearest to `near_m` first when given, else in the order given.
  std::vector<FoundWalker> update(std::vector<vision::PersonCandidate> people, int input,
                                  const std::optional<Eigen::Vector2d>& near_m = std::nullopt);
  // Forgets what was seen (someone was started, or the input starts over).
  void clear() { sightings_.clear(); }

 private:
  struct Sighting {
    int input = 0;
    vision::PersonCandidate person;
  };
  int heading_frames_;
  double min_walk_m_;
  std::deque<std::vector<Sighting>> sightings_;  // the people seen in the last frames
};

}  // namespace kneed_walker::core::person
