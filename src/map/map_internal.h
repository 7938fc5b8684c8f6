// Private declarations shared by the map's sources: the parsed documents, colours, layout and
// the MapPainter canvas.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hameritt/map/scenario_map.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/params_table.h"
#include "hameritt/scenario/scenario_io.h"
namespace hameritt::map {

namespace map_internal {

using geometry::Aabb2;
using geometry::Vec2;
using nlohmann::json;
using scenario::ConfigError;

// ------------------------------------------------------------------------------ parsed input

struct Window {
  std::optional<double> net;
  std::optional<double> nlt;
};

struct AoiData {
  std::string id;
  std::vector<Vec2> polygon;
  Window window;
};

struct KozData {
  std::string id;
  std::string purpose;
  std::vector<Vec2> polygon;
  std::optional<double> alt_min;
  std::optional<double> alt_max;
  Window window;
};

struct CellData {
  std::vector<Vec2> polygon;
  double probability = 0.0;
};

struct PriorData {
  std::string aoi_id;
  std::vector<CellData> cells;
};

struct RouteData {
  std::string id;
  std::vector<Vec2> polyline;
  std::vector<Vec2> band;
  std::vector<std::string> streets;
  double band_width = 0.0;
};

struct TargetData {
  std::string id;
  std::string description;  // "black Ford Explorer (suv)"
};

// A scenario entity: its t = 0 pose and footprint size, and its path (empty when it stays).
struct MoverData {
  std::string id;
  std::string cls;
  std::string role;
  Vec2 position{0, 0};
  double yaw = 0.0;
  double length = 0.0;
  double width = 0.0;
  std::vector<double> times;
  std::vector<Vec2> path;
};

// An avoid phase's goal: where, its height and the radius that counts as reached.
struct GoalData {
  Vec2 position{0, 0};
  double z = 0.0;
  double radius = 0.0;
};

struct MapData {
  std::string scenario_id;
  std::string cls;
  std::string objective_type;
  std::string objective_text;
  double time_limit = 0.0;
  std::vector<TargetData> targets;
  std::vector<AoiData> aois;
  std::vector<KozData> kozs;
  std::vector<PriorData> priors;
  std::vector<RouteData> routes;
  std::vector<std::string> relations;
  std::vector<MoverData> entities;  // aircraft too (role "aircraft", class = model)
  std::optional<GoalData> goal;
  Vec2 uav_start{0, 0};
  double uav_yaw = 0.0;
  double uav_alt_min = 0.0;
  double uav_alt_max = 0.0;
};

inline std::string member(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

inline std::string element(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

// Typed access to one JSON document; every failure is a ConfigError "FILE: PATH: problem".
class DocReader {
 public:
  explicit DocReader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw ConfigError(file_ + ": " + (path.empty() ? std::string("(document)") : path) + ": " +
                      what);
  }

  const json& at(const json& obj, const std::string& path, const char* key) const {
    if (!obj.is_object()) fail(path, "expected an object");
    const auto it = obj.find(key);
    if (it == obj.end()) fail(member(path, key), "missing");
    return *it;
  }

  const json* find(const json& obj, const std::string& path, const char* key) const {
    if (!obj.is_object()) fail(path, "expected an object");
    const auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
  }

  double number(const json& j, const std::string& path) const {
    if (!j.is_number()) fail(path, "expected a number");
    const double v = j.get<double>();
    if (!std::isfinite(v)) fail(path, "expected a finite number");
    return v;
  }

  std::string string(const json& j, const std::string& path) const {
    if (!j.is_string()) fail(path, "expected a string");
    return j.get<std::string>();
  }

  const json& array(const json& j, const std::string& path) const {
    if (!j.is_array()) fail(path, "expected an array");
    return j;
  }

  double numberAt(const json& obj, const std::string& path, const char* key) const {
    return number(at(obj, path, key), member(path, key));
  }

  std::string stringAt(const json& obj, const std::string& path, const char* key) const {
    return string(at(obj, path, key), member(path, key));
  }

  std::optional<double> optionalNumber(const json& obj, const std::string& path,
                                       const char* key) const {
    const json* j = find(obj, path, key);
    if (!j) return std::nullopt;
    return number(*j, member(path, key));
  }

  std::vector<Vec2> points(const json& j, const std::string& path, std::size_t min_count) const {
    array(j, path);
    if (j.size() < min_count) {
      fail(path, "expected at least " + std::to_string(min_count) + " points, got " +
                     std::to_string(j.size()));
    }
    std::vector<Vec2> out;
    out.reserve(j.size());
    for (std::size_t i = 0; i < j.size(); ++i) {
      const std::string p = element(path, i);
      if (!j[i].is_array() || j[i].size() != 2) fail(p, "expected [x, y]");
      out.emplace_back(number(j[i][0], element(p, 0)), number(j[i][1], element(p, 1)));
    }
    return out;
  }

  Window window(const json& obj, const std::string& path) const {
    const std::string p = member(path, "time_window");
    const json& w = at(obj, path, "time_window");
    Window out;
    out.net = optionalNumber(w, p, "net");
    out.nlt = optionalNumber(w, p, "nlt");
    if (out.net && out.nlt && *out.net > *out.nlt) fail(p, "net is later than nlt");
    return out;
  }

 private:
  std::string file_;
};

MapData parseDocuments(const json& mission, const json& sim, const std::string& mission_file,
                       const std::string& sim_file);

// ------------------------------------------------------------------------------ style

constexpr int kShift = 3;  // fractional bits of the drawing coordinates
constexpr double kOne = 1 << kShift;
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kBoldFont = cv::FONT_HERSHEY_DUPLEX;

inline cv::Scalar rgb(int r, int g, int b) { return cv::Scalar(b, g, r); }

const cv::Scalar kGround = rgb(243, 241, 234);
const cv::Scalar kLawn = rgb(225, 236, 212);
const cv::Scalar kSidewalk = rgb(212, 210, 204);
const cv::Scalar kStreet = rgb(170, 170, 175);
const cv::Scalar kDriveway = rgb(200, 198, 192);
const cv::Scalar kHouse = rgb(214, 168, 138);
const cv::Scalar kHouseEdge = rgb(150, 108, 85);
const cv::Scalar kGarage = rgb(184, 170, 160);
const cv::Scalar kGarageEdge = rgb(120, 105, 95);
const cv::Scalar kFence = rgb(125, 92, 60);
const cv::Scalar kTree = rgb(128, 178, 100);
const cv::Scalar kTreeEdge = rgb(84, 136, 62);
const cv::Scalar kWorldCar = rgb(112, 120, 138);
const cv::Scalar kAoi = rgb(25, 65, 160);
const cv::Scalar kKozEdge = rgb(165, 15, 25);
const cv::Scalar kRoute = rgb(120, 40, 170);
const cv::Scalar kTargetDark = rgb(160, 10, 25);
const cv::Scalar kConfuserDark = rgb(185, 85, 0);
const cv::Scalar kTraffic = rgb(60, 60, 66);
const cv::Scalar kPedestrian = rgb(0, 125, 140);
const cv::Scalar kVignette = rgb(175, 0, 175);
const cv::Scalar kUav = rgb(0, 95, 210);
const cv::Scalar kAircraft = kAircraftColor;
const cv::Scalar kGoal = kGoalColor;
const cv::Scalar kText = rgb(30, 30, 30);
const cv::Scalar kWhite = rgb(255, 255, 255);
const cv::Scalar kBlack = rgb(0, 0, 0);

constexpr double kPriorAlpha = 0.5;
constexpr double kKozAlpha = 0.45;
constexpr double kBandAlpha = 0.12;
constexpr double kLabelBoxAlpha = 0.78;
constexpr double kTickSeconds = 30.0;

// Text, colour scale and glyph functions (map_drawing.cpp).
cv::Scalar heatColor(double u);
std::string fixed(double v, int digits);
std::string compact(double v);
std::string windowText(const Window& w);
std::string altitudeText(const KozData& k);
std::string ascii(const std::string& s);
std::vector<std::string> wrapText(const std::string& text, int font, double scale, int thickness,
                                  int max_width);
bool isTarget(const MoverData& m, const MapData& d);
double maxProbability(const MapData& d);
double scaleBarLength(double px_per_m, int max_px);
void confuserGlyph(cv::Mat& img, cv::Point c, int r);
void uavGlyph(cv::Mat& img, cv::Point2d c, double yaw, double r);

// ------------------------------------------------------------------------------ layout

struct Layout {
  MapFrame frame;
  std::vector<std::string> title_bold;   // scenario id, class and time limit
  std::vector<std::string> title_lines;  // the objective
  int title_height = 0;
  cv::Mat panel;
};

constexpr double kTitleScale = 0.7;
constexpr double kSubtitleScale = 0.55;
constexpr int kTitleStep = 28;
constexpr int kSubtitleStep = 22;

Layout computeLayout(const scenario::World& world, const MapData& d, const MapStyle& style);

// ------------------------------------------------------------------------------ map painter

class MapPainter {
 public:
  MapPainter(const MapFrame& frame, const MapStyle& style);

  cv::Mat& image() { return img_; }

  cv::Point2d px(const Vec2& p) const;

  cv::Point fx(const cv::Point2d& p) const;

  cv::Point fx(const Vec2& p) const { return fx(px(p)); }

  std::vector<cv::Point> fx(const std::vector<Vec2>& pts) const;

  bool visible(const Aabb2& b) const;

  void fill(const std::vector<Vec2>& poly, const cv::Scalar& c, cv::Mat* target = nullptr,
            int line_type = cv::LINE_AA);

  void outline(const std::vector<Vec2>& pts, bool closed, const cv::Scalar& c, int thickness,
               int line_type = cv::LINE_AA);

  void dashed(std::vector<Vec2> pts, bool closed, const cv::Scalar& c, int thickness,
              double dash_px = 9.0, double gap_px = 6.0);

  // Blends `layer` into the image with `alpha` where `mask` is set.
  // Polygons filled with their colours and blended over the map at `alpha` (areas, zones,
  // bands): one layer and one mask, so overlaps are not darkened twice.
  void translucent(const std::vector<std::pair<const std::vector<Vec2>*, cv::Scalar>>& shapes,
                   double alpha);

  void blend(const cv::Mat& layer, const cv::Mat& mask, double alpha);

  // Diagonal hatching clipped to a polygon.
  void hatch(const std::vector<Vec2>& poly, const cv::Scalar& c, int spacing);

  // ------------------------------------------------------------------ labels

  // Places a (multi-line) label near `anchor` (map pixels), avoiding earlier labels and marker
  // boxes; falls back to the first candidate inside the map.
  void placeLabel(const std::vector<std::string>& lines, cv::Point2d anchor, double gap,
                  double scale, int thickness, const cv::Scalar& color);

  void reserve(const cv::Point2d& c, int half);

  // ------------------------------------------------------------------ layers

  void drawWorld(const scenario::World& world);

  void drawPriors(const MapData& d);

  void drawAois(const MapData& d);

  void drawKozs(const MapData& d);

  void drawRoutes(const MapData& d);

  // A filled arrow head at the end of a polyline, pointing along its last segment.
  void arrowHead(const std::vector<Vec2>& pts, const cv::Scalar& c, double size);

  void drawMovers(const MapData& d);

  static Vec2 pathAt(const MoverData& m, double t);

  void drawMarkersAndLabels(const MapData& d);

  // The top-left-most vertex in the image (north-west corner of the polygon).
  cv::Point2d topCorner(const std::vector<Vec2>& poly) const;

 private:
  const MapFrame& frame_;
  const MapStyle& style_;
  cv::Mat img_;
  std::vector<cv::Rect> occupied_;
};

}  // namespace map_internal

using namespace map_internal;

}  // namespace hameritt::map
