#include "kneed_walker/core/vision/appearance_model.h"

#include <opencv2/ml.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace kneed_walker::core::vision {
namespace {

constexpr int kLevels = 64;  // colour cells per channel

// A Gaussian mixture in colour, tabulated at the cell centres.
std::vector<float> tabulate(const std::vector<cv::Vec3b>& pixels, const AppearanceOptions& options) {
  cv::Mat samples(static_cast<int>(pixels.size()), 3, CV_64F);
  for (int i = 0; i < samples.rows; ++i)
    for (int c = 0; c < 3; ++c) samples.at<double>(i, c) = pixels[i][c];
  const int k = std::max(1, std::min(options.components, samples.rows / 10));
  cv::Ptr<cv::ml::EM> em = cv::ml::EM::create();
  em->setClustersNumber(k);
  em->setCovarianceMatrixType(cv::ml::EM::COV_MAT_GENERIC);
  em->setTermCriteria(cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-4));
  cv::theRNG().state = 12345;  // EM's k-means start is random: seed it, for repeatable models
  if (!em->trainEM(samples)) throw std::runtime_error("appearance model: EM did not converge");
  const cv::Mat weights = em->getWeights();
  const cv::Mat means = em->getMeans();
  std::vector<cv::Mat> covariances;
  em->getCovs(covariances);
  // Floored components: the inverse and log normaliser of each.
  std::vector<cv::Matx33d> inverses(k);
  std::vector<double> log_normalisers(k);
  for (int j = 0; j < k; ++j) {
    cv::Matx33d covariance = cv::Matx33d(covariances[j]);
    for (int c = 0; c < 3; ++c) covariance(c, c) += options.colour_floor * options.colour_floor;
    inverses[j] = covariance.inv();
    log_normalisers[j] = std::log(std::max(weights.at<double>(j), 1e-12)) -
                         0.5 * (3 * std::log(2 * M_PI) + std::log(cv::determinant(covariance)));
  }
  std::vector<float> table(kLevels * kLevels * kLevels);
  for (int b = 0; b < kLevels; ++b)
    for (int g = 0; g < kLevels; ++g)
      for (int r = 0; r < kLevels; ++r) {
        const cv::Vec3d colour(4 * b + 1.5, 4 * g + 1.5, 4 * r + 1.5);
        double best = -1e300, terms[8];
        for (int j = 0; j < k; ++j) {
          const cv::Vec3d d = colour - cv::Vec3d(means.at<double>(j, 0), means.at<double>(j, 1), means.at<double>(j, 2));
          terms[j] = log_normalisers[j] - 0.5 * d.dot(inverses[j] * d);
          best = std::max(best, terms[j]);
        }
        double sum = 0;
        for (int j = 0; j < k; ++j) sum += std::exp(terms[j] - best);
        table[(b * kLevels + g) * kLevels + r] = static_cast<float>(best + std::log(sum));
      }
  return table;
}

}  // namespace

PartKind partKind(body::BodyPart part) {
  switch (part) {
    case body::kTorsoPart: return kTorsoKind;
    case body::kHeadPart: return kHeadKind;
    case body::kLeftThighPart:
    case body::kRightThighPart: return kThighKind;
    case body::kLeftShankPart:
    case body::kRightShankPart: return kShankKind;
    default: return kFootKind;
  }
}

AppearanceModel AppearanceModel::learn(const std::array<std::vector<cv::Vec3b>, kNumPartKinds>& samples,
                                       const AppearanceOptions& options) {
  std::vector<cv::Vec3b> all;
  for (const auto& kind : samples) all.insert(all.end(), kind.begin(), kind.end());
  if (static_cast<int>(all.size()) < options.min_pixels)
    throw std::invalid_argument("appearance model: " + std::to_string(all.size()) +
                                " foreground pixels, fewer than " + std::to_string(options.min_pixels));
  AppearanceModel model;
  std::vector<float> pooled;
  for (int kind = 0; kind < kNumPartKinds; ++kind) {
    if (static_cast<int>(samples[kind].size()) >= options.min_pixels) {
      model.table_[kind] = tabulate(samples[kind], options);
    } else {
      if (pooled.empty()) pooled = tabulate(all, options);
      model.table_[kind] = pooled;
    }
  }
  const double variance = options.gradient_sd * options.gradient_sd;
  model.gradient_scale_ = static_cast<float>(-0.5 / variance);
  model.gradient_log_normaliser_ = static_cast<float>(-std::log(2 * M_PI * variance));
  return model;
}

}  // namespace kneed_walker::core::vision
