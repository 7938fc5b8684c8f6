#include "hameritt/map/scenario_map.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <iterator>
#include <optional>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/params_table.h"
#include "hameritt/scenario/scenario_io.h"

namespace hameritt::map {

namespace {

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
  std::vector<MoverData> entities;
  Vec2 uav_start{0, 0};
  double uav_yaw = 0.0;
  double uav_alt_min = 0.0;
  double uav_alt_max = 0.0;
};

std::string member(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

std::string element(const std::string& path, std::size_t i) {
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

void parseMission(const json& m, const DocReader& r, MapData* d) {
  d->scenario_id = r.stringAt(m, "", "scenario_id");
  d->cls = r.stringAt(m, "", "class");
  d->time_limit = r.numberAt(m, "", "time_limit");

  const json& obj = r.at(m, "", "objective");
  d->objective_type = r.stringAt(obj, "objective", "type");
  d->objective_text = r.stringAt(obj, "objective", "text");
  const json& targets = r.array(r.at(obj, "objective", "targets"), "objective.targets");
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const std::string p = element("objective.targets", i);
    TargetData t;
    t.id = r.stringAt(targets[i], p, "id");
    std::string desc;
    for (const char* key : {"color", "make", "model"}) {
      const json* v = r.find(targets[i], p, key);
      if (v && !r.string(*v, member(p, key)).empty()) {
        desc += (desc.empty() ? "" : " ") + v->get<std::string>();
      }
    }
    if (const json* v = r.find(targets[i], p, "vehicle_class")) {
      const std::string vc = r.string(*v, member(p, "vehicle_class"));
      if (!vc.empty()) desc += (desc.empty() ? "" : " ") + std::string("(") + vc + ")";
    }
    t.description = desc;
    d->targets.push_back(std::move(t));
  }

  const json& aois = r.array(r.at(m, "", "areas_of_interest"), "areas_of_interest");
  for (std::size_t i = 0; i < aois.size(); ++i) {
    const std::string p = element("areas_of_interest", i);
    AoiData a;
    a.id = r.stringAt(aois[i], p, "id");
    a.polygon = r.points(r.at(aois[i], p, "polygon"), member(p, "polygon"), 3);
    a.window = r.window(aois[i], p);
    d->aois.push_back(std::move(a));
  }

  const json& kozs = r.array(r.at(m, "", "keep_out_zones"), "keep_out_zones");
  for (std::size_t i = 0; i < kozs.size(); ++i) {
    const std::string p = element("keep_out_zones", i);
    KozData k;
    k.id = r.stringAt(kozs[i], p, "id");
    k.purpose = r.stringAt(kozs[i], p, "purpose");
    k.polygon = r.points(r.at(kozs[i], p, "polygon"), member(p, "polygon"), 3);
    const json& alt = r.at(kozs[i], p, "altitude");
    k.alt_min = r.optionalNumber(alt, member(p, "altitude"), "min");
    k.alt_max = r.optionalNumber(alt, member(p, "altitude"), "max");
    k.window = r.window(kozs[i], p);
    d->kozs.push_back(std::move(k));
  }

  const json& priors = r.array(r.at(m, "", "area_priors"), "area_priors");
  for (std::size_t i = 0; i < priors.size(); ++i) {
    const std::string p = element("area_priors", i);
    PriorData pr;
    pr.aoi_id = r.stringAt(priors[i], p, "aoi_id");
    const std::string cp = member(p, "cells");
    const json& cells = r.array(r.at(priors[i], p, "cells"), cp);
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const std::string q = element(cp, c);
      CellData cell;
      cell.polygon = r.points(r.at(cells[c], q, "polygon"), member(q, "polygon"), 3);
      cell.probability = r.numberAt(cells[c], q, "probability");
      if (cell.probability < 0.0 || cell.probability > 1.0) {
        r.fail(member(q, "probability"), "expected a probability in [0, 1]");
      }
      pr.cells.push_back(std::move(cell));
    }
    d->priors.push_back(std::move(pr));
  }

  const json& routes = r.array(r.at(m, "", "routes"), "routes");
  for (std::size_t i = 0; i < routes.size(); ++i) {
    const std::string p = element("routes", i);
    RouteData rt;
    rt.id = r.stringAt(routes[i], p, "id");
    rt.polyline = r.points(r.at(routes[i], p, "polyline"), member(p, "polyline"), 2);
    rt.band = r.points(r.at(routes[i], p, "band_polygon"), member(p, "band_polygon"), 3);
    rt.band_width = r.numberAt(routes[i], p, "band_width");
    const std::string sp = member(p, "streets");
    const json& streets = r.array(r.at(routes[i], p, "streets"), sp);
    for (std::size_t s = 0; s < streets.size(); ++s) {
      rt.streets.push_back(r.string(streets[s], element(sp, s)));
    }
    d->routes.push_back(std::move(rt));
  }

  if (const json* rel = r.find(m, "", "scene_relations")) {
    r.array(*rel, "scene_relations");
    for (std::size_t i = 0; i < rel->size(); ++i) {
      d->relations.push_back(r.stringAt((*rel)[i], element("scene_relations", i), "text"));
    }
  }
}

void parseSimConfig(const json& s, const DocReader& r, MapData* d) {
  const json& entities = r.array(r.at(s, "", "entities"), "entities");
  for (std::size_t i = 0; i < entities.size(); ++i) {
    const std::string p = element("entities", i);
    const json& e = entities[i];
    MoverData mv;
    mv.id = r.stringAt(e, p, "id");
    mv.cls = r.stringAt(e, p, "class");
    mv.role = r.stringAt(e, p, "role");
    const std::string pp = member(p, "pose");
    const json& pose = r.at(e, p, "pose");
    mv.position = Vec2(r.numberAt(pose, pp, "x"), r.numberAt(pose, pp, "y"));
    mv.yaw = r.numberAt(pose, pp, "yaw");
    const std::string zp = member(p, "size");
    const json& size = r.array(r.at(e, p, "size"), zp);
    if (size.size() != 3) r.fail(zp, "expected [length, width, height]");
    mv.length = r.number(size[0], element(zp, 0));
    mv.width = r.number(size[1], element(zp, 1));
    if (mv.length <= 0.0 || mv.width <= 0.0) r.fail(zp, "expected positive sizes");
    const std::string tp = member(p, "trajectory");
    const json& traj = r.array(r.at(e, p, "trajectory"), tp);
    for (std::size_t k = 0; k < traj.size(); ++k) {
      const std::string q = element(tp, k);
      if (!traj[k].is_array() || traj[k].size() != 5) r.fail(q, "expected [t, x, y, z, yaw]");
      const double t = r.number(traj[k][0], element(q, 0));
      if (!mv.times.empty() && t < mv.times.back()) r.fail(element(q, 0), "time goes backwards");
      mv.times.push_back(t);
      mv.path.emplace_back(r.number(traj[k][1], element(q, 1)),
                           r.number(traj[k][2], element(q, 2)));
    }
    d->entities.push_back(std::move(mv));
  }
  const json& uav = r.at(s, "", "uav");
  const json& start = r.at(uav, "uav", "start");
  d->uav_start = Vec2(r.numberAt(start, "uav.start", "x"), r.numberAt(start, "uav.start", "y"));
  d->uav_yaw = r.numberAt(start, "uav.start", "yaw");
  const json& alt = r.at(uav, "uav", "altitude");
  d->uav_alt_min = r.numberAt(alt, "uav.altitude", "min");
  d->uav_alt_max = r.numberAt(alt, "uav.altitude", "max");
}

MapData parseDocuments(const json& mission, const json& sim, const std::string& mission_file,
                       const std::string& sim_file) {
  MapData d;
  const DocReader mr(mission_file), sr(sim_file);
  parseMission(mission, mr, &d);
  parseSimConfig(sim, sr, &d);
  const std::string sim_id = sr.stringAt(sim, "", "scenario_id");
  if (sim_id != d.scenario_id) {
    sr.fail("scenario_id", "'" + sim_id + "' does not match " + mission_file + " ('" +
                               d.scenario_id + "')");
  }
  for (std::size_t i = 0; i < d.targets.size(); ++i) {
    const bool found = std::any_of(d.entities.begin(), d.entities.end(),
                                   [&](const MoverData& m) { return m.id == d.targets[i].id; });
    if (!found) {
      mr.fail(element("objective.targets", i) + ".id",
              "'" + d.targets[i].id + "' is not among the entities of " + sim_file);
    }
  }
  return d;
}

// ------------------------------------------------------------------------------ style helpers

constexpr int kShift = 3;  // fractional bits of the drawing coordinates
constexpr double kOne = 1 << kShift;
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kBoldFont = cv::FONT_HERSHEY_DUPLEX;

cv::Scalar rgb(int r, int g, int b) { return cv::Scalar(b, g, r); }

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
const cv::Scalar kText = rgb(30, 30, 30);
const cv::Scalar kWhite = rgb(255, 255, 255);
const cv::Scalar kBlack = rgb(0, 0, 0);

constexpr double kPriorAlpha = 0.5;
constexpr double kKozAlpha = 0.45;
constexpr double kBandAlpha = 0.12;
constexpr double kLabelBoxAlpha = 0.78;
constexpr double kTickSeconds = 30.0;

// Yellow-green-blue ramp for prior probabilities (u in [0, 1]).
cv::Scalar heatColor(double u) {
  static const double stops[][3] = {
      {255, 255, 217}, {199, 233, 180}, {65, 182, 196}, {34, 94, 168}, {8, 29, 88}};
  u = std::clamp(u, 0.0, 1.0) * 4.0;
  const int i = std::min(3, static_cast<int>(u));
  const double f = u - i;
  double c[3];
  for (int k = 0; k < 3; ++k) c[k] = stops[i][k] + f * (stops[i + 1][k] - stops[i][k]);
  return rgb(static_cast<int>(std::lround(c[0])), static_cast<int>(std::lround(c[1])),
             static_cast<int>(std::lround(c[2])));
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

// Shortest of "%.0f" / "%.1f" that keeps a tenth.
std::string compact(double v) {
  return std::abs(v - std::round(v)) < 0.05 ? fixed(v, 0) : fixed(v, 1);
}

std::string windowText(const Window& w) {
  if (w.net && w.nlt) return "[t " + fixed(*w.net, 1) + "-" + fixed(*w.nlt, 1) + " s]";
  if (w.net) return "[t >= " + fixed(*w.net, 1) + " s]";
  if (w.nlt) return "[t <= " + fixed(*w.nlt, 1) + " s]";
  return "";
}

std::string altitudeText(const KozData& k) {
  if (k.alt_min && k.alt_max) {
    return "alt " + compact(*k.alt_min) + "-" + compact(*k.alt_max) + " m";
  }
  if (k.alt_min) return "alt >= " + compact(*k.alt_min) + " m";
  if (k.alt_max) return "alt <= " + compact(*k.alt_max) + " m";
  return "";
}

// Hershey fonts are ASCII only.
std::string ascii(const std::string& s) {
  std::string out;
  for (unsigned char c : s) out += (c >= 32 && c < 127) ? static_cast<char>(c) : '?';
  return out;
}

std::vector<std::string> wrapText(const std::string& text, int font, double scale, int thickness,
                                  int max_width) {
  std::vector<std::string> lines;
  std::string line;
  auto width = [&](const std::string& s) {
    int base = 0;
    return cv::getTextSize(s, font, scale, thickness, &base).width;
  };
  std::size_t pos = 0;
  const std::string t = ascii(text);
  while (pos < t.size()) {
    std::size_t end = t.find(' ', pos);
    if (end == std::string::npos) end = t.size();
    std::string word = t.substr(pos, end - pos);
    pos = end + 1;
    const std::string candidate = line.empty() ? word : line + " " + word;
    if (width(candidate) <= max_width) {
      line = candidate;
      continue;
    }
    if (!line.empty()) lines.push_back(line);
    line.clear();
    // A word wider than a line is broken where it no longer fits.
    while (width(word) > max_width && word.size() > 1) {
      std::size_t n = word.size() - 1;
      while (n > 1 && width(word.substr(0, n)) > max_width) --n;
      lines.push_back(word.substr(0, n));
      word = word.substr(n);
    }
    line = word;
  }
  if (!line.empty() || lines.empty()) lines.push_back(line);
  return lines;
}

// ------------------------------------------------------------------------------ layout

struct Interest {
  bool any = false;
  Aabb2 box;
  void add(const Vec2& p) {
    if (!any) {
      box.min = box.max = p;
      any = true;
      return;
    }
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  }
  void add(const std::vector<Vec2>& pts) {
    for (const auto& p : pts) add(p);
  }
};

bool isTarget(const MoverData& m, const MapData& d) {
  if (m.role == "target") return true;
  return std::any_of(d.targets.begin(), d.targets.end(),
                     [&](const TargetData& t) { return t.id == m.id; });
}

// Widens [lo, hi] to at least `want` (never beyond [full_lo, full_hi]), sliding it back
// inside the full range where it sticks out.
void fitSpan(double want, double full_lo, double full_hi, double* lo, double* hi) {
  const double size = *hi - *lo;
  if (size >= full_hi - full_lo || want >= full_hi - full_lo) {
    *lo = full_lo;
    *hi = full_hi;
    return;
  }
  const double grow = 0.5 * std::max(0.0, want - size);
  *lo -= grow;
  *hi += grow;
  if (*lo < full_lo) {
    *hi += full_lo - *lo;
    *lo = full_lo;
  }
  if (*hi > full_hi) {
    *lo -= *hi - full_hi;
    *hi = full_hi;
  }
}

// The ENU rectangle shown: the world bounds (grown to take in any mission geometry that sticks
// out of the world) plus the margin, or, when cropping, the mission region plus its margin, at
// least min_interest_size_m wide and min_height_m tall.
Aabb2 mapRegion(const scenario::World& world, const MapData& d, const MapStyle& style,
                double min_height_m) {
  Interest in;
  for (const auto& a : d.aois) in.add(a.polygon);
  for (const auto& k : d.kozs) in.add(k.polygon);
  for (const auto& r : d.routes) in.add(r.band);
  for (const auto& m : d.entities) {
    if (!isTarget(m, d)) continue;
    in.add(m.position);
    in.add(m.path);
  }
  in.add(d.uav_start);
  Aabb2 full = world.bounds();
  full.min = full.min.cwiseMin(in.box.min) - Vec2(style.margin_m, style.margin_m);
  full.max = full.max.cwiseMax(in.box.max) + Vec2(style.margin_m, style.margin_m);
  if (!style.crop_to_interest) return full;
  Aabb2 r = in.box;
  r.min -= Vec2(style.interest_margin_m, style.interest_margin_m);
  r.max += Vec2(style.interest_margin_m, style.interest_margin_m);
  fitSpan(std::max(style.min_interest_size_m, min_height_m), full.min.y(), full.max.y(), &r.min.y(),
          &r.max.y());
  // Not much narrower than tall (a tall panel would otherwise leave a sliver of map).
  fitSpan(std::max(style.min_interest_size_m, 0.75 * (r.max.y() - r.min.y())), full.min.x(),
          full.max.x(), &r.min.x(), &r.max.x());
  return r;
}

double maxProbability(const MapData& d) {
  double p = 0.0;
  for (const auto& pr : d.priors) {
    for (const auto& c : pr.cells) p = std::max(p, c.probability);
  }
  return p;
}

// Largest round length (metres) whose bar fits in max_px.
double scaleBarLength(double px_per_m, int max_px) {
  static const double lengths[] = {1000, 500, 200, 100, 50, 20, 10, 5, 2, 1};
  for (double l : lengths) {
    if (l * px_per_m <= max_px) return l;
  }
  return 1.0;
}

void confuserGlyph(cv::Mat& img, cv::Point c, int r) {
  std::vector<cv::Point> pts = {{c.x, c.y - r - 1}, {c.x + r + 1, c.y}, {c.x, c.y + r + 1},
                                {c.x - r - 1, c.y}};
  cv::fillConvexPoly(img, pts, kBlack, cv::LINE_AA);
  pts = {{c.x, c.y - r}, {c.x + r, c.y}, {c.x, c.y + r}, {c.x - r, c.y}};
  cv::fillConvexPoly(img, pts, kConfuserColor, cv::LINE_AA);
}

// Triangle pointing along the ENU yaw (image y points south).
void uavGlyph(cv::Mat& img, cv::Point2d c, double yaw, double r) {
  const cv::Point2d f(std::cos(yaw), -std::sin(yaw));
  const cv::Point2d s(-f.y, f.x);
  std::vector<cv::Point> pts;
  for (const cv::Point2d& p : {c + f * r, c - f * (0.6 * r) + s * (0.7 * r),
                               c - f * (0.6 * r) - s * (0.7 * r)}) {
    pts.emplace_back(static_cast<int>(std::lround(p.x * kOne)),
                     static_cast<int>(std::lround(p.y * kOne)));
  }
  cv::fillConvexPoly(img, pts, kUav, cv::LINE_AA, kShift);
  cv::polylines(img, pts, true, kWhite, 1, cv::LINE_AA, kShift);
}

// Draws the legend and mission panel into a tall canvas and returns it trimmed to its content.
class PanelBuilder {
 public:
  PanelBuilder(const MapData& d, const MapStyle& style) : d_(d), style_(style) {
    width_ = style.panel_width_px;
    img_ = cv::Mat(6000, width_, CV_8UC3, kWhite);
  }

  cv::Mat build() {
    y_ = 14;
    heading("LEGEND");
    worldEntries();
    missionEntries();
    moverEntries();
    if (!d_.priors.empty()) priorBar();
    scaleAndNorth();
    missionText();
    y_ += 8;
    const int h = std::min(y_, img_.rows);
    cv::Mat out = img_(cv::Rect(0, 0, width_, h)).clone();
    cv::line(out, cv::Point(0, 0), cv::Point(0, h - 1), rgb(160, 160, 160), 1);
    return out;
  }

 private:
  static constexpr int kPad = 14;
  static constexpr int kRow = 21;
  static constexpr double kScale = 0.45;

  void heading(const std::string& s) {
    y_ += 6;
    cv::putText(img_, s, cv::Point(kPad, y_ + 14), kBoldFont, 0.55, kText, 1, cv::LINE_AA);
    y_ += 20;
    cv::line(img_, cv::Point(kPad, y_), cv::Point(width_ - kPad, y_), rgb(190, 190, 190), 1);
    y_ += 6;
  }

  void label(const std::string& s, int x, int y) {
    cv::putText(img_, ascii(s), cv::Point(x, y), kFont, kScale, kText, 1, cv::LINE_AA);
  }

  // One legend row: a 28 x 14 swatch painted by `draw`, then the text.
  template <typename Draw>
  void entry(const std::string& text, Draw draw) {
    const cv::Rect box(kPad, y_ + 3, 28, 14);
    draw(box);
    label(text, kPad + 36, y_ + 15);
    y_ += kRow;
  }

  void worldEntries() {
    struct Item {
      const char* text;
      int kind;
    };
    const Item items[] = {{"Street", 0}, {"Driveway", 1}, {"Sidewalk", 2}, {"House", 3},
                          {"Garage", 4}, {"Fence", 5},    {"Tree", 6},     {"Parked car", 7}};
    int column = 0;
    for (const auto& it : items) {
      const int kind = it.kind;
      entryColumn(column, it.text, [&, kind](const cv::Rect& b) { worldSwatch(kind, b); });
      column = 1 - column;
    }
    if (column == 1) y_ += kRow;
  }

  // Half-width legend entry in column 0 or 1; the row advances after column 1.
  template <typename Draw>
  void entryColumn(int column, const std::string& text, Draw draw) {
    const int col_w = (width_ - 2 * kPad) / 2;
    const int x = kPad + column * col_w;
    const cv::Rect box(x, y_ + 3, 28, 14);
    draw(box);
    label(text, x + 36, y_ + 15);
    if (column == 1) y_ += kRow;
  }

  void worldSwatch(int kind, const cv::Rect& b) {
    const cv::Point c(b.x + b.width / 2, b.y + b.height / 2);
    switch (kind) {
      case 0:
        cv::rectangle(img_, b, kStreet, cv::FILLED);
        break;
      case 1:
        cv::rectangle(img_, b, kDriveway, cv::FILLED);
        break;
      case 2:
        cv::rectangle(img_, b, kLawn, cv::FILLED);
        cv::line(img_, cv::Point(b.x, c.y), cv::Point(b.x + b.width, c.y), kSidewalk, 3);
        break;
      case 3:
        cv::rectangle(img_, b, kHouse, cv::FILLED);
        cv::rectangle(img_, b, kHouseEdge, 1);
        break;
      case 4:
        cv::rectangle(img_, cv::Rect(b.x + 6, b.y + 1, 16, 12), kGarage, cv::FILLED);
        cv::rectangle(img_, cv::Rect(b.x + 6, b.y + 1, 16, 12), kGarageEdge, 1);
        break;
      case 5:
        cv::line(img_, cv::Point(b.x, c.y), cv::Point(b.x + b.width, c.y), kFence, 2);
        break;
      case 6:
        cv::circle(img_, c, 6, kTree, cv::FILLED, cv::LINE_AA);
        cv::circle(img_, c, 6, kTreeEdge, 1, cv::LINE_AA);
        break;
      default:
        cv::rectangle(img_, cv::Rect(c.x - 6, c.y - 3, 12, 6), kWorldCar, cv::FILLED);
        break;
    }
  }

  void missionEntries() {
    y_ += 4;
    if (!d_.aois.empty()) {
      entry("Area of interest (AOI)", [&](const cv::Rect& b) {
        cv::rectangle(img_, b, heatColor(0.3), cv::FILLED);
        cv::rectangle(img_, b, kAoi, 2);
      });
    }
    bool bounded = false, unbounded = false;
    for (const auto& k : d_.kozs) {
      if (k.window.net || k.window.nlt) bounded = true;
      else unbounded = true;
    }
    if (unbounded) {
      entry("Keep-out zone (KOZ)", [&](const cv::Rect& b) { kozSwatch(b, false); });
    }
    if (bounded) {
      entry("KOZ active only in [t window]", [&](const cv::Rect& b) { kozSwatch(b, true); });
    }
    if (!d_.routes.empty()) {
      entry("Route of interest + search band", [&](const cv::Rect& b) {
        cv::rectangle(img_, b, kRoute, 1);
        cv::line(img_, cv::Point(b.x, b.y + 7), cv::Point(b.x + b.width, b.y + 7), kRoute, 4);
      });
    }
  }

  void kozSwatch(const cv::Rect& b, bool dashed) {
    cv::Mat roi = img_(b);
    cv::Mat tint(roi.size(), roi.type(), kKozColor);
    cv::addWeighted(roi, 1.0 - kKozAlpha, tint, kKozAlpha, 0.0, roi);
    for (int k = -b.height; k < b.width; k += 7) {
      cv::line(roi, cv::Point(k, b.height), cv::Point(k + b.height, 0), kKozEdge, 1, cv::LINE_AA);
    }
    if (dashed) {
      for (int x = b.x; x < b.x + b.width; x += 8) {
        const int x1 = std::min(x + 4, b.x + b.width);
        cv::line(img_, cv::Point(x, b.y), cv::Point(x1, b.y), kKozEdge, 2);
        cv::line(img_, cv::Point(x, b.y + b.height), cv::Point(x1, b.y + b.height), kKozEdge, 2);
      }
    } else {
      cv::rectangle(img_, b, kKozEdge, 2);
    }
  }

  void moverEntries() {
    bool has[4] = {false, false, false, false};  // confuser, traffic, pedestrian, other
    for (const auto& m : d_.entities) {
      if (isTarget(m, d_)) continue;
      if (m.role == "confuser") has[0] = true;
      else if (m.role == "traffic") has[1] = true;
      else if (m.role == "pedestrian") has[2] = true;
      else has[3] = true;
    }
    entry("Target (t = 0) and its path", [&](const cv::Rect& b) {
      const cv::Point c(b.x + 20, b.y + 7);
      cv::line(img_, cv::Point(b.x - 2, c.y), c, kTargetColor, 3, cv::LINE_AA);
      cv::circle(img_, c, 7, kBlack, cv::FILLED, cv::LINE_AA);
      cv::circle(img_, c, 6, kWhite, cv::FILLED, cv::LINE_AA);
      cv::circle(img_, c, 4, kTargetColor, cv::FILLED, cv::LINE_AA);
    });
    entry("Target path end; dots every 30 s", [&](const cv::Rect& b) {
      const cv::Point c(b.x + 20, b.y + 7);
      cv::line(img_, cv::Point(b.x - 2, c.y), c, kTargetColor, 3, cv::LINE_AA);
      cv::circle(img_, cv::Point(b.x + 6, c.y), 2, kWhite, cv::FILLED, cv::LINE_AA);
      cv::circle(img_, c, 5, kTargetColor, 2, cv::LINE_AA);
    });
    if (has[0]) {
      entry("Confuser (look-alike)", [&](const cv::Rect& b) {
        confuserGlyph(img_, cv::Point(b.x + 14, b.y + 7), 6);
      });
    }
    if (has[1]) {
      entry("Traffic car and path", [&](const cv::Rect& b) {
        cv::line(img_, cv::Point(b.x, b.y + 7), cv::Point(b.x + b.width, b.y + 7), kTraffic, 1,
                 cv::LINE_AA);
        cv::rectangle(img_, cv::Rect(b.x + 10, b.y + 5, 8, 4), kTraffic, cv::FILLED);
      });
    }
    if (has[2]) {
      entry("Pedestrian and path", [&](const cv::Rect& b) {
        cv::line(img_, cv::Point(b.x, b.y + 7), cv::Point(b.x + b.width, b.y + 7), kPedestrian, 1,
                 cv::LINE_AA);
        cv::circle(img_, cv::Point(b.x + 14, b.y + 7), 2, kPedestrian, cv::FILLED, cv::LINE_AA);
      });
    }
    if (has[3]) {
      entry("Vignette actor and path", [&](const cv::Rect& b) {
        cv::line(img_, cv::Point(b.x, b.y + 7), cv::Point(b.x + b.width, b.y + 7), kVignette, 1,
                 cv::LINE_AA);
        cv::circle(img_, cv::Point(b.x + 14, b.y + 7), 3, kVignette, cv::FILLED, cv::LINE_AA);
      });
    }
    entry("UAV start (heading)", [&](const cv::Rect& b) {
      uavGlyph(img_, cv::Point2d(b.x + 14, b.y + 7), 0.0, 8.0);
    });
  }

  void priorBar() {
    y_ += 4;
    const double pmax = maxProbability(d_);
    label("Prior P(target in cell), colour scale", kPad, y_ + 14);
    y_ += 22;
    const int x0 = kPad, w = width_ - 2 * kPad - 10, h = 14;
    for (int i = 0; i < w; ++i) {
      const cv::Scalar c = heatColor(static_cast<double>(i) / (w - 1));
      cv::Mat col = img_(cv::Rect(x0 + i, y_, 1, h));
      cv::Mat base = col.clone();
      base.setTo(kGround);
      cv::Mat tint(col.size(), col.type(), c);
      cv::addWeighted(base, 1.0 - kPriorAlpha, tint, kPriorAlpha, 0.0, col);
    }
    cv::rectangle(img_, cv::Rect(x0, y_, w, h), rgb(120, 120, 120), 1);
    y_ += h;
    for (int k = 0; k <= 4; ++k) {
      const int x = x0 + k * (w - 1) / 4;
      cv::line(img_, cv::Point(x, y_), cv::Point(x, y_ + 4), kText, 1);
      const std::string s = fixed(pmax * k / 4.0, 2);
      int base = 0;
      const int tw = cv::getTextSize(s, kFont, 0.4, 1, &base).width;
      const int tx = std::clamp(x - tw / 2, 0, width_ - tw - 2);
      cv::putText(img_, s, cv::Point(tx, y_ + 18), kFont, 0.4, kText, 1, cv::LINE_AA);
    }
    y_ += 26;
  }

  void scaleAndNorth() {
    y_ += 6;
    const double len = scaleBarLength(style_.px_per_m, width_ - 2 * kPad - 80);
    const int bar = static_cast<int>(std::lround(len * style_.px_per_m));
    const int x0 = kPad, yb = y_ + 30;
    // Alternating black and white halves.
    cv::rectangle(img_, cv::Rect(x0, yb - 6, bar / 2, 6), kBlack, cv::FILLED);
    cv::rectangle(img_, cv::Rect(x0 + bar / 2, yb - 6, bar - bar / 2, 6), kWhite, cv::FILLED);
    cv::rectangle(img_, cv::Rect(x0, yb - 6, bar, 6), kBlack, 1);
    label("0", x0 - 3, yb + 16);
    const std::string ls = compact(len) + " m";
    int base = 0;
    const int tw = cv::getTextSize(ls, kFont, kScale, 1, &base).width;
    label(ls, x0 + bar - tw / 2, yb + 16);
    // North arrow.
    const int nx = width_ - kPad - 24, ny = y_ + 4;
    std::vector<cv::Point> left = {{nx, ny}, {nx - 9, ny + 34}, {nx, ny + 26}};
    std::vector<cv::Point> right = {{nx, ny}, {nx + 9, ny + 34}, {nx, ny + 26}};
    cv::fillConvexPoly(img_, left, kBlack, cv::LINE_AA);
    cv::fillConvexPoly(img_, right, kWhite, cv::LINE_AA);
    cv::polylines(img_, right, true, kBlack, 1, cv::LINE_AA);
    cv::putText(img_, "N", cv::Point(nx - 6, ny + 52), kBoldFont, 0.6, kText, 1, cv::LINE_AA);
    y_ += 62;
  }

  void paragraph(const std::string& text, int indent = 0) {
    for (const auto& line : wrapText(text, kFont, kScale, 1, width_ - 2 * kPad - indent)) {
      label(line, kPad + indent, y_ + 14);
      y_ += 18;
    }
  }

  void missionText() {
    heading("MISSION");
    paragraph("Time limit: " + compact(d_.time_limit) + " s");
    paragraph("UAV altitude: " + compact(d_.uav_alt_min) + "-" + compact(d_.uav_alt_max) + " m");
    y_ += 4;
    paragraph("Targets (" + d_.objective_type + "):");
    for (const auto& t : d_.targets) paragraph(t.id + ": " + t.description, 12);
    if (!d_.kozs.empty()) {
      y_ += 4;
      paragraph("Keep-out zones:");
      for (const auto& k : d_.kozs) {
        std::string s = k.id + ": " + k.purpose;
        const std::string alt = altitudeText(k);
        if (!alt.empty()) s += ", " + alt;
        const std::string w = windowText(k.window);
        s += w.empty() ? ", always" : " " + w;
        paragraph(s, 12);
      }
    }
    if (!d_.routes.empty()) {
      y_ += 4;
      paragraph("Routes:");
      for (const auto& r : d_.routes) {
        std::string s = r.id + " (band " + compact(r.band_width) + " m):";
        for (std::size_t i = 0; i < r.streets.size(); ++i) s += (i ? ", " : " ") + r.streets[i];
        paragraph(s, 12);
      }
    }
    if (!d_.relations.empty()) {
      y_ += 4;
      paragraph("Scene relations:");
      const std::size_t n = std::min<std::size_t>(d_.relations.size(), 5);
      for (std::size_t i = 0; i < n; ++i) paragraph("- " + d_.relations[i], 12);
      if (d_.relations.size() > n) {
        paragraph("(" + std::to_string(d_.relations.size() - n) + " more)", 12);
      }
    }
  }

  const MapData& d_;
  const MapStyle& style_;
  int width_ = 0;
  int y_ = 0;
  cv::Mat img_;
};

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

Layout computeLayout(const scenario::World& world, const MapData& d, const MapStyle& style) {
  style.validate();
  Layout l;
  l.panel = PanelBuilder(d, style).build();
  MapFrame& f = l.frame;
  // A cropped map grows to the panel's height rather than leaving blank space beside it.
  f.region = mapRegion(world, d, style, l.panel.rows / style.px_per_m);
  f.px_per_m = style.px_per_m;
  const int map_w = static_cast<int>(std::ceil((f.region.max.x() - f.region.min.x()) * f.px_per_m));
  const int map_h = static_cast<int>(std::ceil((f.region.max.y() - f.region.min.y()) * f.px_per_m));
  if (map_w > 20000 || map_h > 20000) {
    throw ConfigError("map style: px_per_m " + compact(style.px_per_m) + " gives a " +
                      std::to_string(map_w) + " x " + std::to_string(map_h) +
                      " px map, more than 20000 px; lower px_per_m");
  }
  const int width = map_w + l.panel.cols;
  l.title_bold = wrapText(d.scenario_id, kBoldFont, kTitleScale, 1, width - 24);
  l.title_lines = wrapText("Class " + d.cls + ", time limit " + compact(d.time_limit) +
                               " s. Objective (" + d.objective_type + "): " + d.objective_text,
                           kFont, kSubtitleScale, 1, width - 24);
  l.title_height = 14 + kTitleStep * static_cast<int>(l.title_bold.size()) +
                   kSubtitleStep * static_cast<int>(l.title_lines.size());
  f.map_rect = cv::Rect(0, l.title_height, map_w, map_h);
  f.image_size = cv::Size(width, l.title_height + std::max(map_h, l.panel.rows));
  return l;
}

// ------------------------------------------------------------------------------ map painter

class MapPainter {
 public:
  MapPainter(const MapFrame& frame, const MapStyle& style)
      : frame_(frame), style_(style),
        img_(frame.map_rect.height, frame.map_rect.width, CV_8UC3, kGround) {}

  cv::Mat& image() { return img_; }

  cv::Point2d px(const Vec2& p) const {
    return {(p.x() - frame_.region.min.x()) * frame_.px_per_m,
            (frame_.region.max.y() - p.y()) * frame_.px_per_m};
  }

  cv::Point fx(const cv::Point2d& p) const {
    return {static_cast<int>(std::lround(p.x * kOne)), static_cast<int>(std::lround(p.y * kOne))};
  }

  cv::Point fx(const Vec2& p) const { return fx(px(p)); }

  std::vector<cv::Point> fx(const std::vector<Vec2>& pts) const {
    std::vector<cv::Point> out;
    out.reserve(pts.size());
    for (const auto& p : pts) out.push_back(fx(p));
    return out;
  }

  bool visible(const Aabb2& b) const {
    Aabb2 r = frame_.region;
    return r.overlaps(b);
  }

  void fill(const std::vector<Vec2>& poly, const cv::Scalar& c, cv::Mat* target = nullptr,
            int line_type = cv::LINE_AA) {
    const std::vector<std::vector<cv::Point>> pts = {fx(poly)};
    cv::fillPoly(target ? *target : img_, pts, c, line_type, kShift);
  }

  void outline(const std::vector<Vec2>& pts, bool closed, const cv::Scalar& c, int thickness,
               int line_type = cv::LINE_AA) {
    cv::polylines(img_, fx(pts), closed, c, thickness, line_type, kShift);
  }

  void dashed(std::vector<Vec2> pts, bool closed, const cv::Scalar& c, int thickness,
              double dash_px = 9.0, double gap_px = 6.0) {
    if (closed && !pts.empty()) pts.push_back(pts.front());
    double phase = 0.0;  // distance into the current dash+gap period
    const double period = dash_px + gap_px;
    for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
      const cv::Point2d a = px(pts[i]), b = px(pts[i + 1]);
      const double len = std::hypot(b.x - a.x, b.y - a.y);
      if (len <= 0.0) continue;
      const cv::Point2d u = (b - a) * (1.0 / len);
      double s = 0.0;
      while (s < len) {
        const double in_period = std::fmod(phase + s, period);
        if (in_period < dash_px) {
          const double e = std::min(len, s + dash_px - in_period);
          cv::line(img_, fx(a + u * s), fx(a + u * e), c, thickness, cv::LINE_AA, kShift);
          s = e;
        } else {
          s += period - in_period;
        }
      }
      phase = std::fmod(phase + len, period);
    }
  }

  // Blends `layer` into the image with `alpha` where `mask` is set.
  // Polygons filled with their colours and blended over the map at `alpha` (areas, zones,
  // bands): one layer and one mask, so overlaps are not darkened twice.
  void translucent(const std::vector<std::pair<const std::vector<Vec2>*, cv::Scalar>>& shapes,
                   double alpha) {
    cv::Mat layer = img_.clone();
    cv::Mat mask = cv::Mat::zeros(img_.size(), CV_8UC1);
    for (const auto& [poly, color] : shapes) {
      fill(*poly, color, &layer, cv::LINE_8);
      fill(*poly, cv::Scalar(255), &mask, cv::LINE_8);
    }
    blend(layer, mask, alpha);
  }

  void blend(const cv::Mat& layer, const cv::Mat& mask, double alpha) {
    cv::Mat mixed;
    cv::addWeighted(img_, 1.0 - alpha, layer, alpha, 0.0, mixed);
    mixed.copyTo(img_, mask);
  }

  // Diagonal hatching clipped to a polygon.
  void hatch(const std::vector<Vec2>& poly, const cv::Scalar& c, int spacing) {
    cv::Rect box = cv::boundingRect(fx(poly));
    box = cv::Rect(box.x >> kShift, box.y >> kShift, (box.width >> kShift) + 2,
                   (box.height >> kShift) + 2) &
          cv::Rect(0, 0, img_.cols, img_.rows);
    if (box.area() <= 0) return;
    cv::Mat roi = img_(box);
    cv::Mat mask = cv::Mat::zeros(box.size(), CV_8UC1);
    std::vector<cv::Point> local;
    for (const auto& p : poly) {
      const cv::Point2d q = px(p) - cv::Point2d(box.x, box.y);
      local.push_back(fx(q));
    }
    cv::fillPoly(mask, std::vector<std::vector<cv::Point>>{local}, 255, cv::LINE_8, kShift);
    cv::Mat lines = roi.clone();
    // Phase the lines on absolute pixel coordinates so that neighbouring zones line up.
    const int start = -((box.x + box.y) % spacing) - box.height;
    for (int k = start; k < box.width; k += spacing) {
      cv::line(lines, cv::Point(k, box.height), cv::Point(k + box.height, 0), c, 1, cv::LINE_AA);
    }
    lines.copyTo(roi, mask);
  }

  // ------------------------------------------------------------------ labels

  // Places a (multi-line) label near `anchor` (map pixels), avoiding earlier labels and marker
  // boxes; falls back to the first candidate inside the map.
  void placeLabel(const std::vector<std::string>& lines, cv::Point2d anchor, double gap,
                  double scale, int thickness, const cv::Scalar& color) {
    // Nothing to label when the feature itself lies outside the map.
    if (anchor.x < 0 || anchor.y < 0 || anchor.x >= img_.cols || anchor.y >= img_.rows) return;
    int w = 0, line_h = 0;
    for (const auto& s : lines) {
      int base = 0;
      const cv::Size ts = cv::getTextSize(s, kFont, scale, thickness, &base);
      w = std::max(w, ts.width);
      line_h = std::max(line_h, ts.height + base);
    }
    line_h += 2;
    const int h = line_h * static_cast<int>(lines.size());
    // Candidate offsets of the label's top-left corner: the four diagonal corners, above,
    // below and beside the anchor, first close, then further out.
    std::vector<cv::Point2d> offsets;
    for (double g : {gap, 2.5 * gap + 6.0, 4.0 * gap + 14.0}) {
      const cv::Point2d ring[] = {{g, -g - h},        {g, g},         {-g - w, -g - h},
                                  {-g - w, g},        {-0.5 * w, -g - h}, {-0.5 * w, g},
                                  {g, -0.5 * h},      {-g - w, -0.5 * h}};
      offsets.insert(offsets.end(), std::begin(ring), std::end(ring));
    }
    const cv::Rect bounds(0, 0, img_.cols, img_.rows);
    // The first candidate that overlaps nothing, else the one that overlaps least.
    std::optional<cv::Rect> chosen;
    int least = 0;
    for (const auto& o : offsets) {
      const cv::Rect r(static_cast<int>(std::lround(anchor.x + o.x)) - 2,
                       static_cast<int>(std::lround(anchor.y + o.y)) - 2, w + 4, h + 4);
      if ((r & bounds) != r) continue;
      int overlap = 0;
      for (const auto& q : occupied_) overlap += (q & r).area();
      if (!chosen || overlap < least) {
        chosen = r;
        least = overlap;
      }
      if (overlap == 0) break;
    }
    if (!chosen) return;  // the anchor is too close to the map edge for any placement
    occupied_.push_back(*chosen);
    // A pale box under the text keeps it readable over streets, hatching and prior numbers.
    cv::Mat box = img_(*chosen);
    cv::addWeighted(box, 1.0 - kLabelBoxAlpha, cv::Mat(box.size(), box.type(), kWhite),
                    kLabelBoxAlpha, 0.0, box);
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const int base_y = chosen->y + 2 + line_h * static_cast<int>(i + 1) - 4;
      cv::putText(img_, lines[i], cv::Point(chosen->x + 2, base_y), kFont, scale, color, thickness,
                  cv::LINE_AA);
    }
  }

  void reserve(const cv::Point2d& c, int half) {
    occupied_.emplace_back(static_cast<int>(std::lround(c.x)) - half,
                           static_cast<int>(std::lround(c.y)) - half, 2 * half + 1, 2 * half + 1);
  }

  // ------------------------------------------------------------------ layers

  void drawWorld(const scenario::World& world) {
    using scenario::EntityClass;
    const double ppm = frame_.px_per_m;
    // Plain (aliased) edges: at map scale they look the same and the PNG is half the size.
    const int lt = cv::LINE_8;
    for (const auto& b : world.blocks()) {
      fill(b.interior.vertices(), kLawn, nullptr, lt);
    }
    const int walk =
        std::max(1, static_cast<int>(std::lround(world.params().sidewalk_width * ppm)));
    for (const auto& b : world.blocks()) outline(b.sidewalk, false, kSidewalk, walk);
    const EntityClass order[] = {EntityClass::kStreet, EntityClass::kDriveway, EntityClass::kHouse,
                                 EntityClass::kGarage, EntityClass::kFence,    EntityClass::kCar,
                                 EntityClass::kTree};
    for (EntityClass cls : order) {
      for (const auto& e : world.entities()) {
        if (e.cls != cls || !visible(e.box.bounds2())) continue;
        const auto c = e.box.corners2();
        const std::vector<Vec2> poly(c.begin(), c.end());
        switch (cls) {
          case EntityClass::kStreet:
            fill(poly, kStreet, nullptr, lt);
            break;
          case EntityClass::kDriveway:
            fill(poly, kDriveway, nullptr, lt);
            break;
          case EntityClass::kHouse:
            fill(poly, kHouse, nullptr, lt);
            outline(poly, true, kHouseEdge, 1, lt);
            break;
          case EntityClass::kGarage:
            fill(poly, kGarage, nullptr, lt);
            outline(poly, true, kGarageEdge, 1, lt);
            break;
          case EntityClass::kFence: {
            const Vec2 u(std::cos(e.box.yaw), std::sin(e.box.yaw));
            const Vec2 a = e.box.center2() - 0.5 * e.box.size.x() * u;
            const Vec2 b = e.box.center2() + 0.5 * e.box.size.x() * u;
            cv::line(img_, fx(a), fx(b), kFence, 1, lt, kShift);
            break;
          }
          case EntityClass::kCar:
            fill(poly, kWorldCar, nullptr, lt);
            break;
          case EntityClass::kTree: {
            const int r = static_cast<int>(std::lround(0.5 * e.box.size.x() * ppm * kOne));
            cv::circle(img_, fx(e.box.center2()), r, kTree, cv::FILLED, lt, kShift);
            cv::circle(img_, fx(e.box.center2()), r, kTreeEdge, 1, lt, kShift);
            break;
          }
          default:
            break;
        }
      }
    }
  }

  void drawPriors(const MapData& d) {
    const double pmax = maxProbability(d);
    if (d.priors.empty() || pmax <= 0.0) return;
    std::vector<std::pair<const std::vector<Vec2>*, cv::Scalar>> cells;
    for (const auto& pr : d.priors) {
      for (const auto& c : pr.cells) cells.emplace_back(&c.polygon, heatColor(c.probability / pmax));
    }
    translucent(cells, kPriorAlpha);
    for (const auto& pr : d.priors) {
      for (const auto& c : pr.cells) outline(c.polygon, true, rgb(110, 140, 190), 1);
    }
    if (!style_.show_prior_text) return;
    for (const auto& pr : d.priors) {
      for (const auto& c : pr.cells) {
        const std::string s = fixed(c.probability, c.probability < 0.1 ? 3 : 2);
        int base = 0;
        const double scale = 0.4;
        const cv::Size ts = cv::getTextSize(s, kFont, scale, 1, &base);
        const Aabb2 b = geometry::Polygon(c.polygon).bounds();
        const double cw = (b.max.x() - b.min.x()) * frame_.px_per_m;
        const double ch = (b.max.y() - b.min.y()) * frame_.px_per_m;
        if (cw < ts.width + 10 || ch < ts.height + 10) continue;
        const cv::Point2d m = px(geometry::Polygon(c.polygon).centroid());
        const double u = c.probability / pmax;
        const cv::Scalar color = u > 0.55 ? kWhite : rgb(20, 40, 90);
        const cv::Point org(static_cast<int>(std::lround(m.x - 0.5 * ts.width)),
                            static_cast<int>(std::lround(m.y + 0.5 * ts.height)));
        cv::putText(img_, s, org, kFont, scale, color, 1, cv::LINE_AA);
        occupied_.emplace_back(org.x - 1, org.y - ts.height - 1, ts.width + 2,
                               ts.height + base + 2);
      }
    }
  }

  void drawAois(const MapData& d) {
    for (const auto& a : d.aois) outline(a.polygon, true, kAoi, 2);
  }

  void drawKozs(const MapData& d) {
    if (d.kozs.empty()) return;
    std::vector<std::pair<const std::vector<Vec2>*, cv::Scalar>> zones;
    for (const auto& k : d.kozs) zones.emplace_back(&k.polygon, kKozColor);
    translucent(zones, kKozAlpha);
    for (const auto& k : d.kozs) {
      hatch(k.polygon, kKozEdge, 9);
      if (k.window.net || k.window.nlt) dashed(k.polygon, true, kKozEdge, 2);
      else outline(k.polygon, true, kKozEdge, 2);
    }
  }

  void drawRoutes(const MapData& d) {
    if (d.routes.empty()) return;
    std::vector<std::pair<const std::vector<Vec2>*, cv::Scalar>> bands;
    for (const auto& r : d.routes) bands.emplace_back(&r.band, kRoute);
    translucent(bands, kBandAlpha);
    for (const auto& r : d.routes) {
      dashed(r.band, true, kRoute, 2);
      outline(r.polyline, false, kRoute, 7);
      arrowHead(r.polyline, kRoute, 20.0);
    }
  }

  // A filled arrow head at the end of a polyline, pointing along its last segment.
  void arrowHead(const std::vector<Vec2>& pts, const cv::Scalar& c, double size) {
    if (pts.size() < 2) return;
    const cv::Point2d tip = px(pts.back());
    cv::Point2d dir;
    for (std::size_t i = pts.size() - 1; i > 0; --i) {
      dir = tip - px(pts[i - 1]);
      if (std::hypot(dir.x, dir.y) > 1.0) break;
    }
    const double n = std::hypot(dir.x, dir.y);
    if (n <= 1e-9) return;
    dir *= 1.0 / n;
    const cv::Point2d side(-dir.y, dir.x);
    const cv::Point2d base = tip - dir * size;
    const std::vector<cv::Point> tri = {fx(tip + dir * 3.0), fx(base + side * (0.5 * size)),
                                        fx(base - side * (0.5 * size))};
    cv::fillConvexPoly(img_, tri, c, cv::LINE_AA, kShift);
  }

  void drawMovers(const MapData& d) {
    // Paths, bottom to top: traffic, pedestrians, vignette actors, confusers, targets.
    auto rank = [&](const MoverData& m) {
      if (isTarget(m, d)) return 4;
      if (m.role == "confuser") return 3;
      if (m.role == "traffic") return 0;
      if (m.role == "pedestrian") return 1;
      return 2;
    };
    for (int level = 0; level <= 4; ++level) {
      for (const auto& m : d.entities) {
        if (rank(m) != level || m.path.size() < 2) continue;
        if (level < 4 && !style_.show_trajectories) continue;
        std::vector<Vec2> path = m.path;
        path.insert(path.begin(), m.position);
        switch (level) {
          case 0:
            outline(path, false, kTraffic, 1);
            break;
          case 1:
            outline(path, false, kPedestrian, 1);
            break;
          case 2:
            outline(path, false, kVignette, 1);
            break;
          case 3:
            outline(path, false, kConfuserColor, 2);
            break;
          default:
            outline(path, false, kTargetColor, 3);
            break;
        }
      }
    }
    // Bodies of the non-target movers at t = 0.
    for (const auto& m : d.entities) {
      const int level = rank(m);
      if (level >= 3) continue;
      if (m.cls == "car") {
        const auto poly = geometry::orientedRectangle(m.position, m.length, m.width, m.yaw);
        fill(poly.vertices(), level == 0 ? kTraffic : kVignette);
      } else {
        const cv::Scalar c = level == 1 ? kPedestrian : level == 2 ? kVignette : kTraffic;
        cv::circle(img_, fx(m.position), static_cast<int>((level == 2 ? 3 : 2) * kOne), c,
                   cv::FILLED, cv::LINE_AA, kShift);
      }
    }
    // Target time ticks and path ends.
    for (const auto& m : d.entities) {
      if (!isTarget(m, d) || m.path.size() < 2) continue;
      for (double t = kTickSeconds; t < m.times.back(); t += kTickSeconds) {
        cv::circle(img_, fx(pathAt(m, t)), static_cast<int>(2.5 * kOne), kWhite, cv::FILLED,
                   cv::LINE_AA, kShift);
      }
      cv::circle(img_, fx(m.path.back()), static_cast<int>(6 * kOne), kTargetColor, 2, cv::LINE_AA,
                 kShift);
    }
  }

  static Vec2 pathAt(const MoverData& m, double t) {
    if (t <= m.times.front()) return m.path.front();
    for (std::size_t i = 1; i < m.times.size(); ++i) {
      if (t <= m.times[i]) {
        const double span = m.times[i] - m.times[i - 1];
        const double u = span > 0 ? (t - m.times[i - 1]) / span : 1.0;
        return m.path[i - 1] + u * (m.path[i] - m.path[i - 1]);
      }
    }
    return m.path.back();
  }

  void drawMarkersAndLabels(const MapData& d) {
    // Markers.
    for (const auto& m : d.entities) {
      if (m.role != "confuser" || isTarget(m, d)) continue;
      const cv::Point2d c = px(m.position);
      confuserGlyph(img_, cv::Point(static_cast<int>(std::lround(c.x)),
                                                  static_cast<int>(std::lround(c.y))), 7);
      reserve(c, 9);
    }
    const cv::Point2d uav = px(d.uav_start);
    uavGlyph(img_, uav, d.uav_yaw, 13.0);
    reserve(uav, 13);
    for (int pass = 0; pass < 2; ++pass) {
      for (const auto& m : d.entities) {
        if (!isTarget(m, d)) continue;
        const cv::Point c = fx(m.position);
        if (pass == 0) {
          cv::circle(img_, c, static_cast<int>(12 * kOne), kBlack, cv::FILLED, cv::LINE_AA, kShift);
          cv::circle(img_, c, static_cast<int>(11 * kOne), kWhite, cv::FILLED, cv::LINE_AA, kShift);
        } else {
          cv::circle(img_, c, static_cast<int>(8 * kOne), kTargetColor, cv::FILLED, cv::LINE_AA,
                     kShift);
          reserve(px(m.position), 13);
        }
      }
    }
    for (const auto& k : d.kozs) reserve(px(geometry::Polygon(k.polygon).centroid()), 8);

    // Labels, most important first.
    for (const auto& m : d.entities) {
      if (isTarget(m, d)) placeLabel({m.id}, px(m.position), 12, 0.6, 2, kTargetDark);
    }
    placeLabel({"UAV start"}, uav, 12, 0.45, 1, kUav);
    for (const auto& m : d.entities) {
      if (m.role == "confuser" && !isTarget(m, d)) {
        placeLabel({m.id}, px(m.position), 8, 0.42, 1, kConfuserDark);
      }
    }
    for (const auto& k : d.kozs) {
      std::vector<std::string> lines = {k.id};
      const std::string w = windowText(k.window);
      if (!w.empty()) lines[0] += " " + w;
      const std::string alt = altitudeText(k);
      if (!alt.empty()) lines.push_back(alt);
      placeLabel(lines, topCorner(k.polygon), 4, 0.45, 1, kKozEdge);
    }
    for (const auto& a : d.aois) {
      std::string s = a.id;
      const std::string w = windowText(a.window);
      if (!w.empty()) s += " " + w;
      placeLabel({s}, topCorner(a.polygon), 4, 0.5, 1, kAoi);
    }
    for (const auto& r : d.routes) {
      placeLabel({r.id + " (start)"}, px(r.polyline.front()), 8, 0.5, 1, kRoute);
    }
  }

  // The top-left-most vertex in the image (north-west corner of the polygon).
  cv::Point2d topCorner(const std::vector<Vec2>& poly) const {
    cv::Point2d best = px(poly.front());
    for (const auto& p : poly) {
      const cv::Point2d q = px(p);
      if (q.y + q.x < best.y + best.x) best = q;
    }
    return best;
  }

 private:
  const MapFrame& frame_;
  const MapStyle& style_;
  cv::Mat img_;
  std::vector<cv::Rect> occupied_;
};

cv::Mat render(const scenario::World& world, const MapData& d, const MapStyle& style) {
  const Layout l = computeLayout(world, d, style);
  const MapFrame& f = l.frame;
  MapPainter painter(f, style);
  painter.drawWorld(world);
  painter.drawPriors(d);
  painter.drawAois(d);
  painter.drawRoutes(d);
  painter.drawKozs(d);
  painter.drawMovers(d);
  painter.drawMarkersAndLabels(d);

  cv::Mat img(f.image_size, CV_8UC3, kWhite);
  painter.image().copyTo(img(f.map_rect));
  cv::rectangle(img, f.map_rect, rgb(120, 120, 120), 1);
  l.panel.copyTo(img(cv::Rect(f.map_rect.width, f.map_rect.y, l.panel.cols, l.panel.rows)));
  // Title.
  int y = 6;
  for (const auto& line : l.title_bold) {
    y += kTitleStep;
    cv::putText(img, line, cv::Point(12, y), kBoldFont, kTitleScale, kText, 1, cv::LINE_AA);
  }
  for (const auto& line : l.title_lines) {
    y += kSubtitleStep;
    cv::putText(img, line, cv::Point(12, y), kFont, kSubtitleScale, kText, 1, cv::LINE_AA);
  }
  cv::line(img, cv::Point(0, f.map_rect.y - 1), cv::Point(img.cols - 1, f.map_rect.y - 1),
           rgb(120, 120, 120), 1);
  return img;
}

}  // namespace

void MapStyle::validate() const {
  auto check = [](bool ok, const char* field, double v, const char* expected) {
    if (!ok) {
      throw ConfigError(std::string("map style: ") + field + ": expected " + expected + ", got " +
                        std::to_string(v));
    }
  };
  check(std::isfinite(px_per_m) && px_per_m >= 0.05 && px_per_m <= 20.0, "px_per_m", px_per_m,
        "0.05 to 20");
  check(std::isfinite(margin_m) && margin_m >= 0.0 && margin_m <= 1000.0, "margin_m", margin_m,
        "0 to 1000");
  check(std::isfinite(interest_margin_m) && interest_margin_m >= 0.0 && interest_margin_m <= 1000.0,
        "interest_margin_m", interest_margin_m, "0 to 1000");
  check(std::isfinite(min_interest_size_m) && min_interest_size_m >= 10.0 &&
            min_interest_size_m <= 10000.0,
        "min_interest_size_m", min_interest_size_m, "10 to 10000");
  check(panel_width_px >= 240 && panel_width_px <= 1200, "panel_width_px", panel_width_px,
        "240 to 1200");
}

cv::Point2d MapFrame::toPixel(const geometry::Vec2& p) const {
  return {map_rect.x + (p.x() - region.min.x()) * px_per_m,
          map_rect.y + (region.max.y() - p.y()) * px_per_m};
}

cv::Point MapFrame::pixelAt(const geometry::Vec2& p) const {
  const cv::Point2d q = toPixel(p);
  return {static_cast<int>(std::lround(q.x)), static_cast<int>(std::lround(q.y))};
}

MapFrame computeMapFrame(const scenario::World& world, const nlohmann::json& mission,
                         const nlohmann::json& sim_config, const MapStyle& style) {
  const MapData d = parseDocuments(mission, sim_config, "mission.json", "sim_config.json");
  return computeLayout(world, d, style).frame;
}

cv::Mat drawScenarioMap(const scenario::World& world, const nlohmann::json& mission,
                        const nlohmann::json& sim_config, const MapStyle& style) {
  const MapData d = parseDocuments(mission, sim_config, "mission.json", "sim_config.json");
  return render(world, d, style);
}

void writeScenarioMap(const std::string& scenario_dir, const std::string& out_png,
                      const MapStyle& style) {
  using scenario::OutputError;
  const auto ends_with = [](const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() &&
           s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  if (!ends_with(out_png, ".png") && !ends_with(out_png, ".PNG")) {
    throw ConfigError(out_png + ": expected a .png output file name");
  }
  style.validate();
  const std::string mission_file = scenario_dir + "/mission.json";
  const std::string sim_file = scenario_dir + "/sim_config.json";
  const json mission = scenario::readJsonFile(mission_file);
  const json sim = scenario::readJsonFile(sim_file);

  const DocReader sr(sim_file);
  const json& world_j = sr.at(sim, "", "world");
  const std::string fingerprint = sr.stringAt(world_j, "world", "fingerprint");
  const scenario::WorldParams params =
      scenario::worldParamsFromJson(sr.at(world_j, "world", "params"), sim_file);
  const MapData d = parseDocuments(mission, sim, mission_file, sim_file);
  const scenario::World world = scenario::generateWorld(params);
  const std::string actual = scenario::hex64(world.fingerprint());
  if (actual != fingerprint) {
    sr.fail("world.fingerprint", "'" + fingerprint + "' does not match the world regenerated "
                                 "from world.params (" + actual + ")");
  }
  const cv::Mat img = render(world, d, style);

  std::vector<unsigned char> png;
  if (!cv::imencode(".png", img, png, {cv::IMWRITE_PNG_COMPRESSION, 9})) {
    throw OutputError(out_png + ": PNG encoding failed");
  }
  const std::string tmp = out_png + ".tmp." + std::to_string(::getpid());
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw OutputError(out_png + ": cannot write: " + std::strerror(errno));
  const bool ok = std::fwrite(png.data(), 1, png.size(), f) == png.size();
  const int write_errno = errno;
  if (std::fclose(f) != 0 || !ok) {
    const int err = ok ? errno : write_errno;
    std::remove(tmp.c_str());
    throw OutputError(out_png + ": write failed: " + std::strerror(err));
  }
  if (std::rename(tmp.c_str(), out_png.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    throw OutputError(out_png + ": cannot move into place: " + std::strerror(err));
  }
}

}  // namespace hameritt::map
