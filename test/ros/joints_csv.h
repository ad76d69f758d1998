// Joints CSVs (frame,stamp,joint,x,y,z: make_synthetic's ground truth, track_offline's
// estimates) for the rostests.
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace kneed_walker::ros_glue::test {

struct JointRow {
  int frame;
  double stamp;
  std::string joint;
  double x, y, z;
  int track = 0;  // track_offline's track column (0 without one)
};

// The rows in file order.
inline std::vector<JointRow> readJoints(const std::string& path) {
  std::ifstream in(path);
  std::vector<JointRow> rows;
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string frame, stamp, joint, x, y, z, body, track;
    std::getline(fields, frame, ','), std::getline(fields, stamp, ','), std::getline(fields, joint, ',');
    std::getline(fields, x, ','), std::getline(fields, y, ','), std::getline(fields, z, ',');
    std::getline(fields, body, ','), std::getline(fields, track, ',');
    rows.push_back({std::stoi(frame), std::stod(stamp), joint, std::stod(x), std::stod(y), std::stod(z),
                    track.empty() ? 0 : std::stoi(track)});
  }
  return rows;
}

}  // namespace kneed_walker::ros_glue::test
