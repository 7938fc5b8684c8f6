#pragma once
// Scenario generator configuration (config/generator.json): the randomization ranges of the
// generator and the loaders of config/world.json and config/generator.json.

#include <string>

#include "hameritt/scenario/relations.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::scenario {

// A closed interval a parameter is drawn from.
struct Range {
  double min = 0.0;
  double max = 0.0;
};

// Randomization ranges of the generator (config/generator.json). Lengths in metres, times in
// seconds, speeds in m/s, angles in degrees.
struct GeneratorConfig {
  GeoOrigin origin;
  RelationConfig relations;
  Range time_limit_area_search{420, 900};
  Range time_limit_route_search{240, 480};
  Range time_limit_pursuit{240, 480};
  int aoi_count_min = 1;
  int aoi_count_max = 3;
  Range aoi_length{160, 320};
  Range aoi_width{120, 260};
  double aoi_window_probability = 0.3;
  int prior_depth_min = 1;
  int prior_depth_max = 2;
  int koz_count_min = 1;
  int koz_count_max = 3;
  int confuser_count_min = 1;
  int confuser_count_max = 4;
  int traffic_count_min = 12;
  int traffic_count_max = 16;
  int pedestrian_count_min = 8;
  int pedestrian_count_max = 12;
  Range car_speed{8, 13};
  Range pedestrian_speed{1.0, 1.6};
  Range runner_speed{3.0, 4.5};
  Range band_width{30, 60};
  int route_edges_min = 3;
  int route_edges_max = 6;
  Range depart_time{20, 60};
  // A track target's wait: the UAV starts close enough to reach its area of interest and sweep
  // the likeliest cell before the window (until the departure) closes.
  Range track_depart_time{50, 80};
  Range uav_altitude_min{15, 30};
  Range uav_altitude_max{45, 120};
  double uav_max_speed = 12.0;
  Range time_of_day{6, 20};
  double weather_probability = 0.3;  // chance of each of snow/rain, dust, fog being present
  Range foliage{0.2, 1.0};
  Range wind_speed{0, 8};
  Range gust_intensity{0, 1};
  int camera_width = 640;
  int camera_height = 480;
  double camera_rate_hz = 10.0;
  Range front_pitch{5, 30};
  Range front_hfov{70, 100};
  Range down_hfov{60, 90};
  Range noise_std{0, 0.05};
  Range salt_pepper{0, 0.01};
  Range motion_blur_px{0, 3};
  // Follow: the envelope's point follow_distance (d*) behind the target with its horizontal
  // radius (D), follow_height (h*) above it with its tolerance (H; h* is raised or lowered
  // so that h* +- H lies in the UAV's altitude band), and the follow phase's duration.
  Range follow_distance{10, 20};
  Range follow_distance_tolerance{5, 8};
  Range follow_height{20, 35};
  Range follow_height_tolerance{5, 7};
  Range follow_duration{60, 120};
  // Track: 1-2 moving targets (a second one drives the first one's route as a convoy), the
  // track phase's duration and its criteria (TrackPhaseSpec), written into mission.json.
  int track_targets_min = 1;
  int track_targets_max = 2;
  Range track_duration{60, 120};
  double track_min_visible_fraction = 0.5;
  double track_min_box_area = 400.0;  // px^2
  double track_min_tracked_fraction = 0.7;
  double track_max_reacquire_s = 10.0;
  // Plan a perception-only UAV flight over the targets (sim_config uav.perception_path); the
  // most expensive step of generation, so it can be switched off.
  bool perception_paths = true;

  // Throws ConfigError naming the field ("generator.<field>") and the bad value.
  void validate() const;
};

// Reads config/world.json; unknown or missing keys are errors naming the file and the key.
WorldParams loadWorldParams(const std::string& path);
// Reads config/generator.json, strictly likewise.
GeneratorConfig loadGeneratorConfig(const std::string& path);
// The shipped configuration directory: $HAMERITT_CONFIG_DIR, else the package's config/
// (shareDir() in hameritt/scenario/share_dir.h).
std::string defaultConfigDir();

}  // namespace hameritt::scenario
