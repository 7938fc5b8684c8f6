#include "hameritt/sim/wind.h"

#include <algorithm>
#include <cmath>

namespace hameritt::sim {

namespace {
constexpr double kFtPerM = 3.280839895;
constexpr double kW20PerIntensity = 15.0;  // m/s of W20 at gust_intensity 1
}  // namespace

DrydenTurbulence::DrydenTurbulence(double gust_intensity, std::uint64_t seed)
    : intensity_(std::clamp(gust_intensity, 0.0, 1.0)), seed_(seed), rng_(seed) {}

void DrydenTurbulence::reset() {
  rng_ = scenario::Rng(seed_);
  u_ = v1_ = v2_ = w1_ = w2_ = 0.0;
  gust_.setZero();
}

Eigen::Vector3d DrydenTurbulence::step(double dt, double altitude_m, double airspeed) {
  if (intensity_ <= 0.0) return gust_;
  // MIL-F-8785C low-altitude scales and intensities (feet inside, metres outside); the model
  // is specified for h >= 10 ft.
  const double h = std::clamp(altitude_m * kFtPerM, 10.0, 1000.0);
  const double k = 0.177 + 0.000823 * h;
  const double sigma_w = 0.1 * intensity_ * kW20PerIntensity;  // m/s
  const double sigma_uv = sigma_w / std::pow(k, 0.4);
  const double l_w = h / kFtPerM;                      // m
  const double l_uv = h / std::pow(k, 1.2) / kFtPerM;  // m
  const double v = std::max(airspeed, 1.0);

  // u: exact discretization of the first-order Gauss-Markov process with variance sigma_u^2.
  const double a = std::exp(-v * dt / l_uv);
  u_ = a * u_ + sigma_uv * std::sqrt(1.0 - a * a) * rng_.normal(0.0, 1.0);

  // v, w: second-order Dryden filters in state space (T = L/V), Euler-Maruyama at the physics
  // step (dt << T). Continuous white noise of unit spectral density -> discrete n_k / sqrt(dt).
  auto second = [&](double* x1, double* x2, double l, double sigma) {
    const double tc = l / v;
    // MIL-F-8785C writes the spectra with a 1/pi factor (one-sided in spatial frequency); for
    // white noise of unit two-sided PSD the gain that gives variance sigma^2 is sigma sqrt(L/V).
    const double gain = sigma * std::sqrt(tc);
    const double n = rng_.normal(0.0, 1.0) / std::sqrt(dt);
    // H(s) = gain (1 + sqrt3 tc s) / (1 + tc s)^2 realized as x1' = (n - x1)/tc,
    // x2' = (x1 - x2)/tc, y = gain * (x2 + sqrt3 tc x2') = gain * (x2 + sqrt3 (x1 - x2)).
    const double x1n = *x1 + dt * (n - *x1) / tc;
    const double x2n = *x2 + dt * (*x1 - *x2) / tc;
    *x1 = x1n;
    *x2 = x2n;
    return gain * (*x2 + std::sqrt(3.0) * (*x1 - *x2));
  };
  const double gv = second(&v1_, &v2_, l_uv, sigma_uv);
  const double gw = second(&w1_, &w2_, l_w, sigma_w);
  gust_ = Eigen::Vector3d(u_, gv, gw);
  return gust_;
}

WindModel::WindModel(const Eigen::Vector3d& mean_enu, double gust_intensity, std::uint64_t seed,
                     bool enabled)
    : mean_(mean_enu), enabled_(enabled), turbulence_(gust_intensity, seed) {
  const Eigen::Vector2d h = mean_.head<2>();
  const double heading = h.norm() > 1e-9 ? std::atan2(h.y(), h.x()) : 0.0;
  to_enu_ << std::cos(heading), -std::sin(heading), 0, std::sin(heading), std::cos(heading), 0, 0,
      0, 1;
  reset();
}

void WindModel::reset() {
  turbulence_.reset();
  wind_ = enabled_ ? mean_ : Eigen::Vector3d::Zero();
}

void WindModel::step(double dt, double altitude_m, const Eigen::Vector3d& velocity) {
  if (!enabled_) return;
  if (turbulence_.intensity() <= 0.0) {
    wind_ = mean_;
    return;
  }
  const double airspeed = (velocity - mean_).norm();
  wind_ = mean_ + to_enu_ * turbulence_.step(dt, altitude_m, airspeed);
}

}  // namespace hameritt::sim
