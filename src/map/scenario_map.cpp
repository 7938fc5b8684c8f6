// The public map functions: style checks, the map frame, drawing and writing the PNG file.
#include "hameritt/map/scenario_map.h"

#include "map_internal.h"

namespace hameritt::map {

namespace {

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
    sr.fail("world.fingerprint", "'" + fingerprint +
                                     "' does not match the world regenerated "
                                     "from world.params (" +
                                     actual + ")");
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
