#include "kneed_walker/core/person/walker_finder.h"

#include <algorithm>
#include <cmath>

namespace kneed_walker::core::person {

namespace {

cv::Point2d centre(const cv::Rect2d& box) { return (box.tl() + box.br()) * 0.5; }

}  // namespace

WalkerFinder::WalkerFinder(int heading_frames, double min_walk_m)
    : heading_frames_(heading_frames), min_walk_m_(min_walk_m) {}

std::vector<FoundWalker> WalkerFinder::update(std::vector<vision::PersonCandidate> people, int input,
                                              const std::optional<Eigen::Vector2d>& near_m) {
  std::vector<Sighting> now;
  for (vision::PersonCandidate& person : people) now.push_back({input, std::move(person)});
  while (!sightings_.empty() &&
         (sightings_.front().empty() || sightings_.front().front().input < input - heading_frames_))
    sightings_.pop_front();
  sightings_.push_back(now);
  if (sightings_.front().empty() || sightings_.front().front().input != input - heading_frames_) return {};
  std::vector<const Sighting*> order;
  for (const Sighting& s : now) order.push_back(&s);
  if (near_m)
    std::stable_sort(order.begin(), order.end(), [&](const Sighting* a, const Sighting* b) {
      return (a->person.ground_xy_m - *near_m).norm() < (b->person.ground_xy_m - *near_m).norm();
    });
  std::vector<FoundWalker> walkers;
  for (const Sighting* current : order) {
    const Sighting* before = nullptr;
    double nearest = 0.5 * current->person.box_px.height;  // further than half a body is someone else
    for (const Sighting& old : sightings_.front()) {
      const double d = cv::norm(centre(old.person.box_px) - centre(current->person.box_px));
      if (d < nearest) nearest = d, before = &old;
    }
    if (!before) continue;
    const Eigen::Vector2d walked = current->person.ground_xy_m - before->person.ground_xy_m;
    if (walked.norm() < min_walk_m_) continue;
    walkers.push_back({current->person, std::atan2(walked.y(), walked.x())});
  }
  return walkers;
}

}  // namespace kneed_walker::core::person
