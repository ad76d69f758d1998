// The particle filter of paper §4 ("Inference"), generic over the state: a weighted set of state
// sequences, propagated by the prior and weighted by the likelihood, resampled when the
// effective sample size N_eff = 1 / Σ w² falls below a threshold. Resampling is from time
// t − Δs, with a proposal that mixes the weights at t (probability γ) and at t − Δs, and
// importance re-weighting w ∝ w_{t−Δs} / (γ W_t + (1 − γ) w_{t−Δs}), W_t the weight at t of a
// particle's descendants (the paper, following Doucet et al.); the resampled particles are then
// propagated again to t through the buffered frames.
//
// The model is one callback, propagate(state, frame, random): it advances a state from frame − 1
// to `frame` by the prior and returns log p(z_frame | state) (the last Δs + 1 frames must stay
// available to it, for resampling); the state may cache what the next frame needs. The first
// frame's particles come from sample(random) and are weighed by weigh(state, frame); with
// FilterOptions::initial_oversampling k > 1, k·N are drawn and weighed and N kept by systematic
// resampling (sampling importance resampling of the first frame's posterior with k times the
// particles). Log-weights are doubles, normalised by log-sum-exp. Each
// particle's ancestry through the buffer is kept, so that the MAP state sequence (the ancestry
// of the best particle) is available, not only a per-frame mean. The fixed-lag smoother's
// sequence (mapSequence) keeps to the lineage it followed while that weighs nearly as much as the
// best (kLagContinuityLogRatio): each frame's lagged state then follows from the last one's.
//
// With FilterOptions::keep_paths the ancestry is kept beyond the buffer too, back to the first
// frame (AncestryTree: only lineages that still have descendants), so that the whole MAP state
// sequence of a track can be had at its end: one particle's path, which the prior made, where
// the sequence of each frame's lagged state may jump between particles.
//
// The number of particles may change at a resampling (setParticleCount: a tracker that fits its
// work into a frame's time, as amcl adapts its count): resampling draws the new count from the
// old set.
//
// Deterministic for a seed on any number of threads: particles are processed in fixed chunks of
// kChunk, each with its own generator seeded from (seed, frame, pass, chunk).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "kneed_walker/core/common/parallel.h"
#include "kneed_walker/core/common/random.h"

namespace kneed_walker::core::tracking {

// The filter's settings; the paper's §5 uses 5000 particles and resamples below N_eff = 500.
// Their ranges and help, for people: TrackerOptions' option table (tracker_options.h).
struct FilterOptions {
  int num_particles = 5000;            // N
  double resample_ess_fraction = 0.1;  // resample when N_eff falls below this times N, (0, 1]
  int resample_lag_frames = 3;         // Δs
  double resample_mixing = 0.95;       // γ: weight of the time-t weights in the proposal
  int num_threads = 0;                 // 0: all cores
  std::uint64_t seed = 1;
  bool keep_paths = false;             // keep the ancestry back to the first frame (wholeMapSequence)
  // The first frame draws and weighs this many times N candidates and keeps N of them by
  // systematic resampling (equal weights): a broad initial distribution is searched with k·N
  // samples at k times one frame's cost, once. 1: the N drawn are the particles. A tracker's
  // initial guess is coarse (position ± 0.25 m, heading, phase and gait unknown): N particles
  // drawn from it put none near the person, and the filter locks onto a nearby wrong walk that
  // it cannot leave; k·N ≤ kMaxInitialCandidates (each is weighed, and its weight held).
  int initial_oversampling = 32;       // k ≥ 1
};
// The most candidates a first frame may draw (FilterOptions::initial_oversampling).
constexpr long long kMaxInitialCandidates = 10'000'000;

// The genealogy of a particle system, generation by generation, pruned as it grows: a node is
// kept while it is in the newest generation or has a kept child, so that it holds only the
// lineages of the newest generation (after resampling they coalesce within a few generations;
// Jacob, Murray & Rubenthaler, "Path storage in the particle filter", 2015). Nodes live in one
// pool whose freed slots are reused: no allocation once the pool has grown to its largest size.
template <class Payload>
class AncestryTree {
 public:
  void clear() {
    nodes_.clear();
    free_.clear();
    newest_.clear();
  }
  bool empty() const { return newest_.empty(); }

  // Adds a generation: payloads[i] at `frame` is a child of the newest generation's parents[i]
  // (−1: a root). Then every node left without descendants in it is released.
  void addGeneration(int frame, const std::vector<Payload>& payloads, const std::vector<int>& parents) {
    std::vector<int> generation(payloads.size());
    for (std::size_t i = 0; i < payloads.size(); ++i) {
      const int parent = parents[i] >= 0 && !newest_.empty() ? newest_.at(parents[i]) : -1;
      int id;
      if (free_.empty()) {
        id = static_cast<int>(nodes_.size());
        nodes_.push_back({payloads[i], frame, parent, 1});
      } else {
        id = free_.back();
        free_.pop_back();
        nodes_[id] = {payloads[i], frame, parent, 1};
      }
      if (parent >= 0) ++nodes_[parent].references;
      generation[i] = id;
    }
    for (int id : newest_) release(id);
    newest_ = std::move(generation);
  }

  // The path that ends at the newest generation's particle `index`, oldest first.
  std::vector<Payload> path(int index, std::vector<int>* frames = nullptr) const {
    std::vector<Payload> payloads;
    std::vector<int> path_frames;
    for (int id = newest_.at(index); id >= 0; id = nodes_[id].parent) {
      payloads.push_back(nodes_[id].payload);
      path_frames.push_back(nodes_[id].frame);
    }
    std::reverse(payloads.begin(), payloads.end());
    std::reverse(path_frames.begin(), path_frames.end());
    if (frames) *frames = std::move(path_frames);
    return payloads;
  }

  std::size_t liveNodes() const { return nodes_.size() - free_.size(); }

 private:
  struct Node {
    Payload payload;
    int frame = 0;
    int parent = -1;     // −1: a root
    int references = 0;  // kept children, plus 1 while in the newest generation
  };
  void release(int id) {  // iterative: a released chain may be long
    while (id >= 0 && --nodes_[id].references == 0) {
      free_.push_back(id);
      id = nodes_[id].parent;
    }
  }
  std::vector<Node> nodes_;
  std::vector<int> free_;
  std::vector<int> newest_;  // node of each particle of the newest generation
};

// What one step did.
struct FilterStepReport {
  double effective_sample_size = 0;  // N_eff after the step (after resampling, if any)
  double ess_before_resampling = 0;  // N_eff of the weights at t before any resampling
  bool resampled = false;
  int resampled_from_frame = -1;     // t − Δs (or the oldest buffered frame)
  double max_log_likelihood = 0;     // of the frame's new observation, over the particles
  double resample_ms = 0;            // wall time of the resampling, its re-propagation included
};

// A 64-bit mix of several integers (SplitMix64 steps): the seed of one chunk's generator.
std::uint64_t mixSeed(std::uint64_t seed, std::uint64_t frame, std::uint64_t pass, std::uint64_t chunk);

// log Σ exp(x_i) without overflow; −inf for an empty or all −inf input.
double logSumExp(const std::vector<double>& x);

template <class State>
class ParticleFilter {
 public:
  using Propagate = std::function<double(State& state, int frame, common::Random& random)>;
  using Weigh = std::function<double(State& state, int frame)>;
  static constexpr int kChunk = 64;
  // How much less than the best particle's log-weight the lagged path's lineage may weigh and
  // still be kept (chooseLagPath). Of 0, 2, 5 and 20 nats, 5 gave the lagged output the least
  // foot skate at the same joint error (a 30 fps walk, seeds 1 and 2; the 10 fps sequences).
  static constexpr double kLagContinuityLogRatio = 5.0;

  explicit ParticleFilter(const FilterOptions& options) : options_(options), target_count_(options.num_particles) {
    if (options.num_particles < 1) throw std::invalid_argument("num_particles must be >= 1");
    if (!(options.resample_ess_fraction > 0 && options.resample_ess_fraction <= 1))
      throw std::invalid_argument("resample_ess_fraction must lie in (0, 1]");
    if (options.resample_lag_frames < 0) throw std::invalid_argument("resample_lag_frames must be >= 0");
    if (!(options.resample_mixing >= 0 && options.resample_mixing <= 1))
      throw std::invalid_argument("resample_mixing must lie in [0, 1]");
    if (options.initial_oversampling < 1 ||
        static_cast<long long>(options.num_particles) * options.initial_oversampling > std::numeric_limits<int>::max())
      throw std::invalid_argument("initial_oversampling must be >= 1, and times num_particles an int");
  }

  // Draws the particles of the first frame from `sample` and weighs them by that frame (with
  // initial_oversampling k > 1: draws and weighs k·N, keeps N by systematic resampling).
  // The k·N candidates are not held at once (160 MB for the tracker's 5000 × 32): a first pass
  // keeps their weights only, and the kept ones are then drawn again, by replaying their chunks'
  // generators, and weighed again. So `sample` must draw only from the generator it is given,
  // and `weigh` must give a state the same weight and cached values whenever it is called.
  FilterStepReport initialize(const std::function<State(common::Random&)>& sample,
                              const Weigh& weigh, int frame) {
    sets_.clear();
    retired_.clear();
    Set set;
    set.frame = frame;
    const int n = target_count_;
    const int candidates = n * options_.initial_oversampling;
    set.ancestors.assign(n, -1);
    FilterStepReport report;
    if (candidates == n) {
      set.states.resize(n);
      set.log_weights.assign(n, 0.0);
      forChunks(frame, 0, n, [&](int i, common::Random& random) {
        set.states[i] = sample(random);
        set.log_weights[i] = weigh(set.states[i], frame);
      });
      report.max_log_likelihood = *std::max_element(set.log_weights.begin(), set.log_weights.end());
      normalise(set.log_weights);
    } else {
      std::vector<double> log_weights(candidates);
      forChunks(frame, 0, candidates, [&](int i, common::Random& random) {
        State candidate = sample(random);
        log_weights[i] = weigh(candidate, frame);
      });
      report.max_log_likelihood = *std::max_element(log_weights.begin(), log_weights.end());
      normalise(log_weights);
      std::vector<double> probabilities(candidates);
      for (int i = 0; i < candidates; ++i) probabilities[i] = std::exp(log_weights[i]);
      common::Random random(mixSeed(options_.seed, static_cast<std::uint64_t>(frame), kInitialResamplingPass, 0));
      const std::vector<int> kept = systematic(probabilities, n, std::uniform_real_distribution<double>(0.0, 1.0)(random));
      // The kept candidates (in increasing order) chunk by chunk: each chunk's generator is
      // replayed up to its last kept candidate.
      std::vector<int> chunk_starts;  // positions in `kept` where another chunk's candidates begin
      for (int j = 0; j < n; ++j)
        if (j == 0 || kept[j] / kChunk != kept[j - 1] / kChunk) chunk_starts.push_back(j);
      chunk_starts.push_back(n);
      set.states.resize(n);
      common::parallelFor(static_cast<int>(chunk_starts.size()) - 1, options_.num_threads, [&](int begin, int end) {
        for (int c = begin; c < end; ++c) {
          const int chunk = kept[chunk_starts[c]] / kChunk;
          common::Random replay(mixSeed(options_.seed, static_cast<std::uint64_t>(frame), 0, static_cast<std::uint64_t>(chunk)));
          for (int i = chunk * kChunk, j = chunk_starts[c]; j < chunk_starts[c + 1]; ++i) {
            State candidate = sample(replay);
            if (i != kept[j]) continue;
            weigh(candidate, frame);
            for (; j < chunk_starts[c + 1] && kept[j] == i; ++j) set.states[j] = candidate;
          }
        }
      }, 1);
      set.log_weights.assign(n, -std::log(static_cast<double>(n)));
    }
    sets_.push_back(std::move(set));
    report.effective_sample_size = report.ess_before_resampling = effectiveSampleSize(sets_.back().log_weights);
    lag_choice_ = lag_choice_oldest_ = best();
    return report;
  }

  // Advances every particle to `frame` (the next frame after the last one) and weighs it.
  FilterStepReport step(const Propagate& propagate, int frame) {
    if (sets_.empty()) throw std::logic_error("ParticleFilter::step before initialize");
    const Set& previous = sets_.back();
    Set set;
    set.frame = frame;
    set.states = previous.states;
    set.log_weights.resize(previous.states.size());
    set.ancestors.resize(previous.states.size());
    std::vector<double> likelihoods(previous.states.size());
    forChunks(frame, 0, particleCount(), [&](int i, common::Random& random) {
      likelihoods[i] = propagate(set.states[i], frame, random);
      set.log_weights[i] = previous.log_weights[i] + likelihoods[i];
      set.ancestors[i] = i;
    });
    FilterStepReport report;
    report.max_log_likelihood = *std::max_element(likelihoods.begin(), likelihoods.end());
    normalise(set.log_weights);
    sets_.push_back(std::move(set));
    bool retired = false;
    while (static_cast<int>(sets_.size()) > options_.resample_lag_frames + 1) {
      // The oldest set is final: resampling only rewrites the buffered frames after it.
      if (options_.keep_paths) retired_.addGeneration(sets_.front().frame, sets_.front().states, sets_.front().ancestors);
      sets_.pop_front();
      retired = true;
    }
    report.ess_before_resampling = effectiveSampleSize(sets_.back().log_weights);
    if (report.ess_before_resampling < options_.resample_ess_fraction * particleCount()) {
      const auto started = std::chrono::steady_clock::now();
      resample(propagate, report);
      report.resampled = true;
      report.resample_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
    }
    report.effective_sample_size = effectiveSampleSize(sets_.back().log_weights);
    chooseLagPath(retired);
    return report;
  }

  // The particles now (the newest frame's), and the count the next resampling draws (at least 1;
  // FilterOptions::num_particles until set).
  int particleCount() const { return sets_.empty() ? options_.num_particles : static_cast<int>(sets_.back().states.size()); }
  void setParticleCount(int count) { target_count_ = std::max(1, count); }
  int targetParticleCount() const { return target_count_; }

  // The particles at the newest frame and their normalised log-weights.
  const std::vector<State>& states() const { return sets_.back().states; }
  const std::vector<double>& logWeights() const { return sets_.back().log_weights; }
  int frame() const { return sets_.back().frame; }
  int best() const {
    const auto& w = sets_.back().log_weights;
    return static_cast<int>(std::max_element(w.begin(), w.end()) - w.begin());
  }
  // The fixed-lag smoother's state sequence over the buffered frames, oldest first: the ancestry
  // of the particle at the newest frame that chooseLagPath() chose (the best one, unless the best
  // of those continuing the last retired frame's path weighs nearly as much). `frames` receives
  // their frame numbers.
  std::vector<State> mapSequence(std::vector<int>* frames = nullptr) const { return ancestry(lag_choice_, frames); }
  int lagChoice() const { return lag_choice_; }
  // The ancestry of particle `index` at the newest frame through the buffer, oldest first.
  std::vector<State> ancestry(int index, std::vector<int>* frames = nullptr) const {
    std::vector<State> sequence(sets_.size());
    if (frames) frames->resize(sets_.size());
    for (int s = static_cast<int>(sets_.size()) - 1; s >= 0; --s) {
      sequence[s] = sets_[s].states[index];
      if (frames) (*frames)[s] = sets_[s].frame;
      index = sets_[s].ancestors[index];
      if (index < 0 && s > 0) throw std::logic_error("broken ancestry");
    }
    return sequence;
  }
  // With keep_paths: the MAP state sequence from the first frame, oldest first: the whole
  // ancestry of the best particle at the newest frame. `frames` receives their frame numbers.
  std::vector<State> wholeMapSequence(std::vector<int>* frames = nullptr) const {
    if (!options_.keep_paths) throw std::logic_error("wholeMapSequence needs FilterOptions::keep_paths");
    std::vector<int> buffered_frames;
    std::vector<State> buffered = ancestry(best(), &buffered_frames);
    int oldest_ancestor = best();  // becomes the index into the newest retired generation (−1: none)
    for (int s = static_cast<int>(sets_.size()) - 1; s >= 0; --s) oldest_ancestor = sets_[s].ancestors[oldest_ancestor];
    std::vector<State> sequence;
    if (oldest_ancestor >= 0 && !retired_.empty()) sequence = retired_.path(oldest_ancestor, frames);
    else if (frames) frames->clear();
    sequence.insert(sequence.end(), buffered.begin(), buffered.end());
    if (frames) frames->insert(frames->end(), buffered_frames.begin(), buffered_frames.end());
    return sequence;
  }
  std::size_t keptPathStates() const { return retired_.liveNodes(); }  // states kept beyond the buffer
  const FilterOptions& options() const { return options_; }

  static double effectiveSampleSize(const std::vector<double>& normalised_log_weights) {
    double sum = 0;
    for (double lw : normalised_log_weights) sum += std::exp(2 * lw);
    return sum > 0 ? 1.0 / sum : 0.0;
  }

 private:
  struct Set {
    int frame = 0;
    std::vector<State> states;
    std::vector<double> log_weights;  // normalised
    std::vector<int> ancestors;       // index into the previous set; −1 for the first frame
  };

  // The generator pass of the first frame's resampling of its candidates (the other passes are
  // 0 and, at frame t, 2t + 1 and 2t + 2).
  static constexpr std::uint64_t kInitialResamplingPass = ~std::uint64_t{0};

  // Calls f(i, random) for items 0..n−1 (particles, or the initial candidates), chunk by chunk,
  // each chunk with its own generator.
  template <class F>
  void forChunks(int frame, std::uint64_t pass, int n, F&& f) {
    const int chunks = (n + kChunk - 1) / kChunk;
    common::parallelFor(chunks, options_.num_threads, [&](int begin, int end) {
      for (int c = begin; c < end; ++c) {
        common::Random random(mixSeed(options_.seed, static_cast<std::uint64_t>(frame),
                                      static_cast<std::uint64_t>(pass), static_cast<std::uint64_t>(c)));
        for (int i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) f(i, random);
      }
    }, 1);
  }

  static void normalise(std::vector<double>& log_weights) {
    const double total = logSumExp(log_weights);
    if (!std::isfinite(total)) {  // every particle impossible: start again from equal weights
      std::fill(log_weights.begin(), log_weights.end(), -std::log(double(log_weights.size())));
      return;
    }
    for (double& lw : log_weights) lw -= total;
  }

  // Systematic resampling of `count` indices from normalised probabilities.
  static std::vector<int> systematic(const std::vector<double>& probabilities, int count, double u0) {
    std::vector<int> indices(count);
    double cumulative = probabilities[0];
    int j = 0;
    const int last = static_cast<int>(probabilities.size()) - 1;
    for (int k = 0; k < count; ++k) {
      const double u = (k + u0) / count;
      while (u > cumulative && j < last) cumulative += probabilities[++j];
      indices[k] = j;
    }
    return indices;
  }

  void resample(const Propagate& propagate, FilterStepReport& report) {
    const int count = target_count_;  // after; the buffered sets may differ in size before
    const int base = 0;  // the oldest buffered set: frame t − Δs (or the first frame)
    const int last = static_cast<int>(sets_.size()) - 1;
    report.resampled_from_frame = sets_[base].frame;
    // W: each base particle's share of the weight at t (its descendants').
    std::vector<double> descendants(sets_[last].states.size());
    for (std::size_t i = 0; i < descendants.size(); ++i) descendants[i] = std::exp(sets_[last].log_weights[i]);
    for (int s = last; s > base; --s) {
      std::vector<double> up(sets_[s - 1].states.size(), 0.0);
      for (std::size_t i = 0; i < descendants.size(); ++i) up[sets_[s].ancestors[i]] += descendants[i];
      descendants.swap(up);
    }
    const double gamma = options_.resample_mixing;
    const int n = static_cast<int>(sets_[base].states.size());
    std::vector<double> proposal(n), base_weights(n);
    for (int j = 0; j < n; ++j) {
      base_weights[j] = std::exp(sets_[base].log_weights[j]);
      proposal[j] = gamma * descendants[j] + (1 - gamma) * base_weights[j];
    }
    const double proposal_sum = std::accumulate(proposal.begin(), proposal.end(), 0.0);
    for (double& p : proposal) p /= proposal_sum;
    // Each resampling draws fresh noise: its passes are told apart by the frame it happens at.
    const std::uint64_t now = static_cast<std::uint64_t>(sets_[last].frame);
    common::Random random(mixSeed(options_.seed, now, 2 * now + 2, 0));
    const std::vector<int> picked =
        systematic(proposal, count, std::uniform_real_distribution<double>(0.0, 1.0)(random));

    // The resampled particles at the base frame, re-weighted, then propagated again to t.
    std::vector<State> states(count);
    std::vector<double> log_weights(count);
    for (int k = 0; k < count; ++k) {
      states[k] = sets_[base].states[picked[k]];
      log_weights[k] = base == last ? 0.0
                                    : std::log(base_weights[picked[k]]) - std::log(proposal[picked[k]]);
    }
    if (base == last) {  // no lag buffered: plain resampling at t, equal weights
      Set& set = sets_[last];
      std::vector<int> ancestors(count);
      for (int k = 0; k < count; ++k) ancestors[k] = set.ancestors[picked[k]];
      set.states = std::move(states);
      set.ancestors = std::move(ancestors);
      set.log_weights.assign(count, -std::log(double(count)));
      return;
    }
    for (int s = base + 1; s <= last; ++s) {
      Set& set = sets_[s];
      forChunks(set.frame, 2 * now + 1, count, [&](int i, common::Random& r) {
        log_weights[i] += propagate(states[i], set.frame, r);
      });
      std::vector<double> normalised = log_weights;
      normalise(normalised);
      set.states = states;
      set.log_weights = std::move(normalised);
      if (s == base + 1) {
        set.ancestors = picked;
      } else {
        set.ancestors.resize(count);
        std::iota(set.ancestors.begin(), set.ancestors.end(), 0);
      }
    }
  }

  // The particle at `index` in the newest set's ancestor in the oldest buffered set.
  int oldestAncestor(int index) const {
    for (int s = static_cast<int>(sets_.size()) - 1; s > 0; --s) index = sets_[s].ancestors[index];
    return index;
  }
  // Chooses the particle whose ancestry mapSequence() gives: the best of those whose path
  // continues the path chosen at the last step (through its state in the oldest buffered set,
  // which `retired` says has just been retired) when it weighs no more than kLagContinuityLogRatio
  // less than the best; else the best. A path that jumps between particles jumps between walkers
  // whose feet stand in different places: the output's feet slide.
  void chooseLagPath(bool retired) {
    const std::vector<double>& w = sets_.back().log_weights;
    const int best_index = best();
    int chosen = best_index;
    int continuing = -1;
    for (int i = 0; i < static_cast<int>(w.size()); ++i) {
      const int oldest = oldestAncestor(i);
      const int previous = retired ? sets_.front().ancestors[oldest] : oldest;
      if (previous == lag_choice_oldest_ && (continuing < 0 || w[i] > w[continuing])) continuing = i;
    }
    if (continuing >= 0 && w[continuing] >= w[best_index] - kLagContinuityLogRatio) chosen = continuing;
    lag_choice_ = chosen;
    lag_choice_oldest_ = oldestAncestor(chosen);
  }
  FilterOptions options_;
  int lag_choice_ = 0;         // the newest set's particle whose ancestry mapSequence() gives
  int lag_choice_oldest_ = 0;  // its ancestor in the oldest buffered set
  int target_count_;      // the particles the next resampling draws
  std::deque<Set> sets_;  // the last Δs + 1 frames, oldest first
  AncestryTree<State> retired_;  // with keep_paths: the lineages of the frames before the buffer
};

}  // namespace kneed_walker::core::tracking
