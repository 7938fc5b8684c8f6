#pragma once
// Density and occlusion figures of a generated world (suburb or city), measured from its
// entities: street network, blocks, building plan fraction and heights, line-of-sight
// probability from the air and the street-level sky-view factor, both by ray casting against
// the world's occluder boxes.

#include <cstdint>
#include <string>
#include <vector>

#include "hameritt/scenario/world.h"

namespace hameritt::scenario {

// Sampling of the ray-cast measures. Deterministic for a given seed.
struct MetricsSettings {
  std::uint64_t seed = 7;
  std::vector<double> los_heights{30.0, 50.0, 100.0};  // observer heights above ground (m)
  int los_samples = 3000;                              // observer/sidewalk pairs per height
  double los_radius = 150.0;                           // horizontal distance limit between them (m)
  double sidewalk_point_z = 0.3;                       // height of the seen sidewalk point (m)
  int svf_points = 300;                                // street-level points (on the sidewalks)
  int svf_rays = 144;             // rays per point (cosine-weighted hemisphere)
  double svf_point_z = 1.5;       // height of a street-level point (m)
  double svf_ray_length = 800.0;  // rays end this far away (m)
  double plan_cell = 0.5;         // raster cell of the footprint union (m)
};

// One height's line-of-sight probability.
struct LosMeasure {
  double height = 0.0;
  double probability = 0.0;  // share of pairs with a clear line
  int samples = 0;
};

struct WorldMetrics {
  std::string type;            // "suburb" or "city"
  double tile_area_km2 = 0.0;  // extent_x * extent_y
  int blocks = 0;
  double blocks_per_km2 = 0.0;
  double block_length_min = 0.0, block_length_max = 0.0;  // mean of a block's east-west sides
  double block_depth_min = 0.0, block_depth_max = 0.0;    // mean of its north-south sides
  int arterial_edges = 0, local_edges = 0;
  double arterial_width = 0.0;  // widest street (m)
  double local_width = 0.0;     // narrowest street (m)
  int alleys = 0;
  double alley_width_min = 0.0, alley_width_max = 0.0;
  double sidewalk_width = 0.0;
  // Buildings: building and parking_garage (city), house (suburb).
  int buildings = 0;
  double buildings_per_km2 = 0.0;
  // Union of building, parking_garage, house and garage footprints over the tile area.
  double plan_fraction = 0.0;
  // Storeys of the building class (city) or house class (suburb).
  double median_storeys = 0.0;
  // Share of buildings 60 m or taller, and their height range.
  double tower_share = 0.0;
  double tower_height_min = 0.0, tower_height_max = 0.0;
  int parking_garages = 0, parking_lots = 0, kerb_slots = 0, parked_cars = 0;
  int lamp_posts = 0, street_trees = 0, benches = 0, bus_stops = 0, traffic_lights = 0;
  // Lot frontages (the building's width across the street) of the building class.
  double frontage_min = 0.0, frontage_max = 0.0;
  std::vector<LosMeasure> los;
  double svf_median = 0.0;
  int svf_points = 0;
};

// Measures `world` (see MetricsSettings); the world's own occluder index casts the rays.
WorldMetrics measureWorld(const World& world, const MetricsSettings& settings = {});

// The line-of-sight probability at `height`, or -1 when it was not measured.
double losAt(const WorldMetrics& m, double height);

// The metrics as a JSON object (stable key order, 6 significant digits).
std::string metricsJson(const WorldMetrics& m);

// The sky-view factor at p: the share of `rays` cosine-weighted directions of the upper
// hemisphere that leave p for `length` metres without meeting an occluder.
double skyViewFactor(const World& world, const geometry::Vec3& p, int rays, double length);

}  // namespace hameritt::scenario
