#include "kneed_walker/core/vision/likelihood.h"

#include <Eigen/Core>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>

namespace kneed_walker::core::vision {

const common::OptionTable<LikelihoodOptions>& likelihoodOptionTable() {
  using common::OptionField;
  using O = LikelihoodOptions;
  static const common::OptionTable<LikelihoodOptions> table{
      {"use_optical_flow", [](O& o) -> OptionField { return &o.use_flow; }, 0, 0, "",
       "the likelihood's optical flow term (paper eq. 13); false for footage of a few frames a second"},
      {"appearance_weight", [](O& o) -> OptionField { return &o.appearance_weight; }, 0, 100, "",
       "weight of each part's appearance score (log ratios summed over its pixels, per pixel of its expected area)"},
      {"flow_weight", [](O& o) -> OptionField { return &o.flow_weight; }, 0, 100, "",
       "weight of each part's average flow log ratio"},
      {"flow_min_sd_px", [](O& o) -> OptionField { return &o.flow.min_sd_px; }, 0.01, 100, "px",
       "floor of the optical flow's standard deviation"},
  };
  return table;
}

std::vector<std::string> validate(const LikelihoodOptions& options) {
  return common::rangeProblems(options, likelihoodOptionTable());
}

void FrameEvidence::compute(const cv::Mat& bgr, const cv::Mat& previous_grey, const cv::Rect& roi,
                            const BackgroundModel& background, const AppearanceModel& appearance,
                            const LikelihoodOptions& options) {
  if (bgr.type() != CV_8UC3) throw std::invalid_argument("the likelihood needs BGR 8-bit frames");
  if (bgr.size() != background.size())
    throw std::invalid_argument("the frame's size differs from the background model's");
  roi_ = roi & cv::Rect(0, 0, bgr.cols, bgr.rows);
  if (roi_.empty()) roi_ = cv::Rect(0, 0, 1, 1);
  const cv::Mat z = measurements(bgr, roi_);
  cv::Mat background_density;
  background.logDensity(z, roi_, background_density);
  const float limit = static_cast<float>(options.ratio_limit);
  for (int kind = 0; kind < kNumPartKinds; ++kind) prefix_[kind].create(roi_.height, roi_.width + 1, CV_32F);
  for (int y = 0; y < roi_.height; ++y) {
    const cv::Vec3b* pixels = bgr.ptr<cv::Vec3b>(roi_.y + y) + roi_.x;
    const float* zr = z.ptr<float>(y);
    const float* bg = background_density.ptr<float>(y);
    for (int kind = 0; kind < kNumPartKinds; ++kind) {
      float* prefix = prefix_[kind].ptr<float>(y);
      double running = 0;  // summed in double, stored in float
      prefix[0] = 0;
      for (int x = 0; x < roi_.width; ++x) {
        const float* m = zr + x * kMeasurementChannels;
        const float r = appearance.logDensity(static_cast<PartKind>(kind), pixels[x], m[3], m[4]) - bg[x];
        running += std::clamp(r, -limit, limit);
        prefix[x + 1] = static_cast<float>(running);
      }
    }
  }
  flow_ = FlowField();
  if (options.use_flow && !previous_grey.empty()) {
    cv::Mat grey;
    cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
    flow_.compute(previous_grey, grey, roi_, options.flow);
  }
}

namespace {

// ceil and floor by truncation and a correction: exact for |x| < 2³¹, and inline, where
// std::ceil without SSE4.1 is a call.
inline int ceilToInt(double x) {
  const int truncated = static_cast<int>(x);
  return truncated + (static_cast<double>(truncated) < x);
}
inline int floorToInt(double x) {
  const int truncated = static_cast<int>(x);
  return truncated - (static_cast<double>(truncated) > x);
}

}  // namespace

void rasterize(const PartOutline& outline, RowSpans& spans) {
  spans.rows = 0;
  if (!outline.visible || outline.size < 3) return;
  // The outline's extent and orientation (twice its signed area, shoelace formula).
  const int n = outline.size;
  const Eigen::Vector2d* hull = outline.hull.data();
  double y_min = hull[0].y(), y_max = y_min, x_min = hull[0].x(), x_max = x_min;
  double twice_area = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d& p = hull[i];
    const Eigen::Vector2d& q = hull[i + 1 < n ? i + 1 : 0];  // a compare, not `% n`: no division per edge
    y_min = std::min(y_min, p.y()), y_max = std::max(y_max, p.y());
    x_min = std::min(x_min, p.x()), x_max = std::max(x_max, p.x());
    twice_area += p.x() * q.y() - q.x() * p.y();
  }
  // Pixel centres at integer coordinates; outlines far off the image (whose columns would not
  // fit an int) cover no pixel.
  if (!(std::max(std::abs(y_min), std::abs(y_max)) < 1e6) || !(std::max(std::abs(x_min), std::abs(x_max)) < 1e6)) return;
  spans.first_row = ceilToInt(y_min);
  spans.rows = floorToInt(y_max) - spans.first_row + 1;
  if (spans.rows <= 0) {
    spans.rows = 0;
    return;
  }
  if (static_cast<int>(spans.left.size()) < spans.rows) {
    spans.left.resize(spans.rows);
    spans.right.resize(spans.rows);
  }
  // A convex outline in order is two chains from its top to its bottom vertex, one of edges
  // going down, one going up; every row between crosses each chain once. With a positive
  // signed area (image coordinates) the chain going down is the right one, else the left one.
  // Each edge writes its chain's column bound on its rows: the left chain's x rounded up, the
  // right one's x rounded down plus one, so that a row's pixels are [left, right). An outline's
  // edges span a few rows each (16 edges, about 30 rows a part in bench_tracker): the work per
  // edge is what costs, so each vertex's rows are rounded once, and the columns are written as
  // integers straight away (no chains of doubles, no second pass).
  const bool down_is_right = twice_area > 0;
  int* const left = spans.left.data() - spans.first_row;  // row r at left[r]
  int* const right = spans.right.data() - spans.first_row;
  std::array<int, kOutlineVertices> first_row_at, last_row_at;  // a vertex's ceil(y) and floor(y)
  for (int i = 0; i < n; ++i) {
    first_row_at[i] = ceilToInt(hull[i].y());
    last_row_at[i] = floorToInt(hull[i].y());
  }
  for (int i = 0; i < n; ++i) {
    const int j = i + 1 < n ? i + 1 : 0;
    const Eigen::Vector2d& p = hull[i];
    const Eigen::Vector2d& q = hull[j];
    const bool down = q.y() > p.y();
    const int r0 = down ? first_row_at[i] : first_row_at[j];
    const int r1 = down ? last_row_at[j] : last_row_at[i];
    if (r0 > r1) continue;
    if (p.y() == q.y()) {  // a level edge on a pixel row: its ends are the chains' ends there
      left[r0] = ceilToInt(std::min(p.x(), q.x()));
      right[r0] = floorToInt(std::max(p.x(), q.x())) + 1;
      continue;
    }
    const double slope = (q.x() - p.x()) / (q.y() - p.y());
    if (down != down_is_right) {
      for (int r = r0; r <= r1; ++r) left[r] = ceilToInt(p.x() + (r - p.y()) * slope);
    } else {
      for (int r = r0; r <= r1; ++r) right[r] = floorToInt(p.x() + (r - p.y()) * slope) + 1;
    }
  }
}

namespace {

struct Interval {
  int begin, end;
};
using Pieces = std::array<Interval, body::kNumBodyParts + 1>;

// Removes from the row-y pieces [pieces, pieces + n) the row-y spans of `covers`; returns the
// pieces left (at most one more per cover, up to the array's size). Always inlined: called per
// body row, as a function it cost the likelihood 8.5 % more instructions (callgrind,
// bench_tracker 500 particles).
__attribute__((always_inline)) inline int subtractCovers(Pieces& pieces, int n, int y, const std::array<const RowSpans*, body::kNumBodyParts>& covers,
                   int n_covers, Pieces& scratch) {
  for (int c = 0; c < n_covers && n > 0; ++c) {
    const RowSpans& o = *covers[c];
    const int ko = y - o.first_row;
    if (ko < 0 || ko >= o.rows || o.left[ko] >= o.right[ko]) continue;
    const Interval cover{o.left[ko], o.right[ko]};
    int n_next = 0;
    for (int i = 0; i < n; ++i) {
      const Interval& piece = pieces[i];
      if (cover.end <= piece.begin || cover.begin >= piece.end) {
        scratch[n_next++] = piece;
        continue;
      }
      if (piece.begin < cover.begin && n_next < static_cast<int>(scratch.size())) scratch[n_next++] = {piece.begin, cover.begin};
      if (cover.end < piece.end && n_next < static_cast<int>(scratch.size())) scratch[n_next++] = {cover.end, piece.end};
    }
    std::copy(scratch.begin(), scratch.begin() + n_next, pieces.begin());
    n = n_next;
  }
  return n;
}

// A part kind's log ratios over row pieces: the pixels inside the evidence's region summed, the
// rest counted (each scores LikelihoodOptions::outside_ratio).
struct PixelTally {
  double sum = 0;
  int inside = 0, outside = 0;
  // Adds row y's piece; returns its columns inside the region (begin >= end if none).
  Interval add(const FrameEvidence& evidence, PartKind kind, int y, bool row_inside, const Interval& piece) {
    const cv::Rect& roi = evidence.roi();
    const Interval clipped{std::max(piece.begin, roi.x), std::min(piece.end, roi.x + roi.width)};
    if (row_inside && clipped.begin < clipped.end) {
      sum += evidence.rowSum(kind, y, clipped.begin, clipped.end);
      inside += clipped.end - clipped.begin;
      outside += (piece.end - piece.begin) - (clipped.end - clipped.begin);
      return clipped;
    }
    outside += piece.end - piece.begin;
    return Interval{0, 0};
  }
  int pixels() const { return inside + outside; }
};

// Σ over grid points of the Student-t log-likelihood ratio of eq. 13 (n = 2) of a predicted
// motion against the background's u = 0, −2 (log(1 + e²) − log(1 + e₀²)) clamped to ±limit;
// the log|Σ| terms cancel. Points are gathered and their logarithms taken a block at a time by
// Eigen's vectorised log (a libm call per point was a tenth of the likelihood's time).
class FlowRatioSum {
 public:
  explicit FlowRatioSum(float limit) : limit_(limit) {}
  void add(float squared_error, float log1p_background) {
    squared_error_[n_] = squared_error;
    background_[n_] = log1p_background;
    if (++n_ == kBlock) flush();
  }
  double total() {
    flush();
    return total_;
  }

 private:
  static constexpr int kBlock = 64;
  void flush() {
    if (n_ == 0) return;
    using Block = Eigen::Map<const Eigen::ArrayXf>;
    const auto ratio = -2.0f * ((1.0f + Block(squared_error_.data(), n_)).log() - Block(background_.data(), n_));
    total_ += ratio.max(-limit_).min(limit_).sum();  // an expression: no temporary array
    n_ = 0;
  }
  float limit_;
  std::array<float, kBlock> squared_error_, background_;
  int n_ = 0;
  double total_ = 0;
};

}  // namespace

BodyImageAxes imageAxes(const BodyOutlines& outlines) {
  BodyImageAxes axes;
  for (int p = 0; p < body::kNumBodyParts; ++p) {
    axes[p].visible = outlines[p].visible;
    for (int end = 0; end < 2; ++end) axes[p].ends_px[end] = outlines[p].ends_px[end].cast<float>();
  }
  return axes;
}

double evaluateLikelihood(const FrameEvidence& evidence, const BodyOutlines& outlines,
                          const BodyImageAxes* previous, const LikelihoodOptions& options,
                          PartScores* scores) {
  constexpr int kParts = body::kNumBodyParts;
  thread_local std::array<RowSpans, kParts> thread_spans;
  std::array<RowSpans, kParts>& spans = thread_spans;  // one thread-local look-up, not one per row
  // Parts near to far: a nearer part's pixels are not a farther one's.
  std::array<int, kParts> order;
  for (int p = 0; p < kParts; ++p) order[p] = p;
  std::sort(order.begin(), order.end(), [&](int a, int b) { return outlines[a].depth_m < outlines[b].depth_m; });
  for (int p = 0; p < kParts; ++p) rasterize(outlines[p], spans[p]);
  // The image motion each part predicts: the similarity that takes its axis now to its axis in
  // the previous frame maps a point z now (as a complex number) to where it was,
  // b + s (z − a) (a, b the proximal end now and before, s = axis before / axis now); the motion
  // since is z − that = (1 − s) z − (b − s a), motion_gain z − motion_offset.
  const bool flow = evidence.hasFlow() && previous != nullptr;
  std::array<std::complex<double>, kParts> motion_gain, motion_offset;
  std::array<bool, kParts> has_motion{};
  if (flow) {
    for (int p = 0; p < kParts; ++p) {
      const PartOutline& now = outlines[p];
      const PartImageAxis& before = (*previous)[p];
      if (!now.visible || !before.visible) continue;
      const std::complex<double> axis(now.ends_px[1].x() - now.ends_px[0].x(), now.ends_px[1].y() - now.ends_px[0].y());
      const std::complex<double> axis_before(before.ends_px[1].x() - before.ends_px[0].x(),
                                             before.ends_px[1].y() - before.ends_px[0].y());
      if (std::abs(axis) < 1e-6) continue;
      const std::complex<double> scale = axis_before / axis;
      motion_gain[p] = 1.0 - scale;
      motion_offset[p] = std::complex<double>(before.ends_px[0].x(), before.ends_px[0].y()) -
                         scale * std::complex<double>(now.ends_px[0].x(), now.ends_px[0].y());
      has_motion[p] = true;
    }
  }
  std::array<double, kParts> appearance_sum{}, flow_sum{};
  std::array<int, kParts> inside{}, outside{}, flow_count{};
  const cv::Rect roi = evidence.roi();
  const int step = flow ? evidence.flow().step() : 1;
  const int roi_bottom = roi.y + roi.height;
  const float flow_limit = static_cast<float>(options.flow_ratio_limit);
  Pieces pieces, next;
  // Each part over its own rows, less the spans there of the nearer parts whose rows reach them.
  for (int depth_rank = 0; depth_rank < kParts; ++depth_rank) {
    const int p = order[depth_rank];
    const RowSpans& s = spans[p];
    if (s.rows == 0) continue;
    const int end_row = s.first_row + s.rows;  // one past the part's last row
    std::array<const RowSpans*, kParts> occluders;
    int n_occluders = 0;
    for (int nearer = 0; nearer < depth_rank; ++nearer) {
      const RowSpans& o = spans[order[nearer]];
      if (o.rows > 0 && o.first_row < end_row && o.first_row + o.rows > s.first_row) occluders[n_occluders++] = &o;
    }
    const PartKind kind = partKind(static_cast<body::BodyPart>(p));
    const bool part_flow = flow && has_motion[p];
    // The part's sums in locals (registers), not in the arrays indexed by part.
    PixelTally appearance;
    FlowRatioSum motion(flow_limit);
    int points = 0;
    // Rows until the next flow grid row (a multiple of step), counted down: no division per row.
    int rows_to_grid = ((-s.first_row) % step + step) % step;
    for (int k = 0; k < s.rows; ++k) {
      const bool grid_row = rows_to_grid == 0;
      rows_to_grid = grid_row ? step - 1 : rows_to_grid - 1;
      if (s.left[k] >= s.right[k]) continue;
      const int y = s.first_row + k;
      pieces[0] = Interval{s.left[k], s.right[k]};
      const int n_pieces = subtractCovers(pieces, 1, y, occluders, n_occluders, next);
      const bool row_inside = y >= roi.y && y < roi_bottom;
      const bool flow_row = part_flow && row_inside && grid_row;
      for (int i = 0; i < n_pieces; ++i) {
        const Interval seen = appearance.add(evidence, kind, y, row_inside, pieces[i]);
        const int ca = seen.begin, cb = seen.end;
        if (flow_row && ca < cb) {
          const FlowField::RowPoints grid = evidence.flow().rowPoints(y, ca, cb);
          // The predicted motion is linear along the row: one complex add per point.
          std::complex<double> motion_px = motion_gain[p] * std::complex<double>(grid.first_x, y) - motion_offset[p];
          const std::complex<double> motion_step_px = motion_gain[p] * static_cast<double>(step);
          for (int i = 0; i < grid.count; ++i, motion_px += motion_step_px) {
            const FlowPoint& point = grid.first[i];
            motion.add(FlowField::squaredError(point, static_cast<float>(motion_px.real()), static_cast<float>(motion_px.imag())),
                       point.log1p_background);
          }
          points += grid.count;
        }
      }
    }
    appearance_sum[p] = appearance.sum;
    flow_sum[p] = motion.total();
    inside[p] = appearance.inside;
    outside[p] = appearance.outside;
    flow_count[p] = points;
  }
  double total = 0;
  for (int p = 0; p < kParts; ++p) {
    const int pixels = inside[p] + outside[p];
    PartScore score;
    score.pixels = pixels;
    score.flow_points = flow_count[p];
    if (pixels >= options.min_part_pixels) {
      const int reference = evidence.referenceAreas()[p];
      score.appearance = (appearance_sum[p] + options.outside_ratio * outside[p]) / (reference > 0 ? reference : pixels);
      total += options.appearance_weight * score.appearance;
    }
    if (flow_count[p] > 0) {
      score.flow = flow_sum[p] / flow_count[p];
      total += options.flow_weight * score.flow;
    }
    if (scores) (*scores)[p] = score;
  }
  return total;
}

PartAreas partAreas(const BodyOutlines& outlines) {
  PartAreas areas{};
  RowSpans spans;
  for (int p = 0; p < body::kNumBodyParts; ++p) {
    rasterize(outlines[p], spans);
    for (int k = 0; k < spans.rows; ++k) areas[p] += std::max(0, spans.right[k] - spans.left[k]);
  }
  return areas;
}

}  // namespace kneed_walker::core::vision
