#pragma once
// Top-down scenario maps: the neighborhood (streets, driveways, houses, garages, fences, trees,
// parked cars) under the mission (areas of interest with their prior heat maps, keep-out zones,
// routes with their search bands) and the simulation (targets, confusers, traffic and
// pedestrians with their trajectories, the UAV start), with a title line, a legend panel, a
// north arrow and a scale bar. Drawn with OpenCV; no ROS.

#include <string>

#include <nlohmann/json_fwd.hpp>
#include <opencv2/core.hpp>

#include "hameritt/geometry/polygon.h"
#include "hameritt/scenario/world.h"

namespace hameritt::map {

// How a map is drawn.
struct MapStyle {
  double px_per_m = 1.2;           // map scale; a 1 km world is about 1300 px across
  double margin_m = 40.0;          // ground shown around the world bounds
  bool crop_to_interest = true;    // show only the AOIs, routes, KOZs, targets and UAV start
  double interest_margin_m = 70.0;   // ground shown around that region when cropping
  double min_interest_size_m = 300.0;  // smallest cropped width and height
  bool show_trajectories = true;   // mover paths (targets' paths are always drawn)
  bool show_prior_text = true;     // probability printed in each prior cell that fits it
  int panel_width_px = 360;        // legend and mission panel on the right

  // Throws scenario::ConfigError naming the field when a value is out of range.
  void validate() const;
};

// BGR fill colour of the target markers (drawn opaque, centred on each target's t = 0 pose).
const cv::Scalar kTargetColor(40, 20, 215);
// BGR fill colour of the confuser markers.
const cv::Scalar kConfuserColor(0, 140, 255);
// BGR colour of the other aircraft of an avoid scenario (paths and t = 0 markers).
const cv::Scalar kAircraftColor(200, 160, 0);
// BGR colour of an avoid goal's ring (its radius to scale) and centre dot.
const cv::Scalar kGoalColor(40, 140, 20);
// BGR tint of the keep-out zones (blended over the map, then hatched in a darker red).
const cv::Scalar kKozColor(45, 35, 225);

// Where the map lies in the image and how ENU metres map to pixels.
struct MapFrame {
  geometry::Aabb2 region;  // ENU rectangle shown, metres
  double px_per_m = 1.0;
  cv::Rect map_rect;       // the map part of the image (below the title, left of the panel)
  cv::Size image_size;
  // Continuous image coordinates of an ENU point (x to the right = east, y down = south).
  cv::Point2d toPixel(const geometry::Vec2& p) const;
  // The pixel containing an ENU point.
  cv::Point pixelAt(const geometry::Vec2& p) const;
};

// Lays out the map of a scenario (title, map area, panel) without drawing it. Throws
// scenario::ConfigError for a malformed mission or sim_config document or a bad style.
MapFrame computeMapFrame(const scenario::World& world, const nlohmann::json& mission,
                         const nlohmann::json& sim_config, const MapStyle& style);

// Draws the map of a scenario (mission.json and sim_config.json documents) over its world.
// Deterministic. Throws scenario::ConfigError naming the document and JSON path of a missing
// or malformed field, or for a bad style.
cv::Mat drawScenarioMap(const scenario::World& world, const nlohmann::json& mission,
                        const nlohmann::json& sim_config, const MapStyle& style);

// Loads DIR/mission.json and DIR/sim_config.json, regenerates the world from
// sim_config.world.params, checks it against sim_config.world.fingerprint, draws the map and
// writes it to `out_png` atomically (temporary file in the same directory, then rename).
// Throws scenario::ConfigError for missing or malformed input (file and JSON path in the
// message) and scenario::OutputError when the PNG cannot be written.
void writeScenarioMap(const std::string& scenario_dir, const std::string& out_png,
                      const MapStyle& style);

}  // namespace hameritt::map
