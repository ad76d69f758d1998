// The image likelihood of paper §4: log p(z_t | s_t) up to a constant, as the sum over body
// parts of each part's appearance log-likelihood ratio (foreground part model against the
// background model) summed over its visible pixels and divided by its reference area (the
// paper averages over the part's own pixels, which lets a body shrink inside the person's
// silhouette, i.e. move away, at no cost), and its average optical-flow log-likelihood
// ratio (eq. 13 at the motion the particle predicts against u = 0) over its visible grid
// points. Parts occlude each other: a part's pixels covered by a nearer part are not its own.
//
// FrameEvidence holds everything shared by all particles of a frame, computed once: per part
// kind the row-wise prefix sums of the clamped per-pixel log ratios, and the flow grid. A
// particle then costs two look-ups per row its outline covers (cost grows with the rows, not
// with the area) and one Student-t per visible flow grid point; evaluate() allocates nothing.
#pragma once

#include <opencv2/core.hpp>

#include <array>
#include <string>
#include <vector>

#include "kneed_walker/core/common/option_table.h"
#include "kneed_walker/core/vision/appearance_model.h"
#include "kneed_walker/core/vision/background_model.h"
#include "kneed_walker/core/vision/body_projection.h"
#include "kneed_walker/core/vision/optical_flow.h"

namespace kneed_walker::core::vision {

struct LikelihoodOptions {
  BackgroundOptions background;
  AppearanceOptions appearance;
  FlowOptions flow;
  bool use_flow = true;
  double ratio_limit = 6.0;     // per-pixel appearance log ratios are clamped to ±this
  // Per-point flow log ratios are clamped to ±this: DIS loses thin fast limbs (a swinging foot
  // moves 30 px between frames at 10 fps), and one lost point must not outweigh a whole part.
  double flow_ratio_limit = 4.0;
  double outside_ratio = -3.0;  // the log ratio a part's pixel scores outside the evidence's region or image
  int min_part_pixels = 6;      // a part with fewer visible pixels is left out (hidden)
  // Weights of each part's appearance and flow averages. The paper sums the averages with
  // weight 1, which makes neighbouring particles' log-likelihoods differ by tens: N_eff collapses
  // to a few particles every frame and the person is lost in most runs; of 0.15, 0.3, 0.5 and 1,
  // 0.3 tracked the synthetic sequences best.
  double appearance_weight = 0.3;
  double flow_weight = 0.3;
};

// The likelihood's options people set: name, range, unit, help (common/option_table.h).
const common::OptionTable<LikelihoodOptions>& likelihoodOptionTable();
// Every problem with those options, naming each; empty when usable.
std::vector<std::string> validate(const LikelihoodOptions& options);

// Pixels per body part.
using PartAreas = std::array<int, body::kNumBodyParts>;

class FrameEvidence {
 public:
  // The evidence of one BGR frame inside `roi` (clipped to the image). `previous_grey` is the
  // previous frame's 8-bit grey image, or empty for the first frame (no flow).
  void compute(const cv::Mat& bgr, const cv::Mat& previous_grey, const cv::Rect& roi,
               const BackgroundModel& background, const AppearanceModel& appearance,
               const LikelihoodOptions& options);
  const cv::Rect& roi() const { return roi_; }
  // Each part's area, pixels, on a body where the person is believed to be (the last estimate):
  // a part's appearance score is its sum of log ratios over this area, so a body that shrinks
  // inside the person's silhouette (moves away) loses the pixels it leaves, where an average
  // over its own pixels would not mind. Zero for a part: the average over its own pixels.
  void setReferenceAreas(const PartAreas& areas_px) { reference_areas_px_ = areas_px; }
  const PartAreas& referenceAreas() const { return reference_areas_px_; }
  bool hasFlow() const { return !flow_.empty(); }
  const FlowField& flow() const { return flow_; }
  // Σ of a kind's log ratios over columns [x0, x1) of image row y (inside the roi).
  double rowSum(PartKind kind, int y, int x0, int x1) const {
    const float* p = prefix_[kind].ptr<float>(y - roi_.y);
    return p[x1 - roi_.x] - p[x0 - roi_.x];
  }

 private:
  cv::Rect roi_;
  // CV_32F, roi.height × (roi.width + 1): single precision halves the memory the particles read
  // at random (the hot spot); a row's sums stay within 1e-3 of double's.
  std::array<cv::Mat, kNumPartKinds> prefix_;
  FlowField flow_;
  PartAreas reference_areas_px_{};
};

// What evaluate() found per part.
struct PartScore {
  double appearance = 0;  // log ratios over the part's pixels (outside ones at outside_ratio) / reference area
  double flow = 0;        // average flow log ratio over its visible grid points
  int pixels = 0;         // visible pixels (inside and outside the evidence's region)
  int flow_points = 0;
};
using PartScores = std::array<PartScore, body::kNumBodyParts>;

// The image axes of a body's parts, all the flow term needs of the previous frame's body.
struct PartImageAxis {
  std::array<Eigen::Vector2f, 2> ends_px;  // proximal, distal
  bool visible = false;
};
using BodyImageAxes = std::array<PartImageAxis, body::kNumBodyParts>;
BodyImageAxes imageAxes(const BodyOutlines& outlines);

// log p(z | s) + const for one particle's projected body. `previous` is the same body's image
// axes in the previous frame (for the flow it predicts), or nullptr. `scores` receives the parts'
// terms if given. Thread-safe; no allocation after a thread's first call.
double evaluateLikelihood(const FrameEvidence& evidence, const BodyOutlines& outlines,
                          const BodyImageAxes* previous, const LikelihoodOptions& options,
                          PartScores* scores = nullptr);

// The pixels inside a convex outline (either orientation): per image row y in
// [first_row, first_row + rows), the columns [left[i], right[i]), none when left[i] >= right[i].
// Used by evaluateLikelihood and to sample appearance pixels.
struct RowSpans {
  int first_row = 0, rows = 0;
  std::vector<int> left, right;
};
void rasterize(const PartOutline& outline, RowSpans& spans);
// Each visible part's pixels, as if no part hid another (0 for a hidden part).
PartAreas partAreas(const BodyOutlines& outlines);

}  // namespace kneed_walker::core::vision
