#include "environment_model.h"

#include <algorithm>
#include <cmath>

namespace hameritt::render {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kLatitudeDeg = 35.4;
constexpr double kDeclinationDeg = 10.4;

double rad(double d) { return d * kPi / 180.0; }
double deg(double r) { return r * 180.0 / kPi; }

float smoothstep(float a, float b, float x) {
  const float t = std::clamp((x - a) / (b - a), 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

Eigen::Vector3f mix(const Eigen::Vector3f& a, const Eigen::Vector3f& b, float t) {
  return a + t * (b - a);
}

float luminance(const Eigen::Vector3f& c) {
  return 0.2126f * c.x() + 0.7152f * c.y() + 0.0722f * c.z();
}

}  // namespace

Eigen::Vector3d SunPosition::direction() const {
  const double el = rad(elevation_deg), az = rad(azimuth_deg);
  return {std::sin(az) * std::cos(el), std::cos(az) * std::cos(el), std::sin(el)};
}

SunPosition sunPosition(double hours) {
  const double phi = rad(kLatitudeDeg), delta = rad(kDeclinationDeg);
  const double h = rad(15.0 * (hours - 12.0));  // hour angle, negative in the morning
  const double sin_el =
      std::sin(phi) * std::sin(delta) + std::cos(phi) * std::cos(delta) * std::cos(h);
  const double el = std::asin(std::clamp(sin_el, -1.0, 1.0));
  const double y = -std::cos(delta) * std::sin(h);
  const double x = (std::sin(delta) - sin_el * std::sin(phi)) / std::cos(phi);
  SunPosition s;
  s.elevation_deg = deg(el);
  s.azimuth_deg = std::fmod(deg(std::atan2(y, x)) + 360.0, 360.0);
  return s;
}

Lighting lightingFor(const scenario::Environment& env, bool weather) {
  const SunPosition sun = sunPosition(env.time_of_day);
  const float el = static_cast<float>(sun.elevation_deg);
  Lighting l;
  // Daylight fades out over civil twilight; the moon lights the night from a fixed direction.
  const float day = smoothstep(0.0f, 20.0f, el);       // 0 at the horizon, 1 in full day
  const float twilight = smoothstep(-8.0f, 2.0f, el);  // 0 at night
  const float sun_up = smoothstep(-1.0f, 3.0f, el);
  const Eigen::Vector3f low_sun(1.45f, 0.72f, 0.36f), high_sun(1.9f, 1.84f, 1.72f);
  l.sun_color = sun_up * mix(low_sun, high_sun, smoothstep(2.0f, 30.0f, el));
  l.sun_dir = sun.direction().cast<float>();
  if (sun_up <= 0.0f) {
    l.sun_dir = Eigen::Vector3f(0.3f, -0.4f, 0.85f).normalized();  // moon
    l.sun_color = Eigen::Vector3f(0.035f, 0.045f, 0.08f);
  }
  const Eigen::Vector3f night_amb(0.018f, 0.024f, 0.05f), dusk_amb(0.16f, 0.13f, 0.15f),
      day_amb(0.30f, 0.35f, 0.44f);
  l.sky_ambient = mix(night_amb, mix(dusk_amb, day_amb, day), twilight);
  l.ground_ambient = twilight * mix(Eigen::Vector3f(0.05f, 0.04f, 0.03f),
                                    Eigen::Vector3f(0.10f, 0.10f, 0.07f), day);
  const Eigen::Vector3f night_z(0.002f, 0.003f, 0.008f), night_h(0.008f, 0.010f, 0.018f);
  const Eigen::Vector3f dusk_z(0.09f, 0.11f, 0.26f), dusk_h(0.85f, 0.42f, 0.18f);
  const Eigen::Vector3f day_z(0.16f, 0.30f, 0.66f), day_h(0.56f, 0.68f, 0.86f);
  l.sky_zenith = mix(night_z, mix(dusk_z, day_z, day), twilight);
  l.sky_horizon = mix(night_h, mix(dusk_h, day_h, day), twilight);
  l.sun_glow =
      sun_up * mix(Eigen::Vector3f(0.9f, 0.45f, 0.15f), Eigen::Vector3f(0.5f, 0.45f, 0.35f), day);
  l.air_color = l.sky_horizon;
  l.air_k = 3.0f / 8000.0f;
  if (!weather) return l;

  // Clouds come with rain and snowfall: less direct sun, a greyer sky.
  const float rain = static_cast<float>(std::clamp(env.rain, 0.0, 1.0));
  const float snow = static_cast<float>(std::clamp(env.snow, 0.0, 1.0));
  const float fog = static_cast<float>(std::clamp(env.fog, 0.0, 1.0));
  const float dust = static_cast<float>(std::clamp(env.dust, 0.0, 1.0));
  const float overcast = std::max(rain, 0.8f * snow);
  if (overcast > 0.0f) {
    l.sun_color *= 1.0f - 0.75f * overcast;
    l.sun_glow *= 1.0f - overcast;
    const float grey_z = luminance(l.sky_zenith), grey_h = luminance(l.sky_horizon);
    l.sky_zenith = mix(l.sky_zenith, Eigen::Vector3f::Constant(0.8f * grey_h + 0.2f * grey_z),
                       0.8f * overcast);
    l.sky_horizon = mix(l.sky_horizon, Eigen::Vector3f::Constant(grey_h), 0.8f * overcast);
    l.air_color = l.sky_horizon;
    l.sky_ambient =
        mix(l.sky_ambient, Eigen::Vector3f::Constant(luminance(l.sky_ambient)), 0.6f * overcast);
  }
  // Extinction coefficients for a 5 % contrast visibility V: k = 3 / V. Fog 1 -> 80 m,
  // dust 1 -> 150 m, rain 1 -> 1.2 km.
  const float k_fog = fog * 3.0f / 80.0f, k_dust = dust * 3.0f / 150.0f,
              k_rain = rain * 3.0f / 1200.0f;
  l.haze_k = k_fog + k_dust + k_rain;
  if (l.haze_k > 0.0f) {
    // The haze is as bright as the diffuse light that reaches it.
    const float brightness =
        std::clamp(luminance(l.sky_ambient + 0.35f * l.sun_color) /
                       luminance(Eigen::Vector3f(0.30f + 0.35f * 1.9f, 0.35f + 0.35f * 1.84f,
                                                 0.44f + 0.35f * 1.72f)),
                   0.0f, 1.0f);
    const Eigen::Vector3f fog_c(0.78f, 0.80f, 0.82f), dust_c(0.66f, 0.52f, 0.34f),
        rain_c(0.52f, 0.54f, 0.57f);
    l.haze_color = brightness * (k_fog * fog_c + k_dust * dust_c + k_rain * rain_c) / l.haze_k;
  }
  l.snow_cover = snow;
  l.wetness = rain;
  return l;
}

}  // namespace hameritt::render
