#pragma once
// Internal OMPL glue shared by the planners: a seeded state sampler drawing from scenario::Rng,
// a motion validator from a segment predicate, and the console switch.

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>

#include <ompl/base/MotionValidator.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/StateSampler.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>

#include "hameritt/scenario/rng.h"

namespace hameritt::planning::detail {

// Silences OMPL the first time it is called (thread-safe).
void silenceOmplOnce();

// Uniform / near / Gaussian sampling in a RealVectorStateSpace from a seeded scenario::Rng, so
// that no sample depends on OMPL's process-wide seed.
class RngRealVectorSampler : public ompl::base::StateSampler {
 public:
  RngRealVectorSampler(const ompl::base::StateSpace* space, std::uint64_t seed)
      : ompl::base::StateSampler(space), rng_(seed) {}
  void sampleUniform(ompl::base::State* state) override {
    const auto& b = space_->as<ompl::base::RealVectorStateSpace>()->getBounds();
    auto* v = state->as<ompl::base::RealVectorStateSpace::StateType>();
    for (std::size_t i = 0; i < b.low.size(); ++i) v->values[i] = rng_.uniform(b.low[i], b.high[i]);
  }
  void sampleUniformNear(ompl::base::State* state, const ompl::base::State* near,
                         double distance) override {
    const auto& b = space_->as<ompl::base::RealVectorStateSpace>()->getBounds();
    auto* v = state->as<ompl::base::RealVectorStateSpace::StateType>();
    const auto* n = near->as<ompl::base::RealVectorStateSpace::StateType>();
    for (std::size_t i = 0; i < b.low.size(); ++i) {
      v->values[i] = std::clamp(n->values[i] + rng_.uniform(-distance, distance), b.low[i], b.high[i]);
    }
  }
  void sampleGaussian(ompl::base::State* state, const ompl::base::State* mean,
                      double stddev) override {
    const auto& b = space_->as<ompl::base::RealVectorStateSpace>()->getBounds();
    auto* v = state->as<ompl::base::RealVectorStateSpace::StateType>();
    const auto* m = mean->as<ompl::base::RealVectorStateSpace::StateType>();
    for (std::size_t i = 0; i < b.low.size(); ++i) {
      v->values[i] = std::clamp(rng_.normal(m->values[i], stddev), b.low[i], b.high[i]);
    }
  }

 private:
  scenario::Rng rng_;
};

// Allocator handing out samplers seeded deterministically (seed, 0), (seed, 1), ...
// Samplers seeded deriveSeed(seed, k) for k = first, first + 1, ... in the order allocated.
inline ompl::base::StateSamplerAllocator rngSamplerAllocator(std::uint64_t seed,
                                                             std::uint64_t first = 0) {
  auto counter = std::make_shared<std::uint64_t>(first);
  return [seed, counter](const ompl::base::StateSpace* space) {
    return std::make_shared<RngRealVectorSampler>(space, scenario::deriveSeed(seed, (*counter)++));
  };
}

// A motion validator from an exact segment predicate over two OMPL states.
class PredicateMotionValidator : public ompl::base::MotionValidator {
 public:
  using Predicate = std::function<bool(const ompl::base::State*, const ompl::base::State*)>;
  PredicateMotionValidator(ompl::base::SpaceInformation* si, Predicate pred)
      : ompl::base::MotionValidator(si), pred_(std::move(pred)) {}
  bool checkMotion(const ompl::base::State* s1, const ompl::base::State* s2) const override {
    const bool ok = pred_(s1, s2);
    if (ok) ++valid_;
    else ++invalid_;
    return ok;
  }
  // The last valid fraction is found by scanning 32 equal steps with the exact predicate.
  bool checkMotion(const ompl::base::State* s1, const ompl::base::State* s2,
                   std::pair<ompl::base::State*, double>& last_valid) const override {
    if (checkMotion(s1, s2)) return true;
    constexpr int kSteps = 32;
    ompl::base::State* probe = si_->allocState();
    double good = 0.0;
    for (int k = 1; k <= kSteps; ++k) {
      si_->getStateSpace()->interpolate(s1, s2, static_cast<double>(k) / kSteps, probe);
      if (!pred_(s1, probe)) break;
      good = static_cast<double>(k) / kSteps;
    }
    si_->freeState(probe);
    last_valid.second = good;
    if (last_valid.first) si_->getStateSpace()->interpolate(s1, s2, good, last_valid.first);
    return false;
  }

 private:
  Predicate pred_;
};

}  // namespace hameritt::planning::detail
