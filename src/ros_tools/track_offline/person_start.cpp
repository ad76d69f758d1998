#include "person_start.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace kneed_walker::tools::track_offline {

namespace kw = kneed_walker::core;

namespace {

cv::Point2d centre(const cv::Rect2d& box) { return (box.tl() + box.br()) * 0.5; }

}  // namespace

PersonStart::PersonStart(const StartOptions& options, const kw::vision::Camera& camera,
                         const kw::vision::GroundPlane& ground)
    : options_(options), camera_(camera), ground_(ground) {
  if (options.boxes_path.empty()) return;
  std::ifstream in(options.boxes_path);
  if (!in) throw std::runtime_error(options.boxes_path + ": cannot read the boxes");
  std::string line;
  std::getline(in, line);
  for (int number = 2; std::getline(in, line); ++number) {
    std::istringstream fields(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(fields, cell, ',')) v.push_back(std::atof(cell.c_str()));
    if (v.size() < 6 || !(v[3] > v[1] && v[4] > v[2]))
      throw std::runtime_error(options.boxes_path + ":" + std::to_string(number) +
                               ": expected frame,x1,y1,x2,y2,score,...");
    boxes_[static_cast<int>(v[0])].push_back({cv::Rect2d(cv::Point2d(v[1], v[2]), cv::Point2d(v[3], v[4])), v[5]});
  }
}

void PersonStart::startFirst(kw::tracking::TrackingSession& session, int frame) const {
  if (!options_.init_position.empty()) {
    kw::tracking::InitialGuess guess = options_.guess;
    guess.position_m = Eigen::Vector2d(options_.init_position[0], options_.init_position[1]);
    if (!options_.heading_given) guess.heading_sd_rad = M_PI;
    session.startFrom(guess);
  } else if (!options_.init_box.empty()) {
    const std::vector<double>& b = options_.init_box;
    try {
      session.startFrom(guessAt(cv::Rect2d(cv::Point2d(b[0], b[1]), cv::Point2d(b[2], b[3]))));
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(std::string("--init-box: ") + e.what());
    }
  } else if (!options_.boxes_path.empty()) {
    const auto it = boxes_.find(frame);
    if (it == boxes_.end() || it->second.empty())
      throw std::runtime_error("no box for frame " + std::to_string(frame) + " in " + options_.boxes_path);
    const auto best = std::max_element(it->second.begin(), it->second.end(),
                                       [](const auto& a, const auto& b) { return a.second < b.second; });
    session.startFrom(guessAt(best->first));
  }
}

std::optional<kw::tracking::InitialGuess> PersonStart::restartNear(int frame, const cv::Point2d& lost_at_px) const {
  const auto it = boxes_.find(frame);
  if (it == boxes_.end()) return std::nullopt;
  std::optional<cv::Rect2d> nearest;
  double best = 1e300;
  for (const auto& [box, score] : it->second) {
    const double d = cv::norm(centre(box) - lost_at_px);
    if (d < best) best = d, nearest = box;
  }
  if (!nearest) return std::nullopt;
  kw::tracking::InitialGuess again = guessAt(*nearest);
  again.stance_leg.reset();
  return again;
}

kw::tracking::InitialGuess PersonStart::guessAt(const cv::Rect2d& box) const {
  kw::tracking::InitialGuess guess = kw::tracking::guessFromBox(camera_, ground_, box);
  guess.min_speed_kmh = options_.guess.min_speed_kmh;
  guess.max_speed_kmh = options_.guess.max_speed_kmh;
  guess.position_sd_m = options_.guess.position_sd_m;
  if (options_.heading_given) {
    // The user said which way: the track starts at once, not from the person's ground track.
    guess.heading_rad = options_.guess.heading_rad;
    guess.heading_sd_rad = options_.guess.heading_sd_rad;
    guess.from_ground_track = false;
  }
  guess.stance_leg = options_.guess.stance_leg;
  return guess;
}

}  // namespace kneed_walker::tools::track_offline
