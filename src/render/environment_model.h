#pragma once
// Light, sky and atmosphere of a scenario::Environment: a simple solar model for local solar
// time, sky colours by sun elevation, and the fog/dust/rain extinction the shaders apply.

#include <Eigen/Core>

#include "hameritt/scenario/scenario.h"

namespace hameritt::render {

// Sun position for a mid-latitude day (latitude 35.4 deg N, declination 10.4 deg: sunrise
// 5:30, sunset 18:30, noon elevation 65 deg) at local solar time `hours` (NOAA's textbook
// formulas without the equation of time).
struct SunPosition {
  double elevation_deg = 0;
  double azimuth_deg = 0;             // clockwise from north (ENU +y), east = 90
  Eigen::Vector3d direction() const;  // unit vector towards the sun in ENU
};
SunPosition sunPosition(double hours);

// Everything the shaders need from the environment (linear RGB, metres).
struct Lighting {
  Eigen::Vector3f sun_dir{0, 0, 1};
  Eigen::Vector3f sun_color{0, 0, 0};       // direct light (Lambert)
  Eigen::Vector3f sky_ambient{0, 0, 0};     // hemisphere light from above
  Eigen::Vector3f ground_ambient{0, 0, 0};  // hemisphere light from below
  Eigen::Vector3f sky_zenith{0, 0, 0};
  Eigen::Vector3f sky_horizon{0, 0, 0};
  Eigen::Vector3f sun_glow{0, 0, 0};  // sky brightening around the sun
  // Aerial perspective of clear air (visibility about 8 km): surfaces fade towards the colour
  // of the horizon sky; weather or not, it is part of the scene.
  Eigen::Vector3f air_color{0, 0, 0};
  float air_k = 0;
  // Weather: exponential extinction, colour = mix(haze_color, colour, exp(-haze_k * distance)).
  Eigen::Vector3f haze_color{0, 0, 0};
  float haze_k = 0;
  float snow_cover = 0;  // [0, 1]
  float wetness = 0;     // [0, 1]
};

// weather = false gives the clear-air lighting of the same time of day (no clouds, no haze,
// no snow cover, dry surfaces).
Lighting lightingFor(const scenario::Environment& env, bool weather);

}  // namespace hameritt::render
