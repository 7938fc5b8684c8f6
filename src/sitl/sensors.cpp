#include "hameritt/sitl/sensors.h"

#include <cmath>
#include <string>

#include "hameritt/scenario/error.h"

namespace hameritt::sitl {

namespace {
constexpr double kP0 = 101325.0;        // Pa, sea level
constexpr double kT0 = 288.15;          // K
constexpr double kLapse = 0.0065;       // K/m
constexpr double kExponent = 5.255877;  // g0 M / (R L)
}  // namespace

double isaTemperature(double h) { return kT0 - kLapse * h; }
double isaPressure(double h) { return kP0 * std::pow(1.0 - kLapse * h / kT0, kExponent); }
double isaAltitude(double p) { return kT0 / kLapse * (1.0 - std::pow(p / kP0, 1.0 / kExponent)); }

Vec3 fluToFrd(const Vec3& v) { return {v.x(), -v.y(), -v.z()}; }
Vec3 enuToNed(const Vec3& v) { return {v.y(), v.x(), -v.z()}; }

sim::Quat frdToNed(const sim::Quat& flu_to_enu) {
  static const sim::Quat kNedFromEnu(0.0, std::sqrt(0.5), std::sqrt(0.5), 0.0);
  static const sim::Quat kFluFromFrd(0.0, 1.0, 0.0, 0.0);
  return (kNedFromEnu * flu_to_enu * kFluFromFrd).normalized();
}

void SensorConfig::validate() const {
  auto check = [](double v, const char* field) {
    if (!(std::isfinite(v) && v >= 0)) {
      throw scenario::ConfigError(std::string("sitl.noise.") + field +
                                  ": expected a finite value >= 0, got " + std::to_string(v));
    }
  };
  check(noise.accel_noise, "accel_noise");
  check(noise.gyro_noise, "gyro_noise");
  check(noise.mag_noise, "mag_noise");
  check(noise.baro_noise, "baro_noise");
  check(noise.gps_horizontal, "gps_horizontal");
  check(noise.gps_vertical, "gps_vertical");
  check(noise.gps_velocity, "gps_velocity");
  if (!noise.accel_bias.allFinite() || !noise.gyro_bias.allFinite() ||
      !std::isfinite(noise.baro_bias)) {
    throw scenario::ConfigError("sitl.noise: expected finite biases");
  }
  try {
    cop::EnuFrame check_origin(origin);
  } catch (const std::exception& e) {
    throw scenario::ConfigError(std::string("sitl.origin: ") + e.what());
  }
}

SensorModel::SensorModel(const SensorConfig& config)
    : config_(config), frame_(config.origin), rng_(config.seed) {
  config.validate();
}

Vec3 SensorModel::noise3(double sigma) {
  if (sigma <= 0) return Vec3::Zero();
  // Each draw in a fixed order: x, y, z.
  const double x = rng_.normal(0, sigma);
  const double y = rng_.normal(0, sigma);
  const double z = rng_.normal(0, sigma);
  return {x, y, z};
}

ImuSample SensorModel::imu(const sim::UavState& s) {
  ImuSample out;
  out.accel =
      fluToFrd(s.specific_force) + config_.noise.accel_bias + noise3(config_.noise.accel_noise);
  out.gyro =
      fluToFrd(s.angular_velocity) + config_.noise.gyro_bias + noise3(config_.noise.gyro_noise);
  return out;
}

Vec3 SensorModel::mag(const sim::UavState& s) {
  const sim::Quat q = frdToNed(s.orientation);
  return q.conjugate() * config_.mag_field_ned + noise3(config_.noise.mag_noise);
}

BaroSample SensorModel::baro(const sim::UavState& s) {
  const double h = config_.origin.altitude + s.position.z();
  double p = isaPressure(h) + config_.noise.baro_bias;
  if (config_.noise.baro_noise > 0) p += rng_.normal(0, config_.noise.baro_noise);
  BaroSample b;
  b.pressure_hpa = p / 100.0;
  b.altitude_m = isaAltitude(p);
  b.temperature_c = isaTemperature(h) - 273.15;
  return b;
}

GpsSample SensorModel::gps(const sim::UavState& s) {
  const auto& n = config_.noise;
  Vec3 e(0, 0, 0);
  if (n.gps_horizontal > 0) {
    e.x() = rng_.normal(0, n.gps_horizontal);
    e.y() = rng_.normal(0, n.gps_horizontal);
  }
  if (n.gps_vertical > 0) e.z() = rng_.normal(0, n.gps_vertical);
  GpsSample g;
  g.position = frame_.toGeodetic(s.position + e);
  g.velocity_ned = enuToNed(s.velocity) + noise3(n.gps_velocity);
  g.eph = n.gps_horizontal;
  g.epv = n.gps_vertical;
  return g;
}

cop::Geodetic SensorModel::geodetic(const Vec3& enu) const { return frame_.toGeodetic(enu); }

}  // namespace hameritt::sitl
