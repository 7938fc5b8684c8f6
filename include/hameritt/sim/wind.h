#pragma once
// Wind: a mean ENU wind plus Dryden turbulence (MIL-F-8785C low-altitude model), discretized at
// the physics step with a seeded deterministic RNG, so that the same seed gives the same gusts.

#include <Eigen/Core>
#include <cstdint>

#include "hameritt/scenario/rng.h"

namespace hameritt::sim {

// Dryden turbulence, MIL-F-8785C low altitude (h < 1000 ft): with h in feet and W20 the wind
// speed at 20 ft, sigma_w = 0.1 W20, sigma_u = sigma_v = sigma_w / (0.177 + 0.000823 h)^0.4,
// L_w = h, L_u = L_v = h / (0.177 + 0.000823 h)^1.2. The longitudinal (u) shaping filter is
// first order, H_u(s) = sigma_u sqrt(2 L_u / (pi V)) / (1 + L_u s / V), discretized exactly (a
// Gauss-Markov process); the lateral and vertical filters are second order,
// H(s) ~ sigma sqrt(L / V) (1 + sqrt(3) L s / V) / (1 + L s / V)^2 (scaled so that the output
// variance is sigma^2), integrated in state space at the physics step. gust_intensity in [0, 1]
// maps linearly to W20 in [0, 15] m/s (15 m/s ~ 30 kt, the spec's "moderate" turbulence).
// Components are in the mean-wind frame (u along the horizontal mean wind, v to its left, w up).
class DrydenTurbulence {
 public:
  DrydenTurbulence(double gust_intensity, std::uint64_t seed);

  // Back to the initial state and the seed's first draw.
  void reset();
  // Advances by dt at altitude `altitude_m` above ground with airspeed `airspeed` (m/s, at
  // least 1 m/s is used: the turbulence field also convects with the mean wind). Returns the
  // gust (u, v, w) in m/s.
  Eigen::Vector3d step(double dt, double altitude_m, double airspeed);
  const Eigen::Vector3d& gust() const { return gust_; }
  double intensity() const { return intensity_; }

 private:
  double intensity_;
  std::uint64_t seed_;
  scenario::Rng rng_;
  double u_ = 0.0;
  double v1_ = 0.0, v2_ = 0.0;  // lateral filter states
  double w1_ = 0.0, w2_ = 0.0;  // vertical filter states
  Eigen::Vector3d gust_{0, 0, 0};
};

// Mean wind + turbulence in ENU, acting on the UAV through its drag model.
class WindModel {
 public:
  WindModel(const Eigen::Vector3d& mean_enu, double gust_intensity, std::uint64_t seed,
            bool enabled);

  void reset();
  // Advances the turbulence by dt for a UAV at `altitude_m` flying at `velocity` (ENU).
  void step(double dt, double altitude_m, const Eigen::Vector3d& velocity);
  // The current air velocity (ENU, m/s).
  const Eigen::Vector3d& wind() const { return wind_; }

 private:
  Eigen::Vector3d mean_;
  bool enabled_;
  DrydenTurbulence turbulence_;
  Eigen::Matrix3d to_enu_;  // mean-wind frame (u, v, w) to ENU
  Eigen::Vector3d wind_;
};

}  // namespace hameritt::sim
