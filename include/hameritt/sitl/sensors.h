#pragma once
// Sensor models an autopilot flies on: IMU (accelerometer, gyroscope), magnetometer, barometer
// and GPS, with seeded white noise and constant biases. Output frames are the autopilot's:
// body FRD and NED (the simulator's state is ENU / body FLU). ROS-free and deterministic: the
// same seed and state sequence give the same samples.

#include <Eigen/Core>
#include <cstdint>

#include "hameritt/cop/geodetic.h"
#include "hameritt/scenario/rng.h"
#include "hameritt/sim/simulator.h"

namespace hameritt::sitl {

using sim::Vec3;

// Noise (standard deviation of white noise per sample) and constant biases.
struct SensorNoise {
  double accel_noise = 0.05;    // m/s^2
  Vec3 accel_bias{0, 0, 0};     // m/s^2, FRD
  double gyro_noise = 0.004;    // rad/s
  Vec3 gyro_bias{0, 0, 0};      // rad/s, FRD
  double mag_noise = 0.002;     // gauss
  double baro_noise = 0.5;      // Pa (about 4 cm)
  double baro_bias = 0.0;       // Pa
  double gps_horizontal = 0.5;  // m (also the reported eph)
  double gps_vertical = 0.8;    // m (also the reported epv)
  double gps_velocity = 0.05;   // m/s
};

struct SensorConfig {
  cop::Geodetic origin;                   // the map frame's origin (altitude taken as MSL)
  Vec3 mag_field_ned{0.21, -0.01, 0.42};  // gauss (a mid-latitude field)
  SensorNoise noise;
  std::uint64_t seed = 1;
  // Throws scenario::ConfigError naming the field ("sitl.noise.gyro_noise") and the value.
  void validate() const;
};

struct ImuSample {
  Vec3 accel;  // specific force, m/s^2, FRD (at rest level: z about -9.81)
  Vec3 gyro;   // rad/s, FRD
};

struct BaroSample {
  double pressure_hpa = 0;
  double altitude_m = 0;  // pressure altitude of the noisy pressure
  double temperature_c = 0;
};

struct GpsSample {
  cop::Geodetic position;   // WGS84, altitude as MSL
  Vec3 velocity_ned;        // m/s
  double eph = 0, epv = 0;  // m
};

// The International Standard Atmosphere's troposphere (ISO 2533:1975): pressure (Pa) and
// temperature (K) at geopotential altitude h (m).
double isaPressure(double h);
double isaTemperature(double h);
// Its inverse: the altitude (m) of a pressure (Pa).
double isaAltitude(double pressure);

// Frame helpers: body FLU -> FRD and ENU -> NED vectors, and the FRD-to-NED attitude.
Vec3 fluToFrd(const Vec3& v);
Vec3 enuToNed(const Vec3& v);
sim::Quat frdToNed(const sim::Quat& flu_to_enu);

class SensorModel {
 public:
  explicit SensorModel(const SensorConfig& config);
  ImuSample imu(const sim::UavState& s);
  Vec3 mag(const sim::UavState& s);  // gauss, FRD
  BaroSample baro(const sim::UavState& s);
  GpsSample gps(const sim::UavState& s);
  // The noise-free geodetic position of a state (ground truth for HIL_STATE_QUATERNION).
  cop::Geodetic geodetic(const Vec3& enu) const;
  const SensorConfig& config() const { return config_; }

 private:
  Vec3 noise3(double sigma);
  SensorConfig config_;
  cop::EnuFrame frame_;
  scenario::Rng rng_;
};

}  // namespace hameritt::sitl
