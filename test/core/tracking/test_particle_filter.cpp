#include "kneed_walker/core/tracking/particle_filter.h"

#include <gtest/gtest.h>

#include <iostream>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <vector>

namespace kneed_walker::core::tracking {
namespace {

// A 1-D linear-Gaussian model, x_t = a x_{t−1} + N(0, q), z_t = x_t + N(0, r), whose exact
// posterior is the Kalman filter's.
struct LinearGaussian {
  double a = 0.9, q = 0.5, r = 0.3, x0_mean = 1.0, x0_var = 4.0;
  std::vector<double> observations;

  explicit LinearGaussian(int frames, unsigned seed) {
    std::mt19937_64 random(seed);
    std::normal_distribution<double> n(0, 1);
    double x = x0_mean + std::sqrt(x0_var) * n(random);
    for (int t = 0; t < frames; ++t) {
      if (t > 0) x = a * x + std::sqrt(q) * n(random);
      observations.push_back(x + std::sqrt(r) * n(random));
    }
  }
  // Kalman posterior mean and variance at each frame.
  std::vector<std::pair<double, double>> kalman() const {
    std::vector<std::pair<double, double>> result;
    double m = x0_mean, p = x0_var;
    for (size_t t = 0; t < observations.size(); ++t) {
      if (t > 0) m = a * m, p = a * a * p + q;
      const double k = p / (p + r);
      m += k * (observations[t] - m);
      p *= 1 - k;
      result.push_back({m, p});
    }
    return result;
  }
};

std::pair<double, double> weightedMoments(const ParticleFilter<double>& filter) {
  double mean = 0, second = 0;
  for (size_t i = 0; i < filter.states().size(); ++i) {
    const double w = std::exp(filter.logWeights()[i]);
    mean += w * filter.states()[i];
    second += w * filter.states()[i] * filter.states()[i];
  }
  return {mean, second - mean * mean};
}

// Runs the filter on the model; returns the worst errors of mean (in posterior SDs) and variance
// (relative), and how often it resampled.
struct FilterRun {
  double worst_mean_sd = 0, worst_variance = 0;
  // The same errors in units of their Monte Carlo standard errors at the frame's N_eff:
  // √(1/N_eff) posterior SDs for the mean, √(2/N_eff) for the relative variance.
  double worst_mean_z = 0, worst_variance_z = 0;
  int resamplings = 0;
  std::vector<double> final_states;
};
// `count_at(t)`, if given: the particle count the filter is asked for before frame t's step.
FilterRun run(const LinearGaussian& model, FilterOptions options, const std::function<int(int)>& count_at = {}) {
  ParticleFilter<double> filter(options);
  auto likelihood = [&](double& x, int frame) {
    const double e = model.observations[frame] - x;
    return -0.5 * e * e / model.r;
  };
  auto propagate = [&](double& x, int frame, common::Random& random) {
    x = model.a * x + std::sqrt(model.q) * std::normal_distribution<double>(0, 1)(random);
    return likelihood(x, frame);
  };
  filter.initialize([&](common::Random& random) {
    return model.x0_mean + std::sqrt(model.x0_var) * std::normal_distribution<double>(0, 1)(random);
  }, likelihood, 0);
  const auto exact = model.kalman();
  FilterRun result;
  for (int t = 0; t < static_cast<int>(model.observations.size()); ++t) {
    if (t > 0) {
      if (count_at) filter.setParticleCount(count_at(t));
      const bool resampled = filter.step(propagate, t).resampled;
      result.resamplings += resampled;
      // The count changes at a resampling, to the one asked for; the MAP sequence's ancestry
      // runs through sets of different sizes.
      if (resampled) EXPECT_EQ(filter.particleCount(), filter.targetParticleCount()) << "frame " << t;
      EXPECT_EQ(filter.mapSequence().size(), static_cast<size_t>(std::min(t, options.resample_lag_frames) + 1));
    }
    const auto [mean, variance] = weightedMoments(filter);
    const double ess = ParticleFilter<double>::effectiveSampleSize(filter.logWeights());
    const double mean_sd = std::abs(mean - exact[t].first) / std::sqrt(exact[t].second);
    const double variance_error = std::abs(variance / exact[t].second - 1);
    result.worst_mean_sd = std::max(result.worst_mean_sd, mean_sd);
    result.worst_variance = std::max(result.worst_variance, variance_error);
    result.worst_mean_z = std::max(result.worst_mean_z, mean_sd / std::sqrt(1.0 / ess));
    result.worst_variance_z = std::max(result.worst_variance_z, variance_error / std::sqrt(2.0 / ess));
  }
  result.final_states = filter.states();
  return result;
}

// 20000 particles over 40 frames of the model, resampling on most frames: the weighted set stays
// proper, its posterior mean and variance within a few Monte Carlo standard errors (at each
// frame's N_eff) of the Kalman filter's. Dropping the lagged resampling's importance
// re-weighting fails this at 14 standard errors.
FilterRun checkedAgainstKalman(unsigned model_seed, double ess_threshold, int lag,
                               const std::function<int(int)>& count_at = {}) {
  const LinearGaussian model(40, model_seed);
  FilterOptions options;
  options.initial_oversampling = 1;  // the N drawn are the first particles
  options.num_particles = 20000;
  options.resample_ess_fraction = ess_threshold / options.num_particles;
  options.resample_lag_frames = lag;
  options.resample_mixing = 0.95;
  const FilterRun r = run(model, options, count_at);
  std::cout << "lag " << lag << ": worst mean error " << r.worst_mean_sd << " SD (" << r.worst_mean_z
            << " standard errors), worst variance error " << r.worst_variance << " (" << r.worst_variance_z
            << " standard errors), " << r.resamplings << " resamplings\n";
  EXPECT_GT(r.resamplings, 5);
  EXPECT_LT(r.worst_mean_z, 4.5);
  EXPECT_LT(r.worst_variance_z, 4.5);
  return r;
}

TEST(ParticleFilter, MatchesTheKalmanPosteriorWithLaggedMixtureResampling) { checkedAgainstKalman(7, 4000, 3); }

TEST(ParticleFilter, MatchesTheKalmanPosteriorWithPlainResampling) {
  const FilterRun r = checkedAgainstKalman(8, 10000, 0);
  EXPECT_LT(r.worst_mean_sd, 0.08);
  EXPECT_LT(r.worst_variance, 0.12);
}

// A count that changes at resamplings (as a tracker fits its frame time): 20000 particles, then
// 12000 and 30000 in turn; the posterior stays the Kalman filter's.
TEST(ParticleFilter, MatchesTheKalmanPosteriorWhileItsCountChanges) {
  checkedAgainstKalman(9, 4000, 3, [](int t) { return t < 10 ? 20000 : (t / 5) % 2 ? 12000 : 30000; });
}

TEST(ParticleFilter, SameSeedSameParticlesOnAnyNumberOfThreads) {
  const LinearGaussian model(15, 9);
  FilterOptions options;
  options.initial_oversampling = 1;  // the N drawn are the first particles
  options.num_particles = 1000;
  options.resample_ess_fraction = 0.5;
  options.num_threads = 1;
  const FilterRun one = run(model, options);
  options.num_threads = 2;
  const FilterRun two = run(model, options);
  EXPECT_EQ(one.final_states, two.final_states);
  options.seed = 2;
  EXPECT_NE(run(model, options).final_states, one.final_states);
}

// States that carry their own history, in a filter of 200 particles stepped through `frames`
// frames: the MAP sequences must be consistent with it. Returns the number of resamplings;
// after_step(t), if given, is called after each step t.
struct History {
  std::vector<int> visited;
};
int runHistoryFilter(ParticleFilter<History>& filter, int frames, const std::function<void(int)>& after_step = {}) {
  auto likelihood = [](History& h, int frame) { return -std::abs(h.visited.back() - 2 * frame) * 0.5; };
  auto propagate = [&](History& h, int frame, common::Random& random) {
    h.visited.push_back(h.visited.back() + std::uniform_int_distribution<int>(0, 4)(random));
    return likelihood(h, frame);
  };
  filter.initialize([](common::Random& random) { return History{{std::uniform_int_distribution<int>(-2, 2)(random)}}; },
                    likelihood, 0);
  int resamplings = 0;
  for (int t = 1; t <= frames; ++t) {
    resamplings += filter.step(propagate, t).resampled;
    if (after_step) after_step(t);
  }
  return resamplings;
}
FilterOptions historyOptions(bool keep_paths) {
  FilterOptions options;
  options.initial_oversampling = 1;  // the N drawn are the first particles
  options.num_particles = 200;
  options.resample_ess_fraction = 0.75;
  options.resample_lag_frames = 3;
  options.keep_paths = keep_paths;
  return options;
}

TEST(ParticleFilter, MapSequenceFollowsTheChosenParticlesAncestry) {
  ParticleFilter<History> filter(historyOptions(false));
  EXPECT_GT(runHistoryFilter(filter, 12), 0);
  std::vector<int> frames;
  const std::vector<History> sequence = filter.mapSequence(&frames);
  ASSERT_EQ(sequence.size(), 4u);
  const History& chosen = filter.states()[filter.lagChoice()];
  for (size_t s = 0; s < sequence.size(); ++s) {
    EXPECT_EQ(frames[s], 9 + static_cast<int>(s));
    ASSERT_EQ(sequence[s].visited.size(), static_cast<size_t>(frames[s] + 1));
    for (size_t k = 0; k < sequence[s].visited.size(); ++k) EXPECT_EQ(sequence[s].visited[k], chosen.visited[k]);
  }
}

// The lagged path (the oldest buffered frame of mapSequence, as the nodelet publishes it) leaves
// its lineage only for the best particle, and only when the best of its own lineage weighs more
// than kLagContinuityLogRatio less: it breaks less often than the best particle's ancestry does.
TEST(ParticleFilter, TheLaggedPathKeepsToItsLineageUnlessAnotherWeighsFarMore) {
  FilterOptions options = historyOptions(false);
  options.resample_ess_fraction = 0.5;
  ParticleFilter<History> filter(options);
  // A path breaks when a frame's lagged state does not extend the last one's history.
  auto continues = [](const History& before, const History& after) {
    return after.visited.size() == before.visited.size() + 1 &&
           std::equal(before.visited.begin(), before.visited.end(), after.visited.begin());
  };
  History chosen_before, best_before;
  int chosen_breaks = 0, best_breaks = 0, chosen_not_best = 0;
  runHistoryFilter(filter, 60, [&](int t) {
    const std::vector<double>& w = filter.logWeights();
    const int chosen = filter.lagChoice(), best = filter.best();
    EXPECT_GE(w[chosen], w[best] - ParticleFilter<History>::kLagContinuityLogRatio) << "frame " << t;
    const History chosen_now = filter.mapSequence().front(), best_now = filter.ancestry(best).front();
    if (t > options.resample_lag_frames + 1) {
      const bool kept = continues(chosen_before, chosen_now);
      chosen_breaks += !kept;
      best_breaks += !continues(best_before, best_now);
      if (chosen != best) {
        ++chosen_not_best;
        EXPECT_TRUE(kept) << "frame " << t << ": left its lineage for a particle that is not the best";
      }
    }
    chosen_before = chosen_now;
    best_before = best_now;
  });
  std::cout << "path breaks over 56 frames: kept lineage " << chosen_breaks << ", best particle's ancestry "
            << best_breaks << " (" << chosen_not_best << " frames kept a particle other than the best)\n";
  EXPECT_GT(chosen_not_best, 0);
  EXPECT_LT(chosen_breaks, best_breaks);
}

// With keep_paths the whole MAP sequence is the best particle's own history from the first
// frame, and the kept genealogy holds only lineages that still have descendants: after
// resampling they coalesce, so it stays far below frames × N.
TEST(ParticleFilter, WholeMapSequenceIsTheBestParticlesHistoryAndPrunes) {
  const FilterOptions options = historyOptions(true);
  ParticleFilter<History> filter(options);
  constexpr int kFrames = 60;
  EXPECT_GT(runHistoryFilter(filter, kFrames), 10);
  std::vector<int> frames;
  const std::vector<History> sequence = filter.wholeMapSequence(&frames);
  ASSERT_EQ(sequence.size(), static_cast<size_t>(kFrames + 1));
  const History& best = filter.states()[filter.best()];
  for (size_t s = 0; s < sequence.size(); ++s) {
    ASSERT_EQ(frames[s], static_cast<int>(s));
    ASSERT_EQ(sequence[s].visited.size(), s + 1);
    EXPECT_EQ(sequence[s].visited.back(), best.visited[s]) << "frame " << s;
  }
  const std::size_t kept = filter.keptPathStates();
  std::cout << "kept " << kept << " states for " << kFrames - options.resample_lag_frames << " retired frames of "
            << options.num_particles << " particles\n";
  EXPECT_GE(kept, static_cast<size_t>(options.num_particles));  // the newest retired generation
  EXPECT_LT(kept, static_cast<size_t>(6 * options.num_particles));  // measured 3.6 N
  EXPECT_THROW(ParticleFilter<History>(FilterOptions{}).wholeMapSequence(), std::logic_error);
}

// The tree on its own: paths, pruning of dead lineages, reuse of freed nodes.
TEST(AncestryTree, KeepsOnlyLineagesWithDescendants) {
  AncestryTree<int> tree;
  tree.addGeneration(0, {10, 11, 12}, {-1, -1, -1});
  tree.addGeneration(1, {20, 21, 22}, {0, 0, 2});  // 11 has no child: released
  EXPECT_EQ(tree.liveNodes(), 5u);
  tree.addGeneration(2, {30, 31, 32}, {1, 1, 1});  // all from 21: 10, 12, 20, 22 released
  EXPECT_EQ(tree.liveNodes(), 5u);                  // 10, 21, 30, 31, 32
  std::vector<int> frames;
  EXPECT_EQ(tree.path(2, &frames), (std::vector<int>{10, 21, 32}));
  EXPECT_EQ(frames, (std::vector<int>{0, 1, 2}));
  tree.addGeneration(3, {40, 41, 42}, {-1, 0, 2});  // a new root beside two lineages
  EXPECT_EQ(tree.path(0), (std::vector<int>{40}));
  EXPECT_EQ(tree.path(2), (std::vector<int>{10, 21, 32, 42}));
  EXPECT_EQ(tree.liveNodes(), 7u);
}

// A first frame whose likelihood is 1000 times sharper than the initial distribution: N(0, 10²)
// drawn, z = 7.3 observed with SD 0.01, so the posterior is N(≈ 7.3, ≈ 0.01²) and 200 draws put
// about 0.4 within 3 posterior SDs of it. Oversampled 500 times, the 100 000 candidates put about
// 180 there, and the 200 kept (equal weights) are a sample of the posterior; without it, one or
// two particles carry the weight.
TEST(ParticleFilter, InitialOversamplingSamplesASharpFirstPosteriorFromABroadGuess) {
  const double prior_sd = 10.0, z = 7.3, r = 0.01;
  const double posterior_variance = 1.0 / (1.0 / (prior_sd * prior_sd) + 1.0 / (r * r));
  const double posterior_mean = posterior_variance * z / (r * r);
  auto initialized = [&](int oversampling, int threads) {
    FilterOptions options;
    options.num_particles = 200;
    options.resample_ess_fraction = 0.1;
    options.initial_oversampling = oversampling;
    options.num_threads = threads;
    ParticleFilter<double> filter(options);
    const FilterStepReport report = filter.initialize(
        [&](common::Random& random) { return prior_sd * std::normal_distribution<double>(0, 1)(random); },
        [&](double& x, int) { return -0.5 * (x - z) * (x - z) / (r * r); }, 0);
    return std::make_pair(report, filter.states());
  };
  const auto [plain_report, plain] = initialized(1, 0);
  std::cout << "without oversampling: N_eff " << plain_report.effective_sample_size << "\n";
  EXPECT_LT(plain_report.effective_sample_size, 5);

  const auto [report, states] = initialized(500, 1);
  ASSERT_EQ(states.size(), 200u);
  EXPECT_NEAR(report.effective_sample_size, 200, 1e-9);  // equal weights after resampling
  double mean = 0, second = 0;
  for (double x : states) mean += x / states.size(), second += x * x / states.size();
  const double variance = second - mean * mean;
  const std::vector<double> distinct = [&] {
    std::vector<double> d = states;
    std::sort(d.begin(), d.end());
    d.erase(std::unique(d.begin(), d.end()), d.end());
    return d;
  }();
  std::cout << "oversampled 500 times: mean " << mean << " (posterior " << posterior_mean << "), SD "
            << std::sqrt(variance) << " (posterior " << std::sqrt(posterior_variance) << "), " << distinct.size()
            << " distinct of 200\n";
  EXPECT_GT(distinct.size(), 50u);
  EXPECT_LT(std::abs(mean - posterior_mean), 0.5 * std::sqrt(posterior_variance));
  EXPECT_NEAR(variance / posterior_variance, 1.0, 0.5);
  // Deterministic for the seed on any number of threads.
  EXPECT_EQ(initialized(500, 2).second, states);
}

// A state that counts how many of its kind exist at once.
struct CountedState {
  static inline std::atomic<int> alive{0}, peak{0};
  double x = 0;
  double weighed = std::numeric_limits<double>::quiet_NaN();  // what weigh() cached in it
  CountedState() { arrive(); }
  CountedState(const CountedState& other) : x(other.x), weighed(other.weighed) { arrive(); }
  CountedState& operator=(const CountedState&) = default;
  ~CountedState() { --alive; }
  static void arrive() {
    const int now = ++alive;
    int before = peak.load();
    while (now > before && !peak.compare_exchange_weak(before, now)) {
    }
  }
};

// The first frame's k·N candidates are weighed without being held at once (the tracker's are
// 5000 × 32 of 1 kB each): at most the N kept and a few in each thread's hands exist together,
// and each kept one carries what weigh() cached in it.
TEST(ParticleFilter, InitialOversamplingHoldsOnlyTheKeptCandidates) {
  FilterOptions options;
  options.num_particles = 100;
  options.initial_oversampling = 200;
  options.num_threads = 2;
  auto weight = [](double x) { return -0.5 * (x - 1.0) * (x - 1.0) / 0.01; };
  ParticleFilter<CountedState> filter(options);
  CountedState::alive = 0;
  CountedState::peak = 0;
  filter.initialize(
      [](common::Random& random) {
        CountedState s;
        s.x = std::normal_distribution<double>(0, 1)(random);
        return s;
      },
      [&](CountedState& s, int) { return s.weighed = weight(s.x); }, 0);
  std::cout << "candidates held at once, at most: " << CountedState::peak << " (kept: 100, drawn: 20000)\n";
  EXPECT_LE(CountedState::peak, 100 + 10);
  ASSERT_EQ(filter.states().size(), 100u);
  for (const CountedState& s : filter.states()) EXPECT_DOUBLE_EQ(s.weighed, weight(s.x));
}

TEST(ParticleFilter, LogSumExpIsStable) {
  EXPECT_NEAR(logSumExp({1000.0, 1000.0}), 1000.0 + std::log(2.0), 1e-12);
  EXPECT_NEAR(logSumExp({-1000.0, -1001.0}), -1000.0 + std::log1p(std::exp(-1.0)), 1e-12);
  EXPECT_EQ(logSumExp({}), -std::numeric_limits<double>::infinity());
}

TEST(ParticleFilter, RefusesBadOptions) {
  FilterOptions options;
  options.initial_oversampling = 1;  // the N drawn are the first particles
  options.num_particles = 100;
  options.resample_ess_fraction = 5;
  EXPECT_THROW(ParticleFilter<double>{options}, std::invalid_argument);
  options.resample_ess_fraction = 0.5;
  options.resample_mixing = 1.5;
  EXPECT_THROW(ParticleFilter<double>{options}, std::invalid_argument);
  options.resample_mixing = 0.95;
  options.initial_oversampling = 0;
  EXPECT_THROW(ParticleFilter<double>{options}, std::invalid_argument);
}

}  // namespace
}  // namespace kneed_walker::core::tracking
