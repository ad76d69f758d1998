// The foreground model of paper §4: pixels are IID within each body part, each part's colour a
// Gaussian mixture learned (cv::ml::EM) from the initial pose in the first frame. Parts of the
// same kind share a model: foot, shank, thigh, torso, head. The gradient of a foreground pixel
// is modelled as zero-mean and broad (`gradient_sd`), so that foreground and background
// densities are over the same 5-D measurement and their ratio is meaningful.
//
// For speed each mixture is tabulated once on a 64³ colour grid (4 grey levels per cell):
// a pixel's foreground density is then one table look-up per part kind.
#pragma once

#include <opencv2/core.hpp>

#include <array>
#include <vector>

#include "kneed_walker/core/body/body_model.h"

namespace kneed_walker::core::vision {

enum PartKind : int { kFootKind = 0, kShankKind, kThighKind, kTorsoKind, kHeadKind, kNumPartKinds };
PartKind partKind(body::BodyPart part);

struct AppearanceOptions {
  int components = 3;          // mixture components per part kind
  double gradient_sd = 20.0;   // SD of a foreground pixel's gradient components, grey levels per pixel
  double colour_floor = 6.0;   // SD floor of each component's colour channels, grey levels
  int min_pixels = 30;         // fewer pixels of a kind: it borrows the pooled model of all kinds
};

class AppearanceModel {
 public:
  AppearanceModel() = default;
  // Learns each kind's mixture from the BGR pixels `samples[kind]` (any number; kinds with fewer
  // than min_pixels use the mixture of all samples together). Throws std::invalid_argument when
  // there are fewer than min_pixels samples in all.
  static AppearanceModel learn(const std::array<std::vector<cv::Vec3b>, kNumPartKinds>& samples,
                               const AppearanceOptions& options = {});

  // log p(colour, gradient | kind) of a pixel (the gradient term included).
  float logDensity(PartKind kind, const cv::Vec3b& bgr, float gx, float gy) const {
    return table_[kind][index(bgr)] + gradient_scale_ * (gx * gx + gy * gy) + gradient_log_normaliser_;
  }
  bool empty() const { return table_[0].empty(); }

 private:
  static int index(const cv::Vec3b& bgr) { return (bgr[0] >> 2) << 12 | (bgr[1] >> 2) << 6 | (bgr[2] >> 2); }
  std::array<std::vector<float>, kNumPartKinds> table_;  // 64³ log densities each
  float gradient_scale_ = 0, gradient_log_normaliser_ = 0;
};

}  // namespace kneed_walker::core::vision
