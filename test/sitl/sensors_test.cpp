#include "hameritt/sitl/sensors.h"

#include <gtest/gtest.h>

#include <cmath>

#include "hameritt/scenario/error.h"

namespace hameritt::sitl {
namespace {

constexpr double kG = 9.80665;

sim::UavState atRest(double yaw_enu = 0.0) {
  sim::UavState s;
  s.orientation = sim::Quat(Eigen::AngleAxisd(yaw_enu, Vec3::UnitZ()));
  s.specific_force = Vec3(0, 0, kG);  // FLU: the ground pushes up
  return s;
}

SensorConfig quiet() {
  SensorConfig c;
  c.noise = SensorNoise();
  c.noise.accel_noise = c.noise.gyro_noise = c.noise.mag_noise = c.noise.baro_noise = 0;
  c.noise.gps_horizontal = c.noise.gps_vertical = c.noise.gps_velocity = 0;
  return c;
}

TEST(Atmosphere, StandardAtmosphereKnownValues) {
  // ISO 2533 / U.S. Standard Atmosphere 1976 table values.
  EXPECT_NEAR(isaPressure(0), 101325.0, 1e-6);
  EXPECT_NEAR(isaPressure(1000), 89874.6, 1.0);
  EXPECT_NEAR(isaPressure(5000), 54019.9, 5.0);
  EXPECT_NEAR(isaTemperature(1000), 281.65, 1e-9);
  EXPECT_NEAR(isaAltitude(isaPressure(40.0)), 40.0, 1e-6);
  EXPECT_GT(std::abs(isaPressure(1000) - 90874.6), 100);  // control: a wrong table value fails
}

TEST(Sensors, AtRestInFrd) {
  SensorModel m(quiet());
  const ImuSample imu = m.imu(atRest());
  EXPECT_NEAR(imu.accel.z(), -kG, 1e-12);  // FRD: gravity's reaction points up = -z
  EXPECT_NEAR(imu.accel.x(), 0, 1e-12);
  EXPECT_NEAR(imu.gyro.norm(), 0, 1e-12);
  // A body rate about FLU +z (yawing left) is FRD -z.
  sim::UavState s = atRest();
  s.angular_velocity = Vec3(0.1, 0.2, 0.3);
  const ImuSample r = m.imu(s);
  EXPECT_NEAR(r.gyro.x(), 0.1, 1e-12);
  EXPECT_NEAR(r.gyro.y(), -0.2, 1e-12);
  EXPECT_NEAR(r.gyro.z(), -0.3, 1e-12);
}

TEST(Sensors, AttitudeAndMagnetometerFrames) {
  SensorModel m(quiet());
  // ENU yaw 0 faces east: FRD forward is NED east.
  const sim::Quat q = frdToNed(atRest(0.0).orientation);
  EXPECT_NEAR((q * Vec3::UnitX() - Vec3(0, 1, 0)).norm(), 0, 1e-12);
  EXPECT_NEAR((q * Vec3::UnitZ() - Vec3(0, 0, 1)).norm(), 0, 1e-12);  // FRD down is NED down
  // Facing north (ENU yaw 90 deg), the magnetometer reads the NED field as is.
  const Vec3 north = m.mag(atRest(M_PI / 2));
  EXPECT_NEAR((north - m.config().mag_field_ned).norm(), 0, 1e-12);
  // Facing east: forward reads the east component, right reads minus north.
  const Vec3 east = m.mag(atRest(0.0));
  const Vec3 f = m.config().mag_field_ned;
  EXPECT_NEAR(east.x(), f.y(), 1e-12);
  EXPECT_NEAR(east.y(), -f.x(), 1e-12);
  EXPECT_NEAR(east.z(), f.z(), 1e-12);
}

TEST(Sensors, BarometerAtTheOriginAltitude) {
  SensorConfig c = quiet();
  c.origin.altitude = 40.0;
  SensorModel m(c);
  sim::UavState s = atRest();
  const BaroSample b0 = m.baro(s);
  EXPECT_NEAR(b0.pressure_hpa * 100, isaPressure(40.0), 1e-6);
  EXPECT_NEAR(b0.pressure_hpa, 1008.46, 0.05);
  EXPECT_NEAR(b0.altitude_m, 40.0, 1e-6);
  EXPECT_NEAR(b0.temperature_c, 15.0 - 0.26, 1e-9);
  s.position.z() = 10.0;
  EXPECT_NEAR(m.baro(s).altitude_m, 50.0, 1e-6);
}

TEST(Sensors, GpsPositionNoiseAndAccuracyFields) {
  SensorConfig c;
  c.noise.gps_horizontal = 0.5;
  c.noise.gps_vertical = 0.8;
  c.seed = 11;
  SensorModel m(c);
  sim::UavState s = atRest();
  s.position = Vec3(100, 200, 10);  // 100 m east, 200 m north
  s.velocity = Vec3(1, 2, -0.5);
  const cop::EnuFrame frame(c.origin);
  double se = 0, sn = 0, su = 0;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const GpsSample g = m.gps(s);
    const Vec3 e = frame.toEnu(g.position) - s.position;
    se += e.x() * e.x();
    sn += e.y() * e.y();
    su += e.z() * e.z();
    EXPECT_EQ(g.eph, 0.5);
    EXPECT_EQ(g.epv, 0.8);
  }
  EXPECT_NEAR(std::sqrt(se / n), 0.5, 0.05);
  EXPECT_NEAR(std::sqrt(sn / n), 0.5, 0.05);
  EXPECT_NEAR(std::sqrt(su / n), 0.8, 0.08);
  SensorModel q(quiet());
  const GpsSample g = q.gps(s);
  EXPECT_NEAR((frame.toEnu(g.position) - s.position).norm(), 0, 1e-6);
  EXPECT_NEAR((g.velocity_ned - Vec3(2, 1, 0.5)).norm(), 0, 1e-12);  // NED
}

TEST(Sensors, SeededBiasedAndValidated) {
  SensorConfig c;
  c.seed = 5;
  c.noise.gyro_bias = Vec3(0.01, 0, 0);
  SensorModel a(c), b(c);
  c.seed = 6;
  SensorModel other(c);
  const sim::UavState s = atRest();
  const ImuSample ia = a.imu(s), ib = b.imu(s), io = other.imu(s);
  EXPECT_EQ(ia.accel, ib.accel);  // the same seed: the same samples
  EXPECT_NE(ia.accel, io.accel);  // control: another seed differs
  double mean = 0;
  for (int i = 0; i < 2000; ++i) mean += a.imu(s).gyro.x();
  EXPECT_NEAR(mean / 2000, 0.01, 0.0005);
  SensorConfig bad;
  bad.noise.gyro_noise = -1;
  EXPECT_THROW(bad.validate(), scenario::ConfigError);
  bad = SensorConfig();
  bad.origin.latitude = 91;
  EXPECT_THROW(bad.validate(), scenario::ConfigError);
  bad = SensorConfig();
  bad.noise.accel_bias.x() = std::nan("");
  EXPECT_THROW(bad.validate(), scenario::ConfigError);
}

}  // namespace
}  // namespace hameritt::sitl
