// MapPainter's layers: the world, priors, AOIs, keep-out zones, routes, movers and markers.
#include "map_internal.h"

namespace hameritt::map::map_internal {

void MapPainter::drawWorld(const scenario::World& world) {
  using scenario::EntityClass;
  const double ppm = frame_.px_per_m;
  // Plain (aliased) edges: at map scale they look the same and the PNG is half the size.
  const int lt = cv::LINE_8;
  for (const auto& b : world.blocks()) {
    fill(b.interior.vertices(), kLawn, nullptr, lt);
  }
  const int walk = std::max(1, static_cast<int>(std::lround(world.sidewalkWidth() * ppm)));
  for (const auto& b : world.blocks()) outline(b.sidewalk, false, kSidewalk, walk);
  // The suburb's classes first, in their order; the city's classes (absent from a suburb)
  // interleaved where they belong: surfaces under buildings, furniture on top.
  const EntityClass order[] = {
      EntityClass::kStreet,      EntityClass::kAlley,         EntityClass::kParkingLot,
      EntityClass::kDriveway,    EntityClass::kHouse,         EntityClass::kGarage,
      EntityClass::kBuilding,    EntityClass::kParkingGarage, EntityClass::kFence,
      EntityClass::kCar,         EntityClass::kTree,          EntityClass::kStreetTree,
      EntityClass::kBusStop,     EntityClass::kBench,         EntityClass::kLampPost,
      EntityClass::kTrafficLight};
  for (EntityClass cls : order) {
    for (const auto& e : world.entities()) {
      if (e.cls != cls || !visible(e.box.bounds2())) continue;
      const auto c = e.box.corners2();
      const std::vector<Vec2> poly(c.begin(), c.end());
      switch (cls) {
        case EntityClass::kStreet:
        case EntityClass::kAlley:
          fill(poly, kStreet, nullptr, lt);
          break;
        case EntityClass::kParkingLot:
          fill(poly, kDriveway, nullptr, lt);
          outline(poly, true, kGarageEdge, 1, lt);
          break;
        case EntityClass::kBuilding:
        case EntityClass::kParkingGarage: {
          // Darker with height: 1 at the ground, 0.45 at 150 m (towers stand out).
          const double k = 1.0 - 0.55 * std::min(1.0, e.box.size.z() / 150.0);
          const cv::Scalar base = cls == EntityClass::kBuilding ? kHouse : kGarage;
          fill(poly, base * k, nullptr, lt);
          outline(poly, true, cls == EntityClass::kBuilding ? kHouseEdge : kGarageEdge, 1, lt);
          break;
        }
        case EntityClass::kBusStop:
        case EntityClass::kBench:
          fill(poly, kFence, nullptr, lt);
          break;
        case EntityClass::kLampPost:
        case EntityClass::kTrafficLight: {
          const int r = static_cast<int>(std::lround(std::max(1.0, 0.6 * ppm) * kOne));
          cv::circle(img_, fx(e.box.center2()), r,
                     cls == EntityClass::kTrafficLight ? kKozEdge : kText, cv::FILLED, lt, kShift);
          break;
        }
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
        case EntityClass::kTree:
        case EntityClass::kStreetTree: {
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

void MapPainter::drawPriors(const MapData& d) {
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
      occupied_.emplace_back(org.x - 1, org.y - ts.height - 1, ts.width + 2, ts.height + base + 2);
    }
  }
}

void MapPainter::drawAois(const MapData& d) {
  for (const auto& a : d.aois) outline(a.polygon, true, kAoi, 2);
}

void MapPainter::drawKozs(const MapData& d) {
  if (d.kozs.empty()) return;
  std::vector<std::pair<const std::vector<Vec2>*, cv::Scalar>> zones;
  for (const auto& k : d.kozs) zones.emplace_back(&k.polygon, kKozColor);
  translucent(zones, kKozAlpha);
  for (const auto& k : d.kozs) {
    hatch(k.polygon, kKozEdge, 9);
    if (k.window.net || k.window.nlt)
      dashed(k.polygon, true, kKozEdge, 2);
    else
      outline(k.polygon, true, kKozEdge, 2);
  }
}

void MapPainter::drawRoutes(const MapData& d) {
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

void MapPainter::arrowHead(const std::vector<Vec2>& pts, const cv::Scalar& c, double size) {
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

void MapPainter::drawMovers(const MapData& d) {
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
          if (m.role == "aircraft") {
            outline(path, false, kAircraft, 2);
          } else {
            outline(path, false, kVignette, 1);
          }
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
    if (m.role == "aircraft") {
      cv::circle(img_, fx(m.position), static_cast<int>(4 * kOne), kAircraft, cv::FILLED,
                 cv::LINE_AA, kShift);
    } else if (m.cls == "car") {
      const auto poly = geometry::orientedRectangle(m.position, m.length, m.width, m.yaw);
      fill(poly.vertices(), level == 0 ? kTraffic : kVignette);
    } else {
      const cv::Scalar c = level == 1 ? kPedestrian : level == 2 ? kVignette : kTraffic;
      cv::circle(img_, fx(m.position), static_cast<int>((level == 2 ? 3 : 2) * kOne), c, cv::FILLED,
                 cv::LINE_AA, kShift);
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

Vec2 MapPainter::pathAt(const MoverData& m, double t) {
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

void MapPainter::drawMarkersAndLabels(const MapData& d) {
  // Markers.
  for (const auto& m : d.entities) {
    if (m.role != "confuser" || isTarget(m, d)) continue;
    const cv::Point2d c = px(m.position);
    confuserGlyph(
        img_, cv::Point(static_cast<int>(std::lround(c.x)), static_cast<int>(std::lround(c.y))), 7);
    reserve(c, 9);
  }
  if (d.goal) {
    const cv::Point c = fx(d.goal->position);
    const double r_px = std::max(4.0, d.goal->radius * frame_.px_per_m);
    cv::circle(img_, c, static_cast<int>(r_px * kOne), kGoal, 2, cv::LINE_AA, kShift);
    cv::circle(img_, c, static_cast<int>(2.5 * kOne), kGoal, cv::FILLED, cv::LINE_AA, kShift);
    reserve(px(d.goal->position), static_cast<int>(std::ceil(r_px)) + 2);
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
  if (d.goal) {
    placeLabel({d.goal->z > 0.0 ? "goal " + compact(d.goal->z) + " m up" : "landing goal"},
               px(d.goal->position), std::max(6.0, d.goal->radius * frame_.px_per_m) + 4, 0.45, 1,
               kGoal);
  }
  for (const auto& m : d.entities) {
    if (m.role == "aircraft") placeLabel({m.id}, px(m.position), 6, 0.4, 1, kAircraft);
  }
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

}  // namespace hameritt::map::map_internal
