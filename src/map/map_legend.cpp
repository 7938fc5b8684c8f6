// The page layout: the map region, the title and the legend and mission panel.
#include "map_internal.h"

namespace hameritt::map::map_internal {

namespace {

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
  if (d.goal) {
    const Vec2 r(d.goal->radius, d.goal->radius);
    in.add(d.goal->position - r);
    in.add(d.goal->position + r);
  }
  for (const auto& m : d.entities) {
    if (m.role == "aircraft") in.add(m.path);
  }
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
      if (k.window.net || k.window.nlt)
        bounded = true;
      else
        unbounded = true;
    }
    if (unbounded) {
      entry("Keep-out zone (KOZ)", [&](const cv::Rect& b) { kozSwatch(b, false); });
    }
    if (bounded) {
      entry("KOZ active only in [t window]", [&](const cv::Rect& b) { kozSwatch(b, true); });
    }
    if (d_.goal) {
      entry("Goal and its radius", [&](const cv::Rect& b) {
        const cv::Point c(b.x + 14, b.y + 7);
        cv::circle(img_, c, 7, kGoal, 2, cv::LINE_AA);
        cv::circle(img_, c, 2, kGoal, cv::FILLED, cv::LINE_AA);
      });
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
    bool aircraft = false, hostile = false;
    for (const auto& m : d_.entities) {
      if (isTarget(m, d_)) continue;
      if (m.role == "aircraft")
        aircraft = true;
      else if (m.role == "hostile")
        hostile = true;
      else if (m.role == "confuser")
        has[0] = true;
      else if (m.role == "traffic")
        has[1] = true;
      else if (m.role == "pedestrian")
        has[2] = true;
      else
        has[3] = true;
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
      entry("Confuser (look-alike)",
            [&](const cv::Rect& b) { confuserGlyph(img_, cv::Point(b.x + 14, b.y + 7), 6); });
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
    if (hostile) {
      entry("Hostile vehicle (its KOZ moves with it)", [&](const cv::Rect& b) {
        cv::line(img_, cv::Point(b.x, b.y + 7), cv::Point(b.x + b.width, b.y + 7), kVignette, 1,
                 cv::LINE_AA);
        cv::rectangle(img_, cv::Rect(b.x + 10, b.y + 5, 8, 4), kVignette, cv::FILLED);
      });
    }
    if (aircraft) {
      entry("Other aircraft (t = 0) and its path", [&](const cv::Rect& b) {
        cv::line(img_, cv::Point(b.x, b.y + 7), cv::Point(b.x + b.width, b.y + 7), kAircraft, 2,
                 cv::LINE_AA);
        cv::circle(img_, cv::Point(b.x + 14, b.y + 7), 4, kAircraft, cv::FILLED, cv::LINE_AA);
      });
    }
    entry("UAV start (heading)",
          [&](const cv::Rect& b) { uavGlyph(img_, cv::Point2d(b.x + 14, b.y + 7), 0.0, 8.0); });
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

}  // namespace

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

}  // namespace hameritt::map::map_internal
