#include "outputs.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <stdexcept>

namespace kneed_walker::tools::track_offline {

namespace kw = kneed_walker::core;

Outputs::Temporaries::~Temporaries() {
  if (renamed) return;
  for (const File& file : files) std::remove(file.temporary.c_str());
}

const Outputs::File& Outputs::add(const std::string& option, const std::string& target) {
  // The extension kept last: the video writer and the picture encoder choose by it.
  std::filesystem::path temporary = target;
  temporary.replace_extension(".partial" + temporary.extension().string());
  File file{target, temporary.string()};
  std::ofstream probe(file.temporary);  // an unwritable output fails before any work
  if (!probe) throw std::runtime_error(option + " " + target + ": cannot write");
  temporaries_.files.push_back(file);
  return temporaries_.files.back();
}

Outputs::Outputs(const OutputOptions& options) : options_(options) {
  csv_.open(add("--out-csv", options.csv_path).temporary);
  csv_ << "frame,stamp,joint,x,y,z,body,track\n" << std::fixed << std::setprecision(9);
  if (!options.boxes_path.empty()) {
    boxes_csv_.open(add("--out-boxes", options.boxes_path).temporary);
    boxes_csv_ << "frame,x1,y1,x2,y2,body\n" << std::fixed << std::setprecision(2);
  }
  if (!options.ground_track_path.empty()) {
    ground_csv_.open(add("--out-ground-track", options.ground_track_path).temporary);
    ground_csv_ << "frame,stamp,body,x,y,vx,vy,stature,var_x,cov_xy,var_y,var_vx,var_vy,var_stature,measured\n"
                << std::fixed << std::setprecision(6);
  }
  if (!options.overlay_path.empty()) overlay_temporary_ = add("--overlay", options.overlay_path).temporary;
  if (!options.strip_path.empty()) strip_temporary_ = add("--strip", options.strip_path).temporary;
}

void Outputs::openOverlay(cv::Size size, double fps) {
  if (overlay_temporary_.empty()) return;
  overlay_.open(overlay_temporary_, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, size);
  if (!overlay_.isOpened()) throw std::runtime_error("--overlay " + options_.overlay_path + ": cannot write the video");
}

void Outputs::writePose(int frame, double stamp_s, const kw::body::BodyPose& pose, int body, int track,
                        const cv::Rect2d& image_box) {
  for (int j = 0; j < kw::body::kNumBodyJoints; ++j) {
    const Eigen::Vector3d& p = pose.joints[j];
    csv_ << frame << ',' << stamp_s << ',' << kw::body::jointName(kw::body::BodyJoint(j)) << ',' << p.x() << ','
         << p.y() << ',' << p.z() << ',' << body << ',' << track << '\n';
  }
  if (boxes_csv_.is_open() && !image_box.empty())
    boxes_csv_ << frame << ',' << image_box.x << ',' << image_box.y << ',' << image_box.br().x << ','
               << image_box.br().y << ',' << body << '\n';
}

void Outputs::writeGroundTrack(int frame, int body, const kw::person::GroundTrackEstimate& e) {
  using namespace kw::person;
  const GroundTrackMatrix& c = e.covariance;
  ground_csv_ << frame << ',' << e.stamp_s << ',' << body << ',' << e.mean(kX) << ',' << e.mean(kY) << ','
              << e.mean(kVx) << ',' << e.mean(kVy) << ',' << e.mean(kStature) << ',' << c(kX, kX) << ','
              << c(kX, kY) << ',' << c(kY, kY) << ',' << c(kVx, kVx) << ',' << c(kVy, kVy) << ','
              << c(kStature, kStature) << ',' << e.measured << '\n';
}

void Outputs::writeOverlay(const cv::Mat& picture, int frame, const std::optional<cv::Rect2d>& bodies_box) {
  if (overlay_.isOpened()) overlay_.write(picture);
  const std::vector<int>& wanted = options_.strip_frames;
  if (!bodies_box || std::find(wanted.begin(), wanted.end(), frame) == wanted.end()) return;
  // A portrait crop 1.4 body heights tall around the bodies, 240 px tall in the strip.
  const cv::Rect2d& box = *bodies_box;
  const cv::Point2d centre(box.x + box.width / 2, box.y + box.height / 2);
  const double height = 1.4 * box.height, width = std::max(0.75 * height, box.width + 0.2 * height);
  const cv::Rect crop = cv::Rect(cv::Point(cvRound(centre.x - width / 2), cvRound(centre.y - height / 2)),
                                 cv::Size(cvRound(width), cvRound(height))) &
                        cv::Rect(0, 0, picture.cols, picture.rows);
  if (crop.area() == 0) return;
  cv::Mat tile;
  cv::resize(picture(crop), tile, cv::Size(cvRound(240.0 * crop.width / crop.height), 240), 0, 0, cv::INTER_CUBIC);
  cv::putText(tile, std::to_string(frame), {4, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {255, 255, 255}, 1, cv::LINE_AA);
  strip_tiles_[frame] = tile;
}

void Outputs::commit() {
  if (!strip_temporary_.empty()) {
    if (strip_tiles_.empty()) throw std::runtime_error("--strip-frames: none of them was tracked");
    std::vector<cv::Mat> tiles;
    for (const auto& [frame, tile] : strip_tiles_) {
      if (!tiles.empty()) tiles.push_back(cv::Mat(240, 4, CV_8UC3, cv::Scalar(255, 255, 255)));
      tiles.push_back(tile);
    }
    cv::Mat strip;
    cv::hconcat(tiles, strip);
    if (!cv::imwrite(strip_temporary_, strip))
      throw std::runtime_error("--strip " + options_.strip_path + ": cannot write the picture");
  }
  csv_.close();
  boxes_csv_.close();
  ground_csv_.close();
  overlay_.release();
  if (!csv_ || (boxes_csv_.fail() && !options_.boxes_path.empty()) ||
      (ground_csv_.fail() && !options_.ground_track_path.empty()))
    throw std::runtime_error("--out-csv, --out-boxes or --out-ground-track: writing failed (disk full?)");
  for (const File& file : temporaries_.files)
    if (std::rename(file.temporary.c_str(), file.target.c_str()) != 0)
      throw std::runtime_error(file.target + ": cannot replace it with " + file.temporary);
  temporaries_.renamed = true;
}

}  // namespace kneed_walker::tools::track_offline
