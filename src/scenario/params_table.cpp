#include "hameritt/scenario/params_table.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "hameritt/scenario/bounded_json.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/share_dir.h"

namespace hameritt::scenario {

using nlohmann::json;

namespace {

struct WorldField {
  const char* key;
  double WorldParams::*member;
};
constexpr WorldField kWorldFields[] = {
    {"extent_x", &WorldParams::extent_x},
    {"extent_y", &WorldParams::extent_y},
    {"block_length_min", &WorldParams::block_length_min},
    {"block_length_max", &WorldParams::block_length_max},
    {"block_depth_min", &WorldParams::block_depth_min},
    {"block_depth_max", &WorldParams::block_depth_max},
    {"intersection_jitter", &WorldParams::intersection_jitter},
    {"street_width", &WorldParams::street_width},
    {"sidewalk_width", &WorldParams::sidewalk_width},
    {"lot_frontage_min", &WorldParams::lot_frontage_min},
    {"lot_frontage_max", &WorldParams::lot_frontage_max},
    {"lot_depth", &WorldParams::lot_depth},
    {"garage_probability", &WorldParams::garage_probability},
    {"two_door_garage_probability", &WorldParams::two_door_garage_probability},
    {"fence_probability", &WorldParams::fence_probability},
    {"trees_per_lot_max", &WorldParams::trees_per_lot_max},
    {"driveway_car_probability", &WorldParams::driveway_car_probability},
    {"street_parking_probability", &WorldParams::street_parking_probability},
    {"driveway_height", &WorldParams::driveway_height},
};

struct RangeField {
  const char* key;
  Range GeneratorConfig::*member;
};
constexpr RangeField kRangeFields[] = {
    {"time_limit_area_search", &GeneratorConfig::time_limit_area_search},
    {"time_limit_route_search", &GeneratorConfig::time_limit_route_search},
    {"time_limit_pursuit", &GeneratorConfig::time_limit_pursuit},
    {"aoi_length", &GeneratorConfig::aoi_length},
    {"aoi_width", &GeneratorConfig::aoi_width},
    {"car_speed", &GeneratorConfig::car_speed},
    {"pedestrian_speed", &GeneratorConfig::pedestrian_speed},
    {"runner_speed", &GeneratorConfig::runner_speed},
    {"band_width", &GeneratorConfig::band_width},
    {"depart_time", &GeneratorConfig::depart_time},
    {"track_depart_time", &GeneratorConfig::track_depart_time},
    {"uav_altitude_min", &GeneratorConfig::uav_altitude_min},
    {"uav_altitude_max", &GeneratorConfig::uav_altitude_max},
    {"time_of_day", &GeneratorConfig::time_of_day},
    {"foliage", &GeneratorConfig::foliage},
    {"wind_speed", &GeneratorConfig::wind_speed},
    {"gust_intensity", &GeneratorConfig::gust_intensity},
    {"front_pitch", &GeneratorConfig::front_pitch},
    {"front_hfov", &GeneratorConfig::front_hfov},
    {"down_hfov", &GeneratorConfig::down_hfov},
    {"noise_std", &GeneratorConfig::noise_std},
    {"salt_pepper", &GeneratorConfig::salt_pepper},
    {"motion_blur_px", &GeneratorConfig::motion_blur_px},
    {"follow_distance", &GeneratorConfig::follow_distance},
    {"follow_distance_tolerance", &GeneratorConfig::follow_distance_tolerance},
    {"follow_height", &GeneratorConfig::follow_height},
    {"follow_height_tolerance", &GeneratorConfig::follow_height_tolerance},
    {"follow_duration", &GeneratorConfig::follow_duration},
    {"track_duration", &GeneratorConfig::track_duration},
};

struct IntField {
  const char* key;
  int GeneratorConfig::*member;
};
constexpr IntField kIntFields[] = {
    {"aoi_count_min", &GeneratorConfig::aoi_count_min},
    {"aoi_count_max", &GeneratorConfig::aoi_count_max},
    {"prior_depth_min", &GeneratorConfig::prior_depth_min},
    {"prior_depth_max", &GeneratorConfig::prior_depth_max},
    {"koz_count_min", &GeneratorConfig::koz_count_min},
    {"koz_count_max", &GeneratorConfig::koz_count_max},
    {"confuser_count_min", &GeneratorConfig::confuser_count_min},
    {"confuser_count_max", &GeneratorConfig::confuser_count_max},
    {"traffic_count_min", &GeneratorConfig::traffic_count_min},
    {"traffic_count_max", &GeneratorConfig::traffic_count_max},
    {"pedestrian_count_min", &GeneratorConfig::pedestrian_count_min},
    {"pedestrian_count_max", &GeneratorConfig::pedestrian_count_max},
    {"route_edges_min", &GeneratorConfig::route_edges_min},
    {"route_edges_max", &GeneratorConfig::route_edges_max},
    {"camera_width", &GeneratorConfig::camera_width},
    {"camera_height", &GeneratorConfig::camera_height},
    {"track_targets_min", &GeneratorConfig::track_targets_min},
    {"track_targets_max", &GeneratorConfig::track_targets_max},
};

struct DoubleField {
  const char* key;
  double GeneratorConfig::*member;
};
constexpr DoubleField kDoubleFields[] = {
    {"aoi_window_probability", &GeneratorConfig::aoi_window_probability},
    {"uav_max_speed", &GeneratorConfig::uav_max_speed},
    {"weather_probability", &GeneratorConfig::weather_probability},
    {"camera_rate_hz", &GeneratorConfig::camera_rate_hz},
    {"track_min_visible_fraction", &GeneratorConfig::track_min_visible_fraction},
    {"track_min_box_area", &GeneratorConfig::track_min_box_area},
    {"track_min_tracked_fraction", &GeneratorConfig::track_min_tracked_fraction},
    {"track_max_reacquire_s", &GeneratorConfig::track_max_reacquire_s},
};

struct RelationField {
  const char* key;
  double RelationConfig::*member;
};
constexpr RelationField kRelationFields[] = {
    {"next_to_distance", &RelationConfig::next_to_distance},
    {"radius", &RelationConfig::radius},
    {"bearing_tolerance_deg", &RelationConfig::bearing_tolerance_deg},
    {"on_top_tolerance", &RelationConfig::on_top_tolerance},
    {"eventually_dt", &RelationConfig::eventually_dt},
};

// Strict object reader: every key must be known and every known key present.
class ObjectReader {
 public:
  ObjectReader(const json& j, std::string where) : j_(j), where_(std::move(where)) {
    if (!j_.is_object()) throw ConfigError(where_ + ": expected an object, got " + j_.type_name());
  }
  // True when the (optional) key is present; marks it as known.
  bool has(const std::string& key) {
    seen_.insert(key);
    return j_.contains(key);
  }
  const json& at(const std::string& key) {
    seen_.insert(key);
    if (!j_.contains(key)) throw ConfigError(where_ + "." + key + ": missing required key");
    return j_.at(key);
  }
  double number(const std::string& key) {
    const json& v = at(key);
    if (!v.is_number()) {
      throw ConfigError(where_ + "." + key + ": expected a number, got " + v.type_name() + " " + v.dump());
    }
    return v.get<double>();
  }
  long integer(const std::string& key) {
    const json& v = at(key);
    if (!v.is_number_integer()) {
      throw ConfigError(where_ + "." + key + ": expected an integer, got " + v.type_name() + " " + v.dump());
    }
    return v.get<long>();
  }
  std::uint64_t unsignedInteger(const std::string& key) {
    const json& v = at(key);
    if (!v.is_number_unsigned()) {
      throw ConfigError(where_ + "." + key + ": expected a non-negative integer, got " + v.dump());
    }
    return v.get<std::uint64_t>();
  }
  bool boolean(const std::string& key) {
    const json& v = at(key);
    if (!v.is_boolean()) {
      throw ConfigError(where_ + "." + key + ": expected true or false, got " + v.type_name() +
                        " " + v.dump());
    }
    return v.get<bool>();
  }
  Range range(const std::string& key) {
    const json& v = at(key);
    if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number()) {
      throw ConfigError(where_ + "." + key + ": expected [min, max] (two numbers), got " + v.dump());
    }
    return {v[0].get<double>(), v[1].get<double>()};
  }
  void finish() const {
    for (auto it = j_.begin(); it != j_.end(); ++it) {
      if (!seen_.count(it.key())) {
        throw ConfigError(where_ + "." + it.key() + ": unknown key");
      }
    }
  }
  const std::string& where() const { return where_; }

 private:
  const json& j_;
  std::string where_;
  std::set<std::string> seen_;
};

}  // namespace

void writeWorldParams(JsonWriter& w, const WorldParams& p) {
  w.beginObject();
  w.key("seed").value(p.seed);
  // The suburb (the default type) writes no "type" and no "city" key.
  if (p.type != WorldType::kSuburb) w.key("type").value(std::string(toString(p.type)));
  for (const auto& f : kWorldFields) w.key(f.key).value(p.*(f.member));
  if (p.type == WorldType::kCity) {
    w.key("city").beginObject();
    for (const auto& f : cityFieldTable()) w.key(f.key).value(p.city.*(f.member));
    w.endObject();
  }
  w.endObject();
}

WorldParams worldParamsFromJson(const json& j, const std::string& file) {
  ObjectReader r(j, file + ": world");
  WorldParams p;
  p.seed = r.unsignedInteger("seed");
  if (r.has("type")) {
    const json& t = r.at("type");
    if (!t.is_string() || !parseWorldType(t.get<std::string>(), &p.type)) {
      throw ConfigError(r.where() + ".type: expected \"suburb\" or \"city\", got " + t.dump());
    }
  }
  for (const auto& f : kWorldFields) p.*(f.member) = r.number(f.key);
  if (r.has("city")) {
    if (p.type != WorldType::kCity) {
      throw ConfigError(r.where() + ".city: only allowed with \"type\": \"city\"");
    }
    // Every city key is optional: a missing one keeps its default.
    ObjectReader c(r.at("city"), r.where() + ".city");
    for (const auto& f : cityFieldTable()) {
      if (c.has(f.key)) p.city.*(f.member) = c.number(f.key);
    }
    c.finish();
  }
  r.finish();
  try {
    p.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(file + ": " + e.what());
  }
  return p;
}

void writeGeneratorConfig(JsonWriter& w, const GeneratorConfig& c) {
  w.beginObject();
  w.key("origin").beginObject();
  w.key("latitude").value(c.origin.latitude).key("longitude").value(c.origin.longitude);
  w.key("altitude").value(c.origin.altitude).endObject();
  w.key("relations").beginObject();
  for (const auto& f : kRelationFields) w.key(f.key).value(c.relations.*(f.member));
  w.key("max_relations").value(c.relations.max_relations);
  w.endObject();
  for (const auto& f : kRangeFields) w.key(f.key).numbers({(c.*(f.member)).min, (c.*(f.member)).max});
  for (const auto& f : kIntFields) w.key(f.key).value(c.*(f.member));
  for (const auto& f : kDoubleFields) w.key(f.key).value(c.*(f.member));
  w.endObject();
}

GeneratorConfig generatorConfigFromJson(const json& j, const std::string& file) {
  const std::string where = file + ": generator";
  ObjectReader r(j, where);
  GeneratorConfig c;
  {
    ObjectReader o(r.at("origin"), where + ".origin");
    c.origin.latitude = o.number("latitude");
    c.origin.longitude = o.number("longitude");
    c.origin.altitude = o.number("altitude");
    o.finish();
  }
  {
    ObjectReader o(r.at("relations"), where + ".relations");
    for (const auto& f : kRelationFields) c.relations.*(f.member) = o.number(f.key);
    c.relations.max_relations = static_cast<int>(o.integer("max_relations"));
    o.finish();
  }
  for (const auto& f : kRangeFields) c.*(f.member) = r.range(f.key);
  for (const auto& f : kIntFields) c.*(f.member) = static_cast<int>(r.integer(f.key));
  for (const auto& f : kDoubleFields) c.*(f.member) = r.number(f.key);
  c.perception_paths = r.boolean("perception_paths");
  r.finish();
  try {
    c.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(file + ": " + e.what());
  }
  return c;
}

void GeneratorConfig::validate() const {
  relations.validate();
  if (!(origin.latitude >= -90 && origin.latitude <= 90)) {
    throw ConfigError("generator.origin.latitude: expected -90..90, got " + std::to_string(origin.latitude));
  }
  if (!(origin.longitude >= -180 && origin.longitude <= 180)) {
    throw ConfigError("generator.origin.longitude: expected -180..180, got " + std::to_string(origin.longitude));
  }
  for (const auto& f : kRangeFields) {
    const Range& r = this->*(f.member);
    if (!(std::isfinite(r.min) && std::isfinite(r.max) && r.min <= r.max && r.min >= 0)) {
      std::ostringstream os;
      os << "generator." << f.key << ": expected [min, max] with 0 <= min <= max, got [" << r.min
         << ", " << r.max << "]";
      throw ConfigError(os.str());
    }
  }
  for (std::size_t i = 0; i + 1 < std::size(kIntFields); i += 2) {
    const int lo = this->*(kIntFields[i].member), hi = this->*(kIntFields[i + 1].member);
    const std::string k = kIntFields[i].key;
    if (k.size() > 4 && k.compare(k.size() - 4, 4, "_min") == 0 && (lo < 0 || lo > hi)) {
      throw ConfigError("generator." + k + " / " + kIntFields[i + 1].key +
                        ": expected 0 <= min <= max, got " + std::to_string(lo) + " and " +
                        std::to_string(hi));
    }
  }
  if (aoi_count_min < 1) throw ConfigError("generator.aoi_count_min: expected at least 1, got " + std::to_string(aoi_count_min));
  if (prior_depth_min < 1 || prior_depth_max > 4) {
    throw ConfigError("generator.prior_depth_min/prior_depth_max: expected 1 <= min <= max <= 4 "
                      "(2x2 to 16x16 sub-quadrants)");
  }
  if (route_edges_min < 2) throw ConfigError("generator.route_edges_min: expected at least 2, got " + std::to_string(route_edges_min));
  if (confuser_count_max > 16 || traffic_count_max > 48 || pedestrian_count_max > 40) {
    throw ConfigError("generator: confuser_count_max <= 16, traffic_count_max <= 48 and "
                      "pedestrian_count_max <= 40 are expected");
  }
  if (camera_width < 16 || camera_height < 16 || camera_width > 8192 || camera_height > 8192) {
    throw ConfigError("generator.camera_width/camera_height: expected 16..8192");
  }
  if (!(camera_rate_hz > 0 && camera_rate_hz <= 1000)) {
    throw ConfigError("generator.camera_rate_hz: expected (0, 1000], got " + std::to_string(camera_rate_hz));
  }
  if (!(uav_max_speed > 0 && uav_max_speed <= 40)) {
    throw ConfigError("generator.uav_max_speed: expected (0, 40], got " + std::to_string(uav_max_speed));
  }
  for (double p : {aoi_window_probability, weather_probability}) {
    if (!(p >= 0 && p <= 1)) throw ConfigError("generator.aoi_window_probability/weather_probability: expected a probability in [0, 1]");
  }
  if (car_speed.min <= 0 || pedestrian_speed.min <= 0 || runner_speed.min <= 0) {
    throw ConfigError("generator.car_speed/pedestrian_speed/runner_speed: expected positive speeds");
  }
  if (time_of_day.max > 24) throw ConfigError("generator.time_of_day: expected hours within [0, 24]");
  if (foliage.max > 1 || gust_intensity.max > 1) throw ConfigError("generator.foliage/gust_intensity: expected values within [0, 1]");
  if (front_hfov.min <= 0 || front_hfov.max >= 180 || down_hfov.min <= 0 || down_hfov.max >= 180) {
    throw ConfigError("generator.front_hfov/down_hfov: expected degrees within (0, 180)");
  }
  if (aoi_length.min < 40 || aoi_width.min < 40) throw ConfigError("generator.aoi_length/aoi_width: expected at least 40 m");
  if (band_width.min < 20) throw ConfigError("generator.band_width: expected at least 20 m so the band covers the street and kerbs");
  if (time_limit_area_search.min < 60 || time_limit_route_search.min < 60 || time_limit_pursuit.min < 60) {
    throw ConfigError("generator.time_limit_*: expected at least 60 s");
  }
  if (follow_distance_tolerance.min <= 0 || follow_height_tolerance.min <= 0 ||
      follow_duration.min < 10) {
    throw ConfigError(
        "generator.follow_distance_tolerance/follow_height_tolerance/follow_duration: expected "
        "positive tolerances and a duration of at least 10 s");
  }
  if (2 * follow_height_tolerance.max > uav_altitude_max.min - uav_altitude_min.max) {
    throw ConfigError(
        "generator.follow_height_tolerance: expected twice the largest tolerance to fit the "
        "narrowest altitude band (uav_altitude_max.min - uav_altitude_min.max)");
  }
  if (track_targets_min < 1 || track_targets_max > 2 || track_targets_min > track_targets_max) {
    throw ConfigError(
        "generator.track_targets_min/track_targets_max: expected 1 <= min <= max <= 2, got " +
        std::to_string(track_targets_min) + " and " + std::to_string(track_targets_max));
  }
  if (track_duration.min < 10) {
    throw ConfigError("generator.track_duration: expected a duration of at least 10 s");
  }
  if (!(track_min_visible_fraction >= 0 && track_min_visible_fraction <= 1) ||
      !(track_min_tracked_fraction >= 0 && track_min_tracked_fraction <= 1) ||
      !(track_min_box_area >= 0) || !(track_max_reacquire_s >= 0)) {
    throw ConfigError(
        "generator.track_min_visible_fraction/track_min_tracked_fraction: expected fractions in "
        "[0, 1]; track_min_box_area/track_max_reacquire_s: expected numbers >= 0");
  }
  if (depart_time.min < 10 || depart_time.max > time_limit_pursuit.min - 30) {
    throw ConfigError("generator.depart_time: expected 10 s to time_limit_pursuit.min - 30 s");
  }
  if (track_depart_time.min < 10 || track_depart_time.max > time_limit_pursuit.min - 30) {
    throw ConfigError(
        "generator.track_depart_time: expected 10 s to time_limit_pursuit.min - 30 s");
  }
}

json parseJsonString(const std::string& text, const std::string& file) {
  checkJsonText(text, file);
  try {
    return json::parse(text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for a number beyond a double
    throw ConfigError(file + ": malformed JSON: " + e.what());
  }
}

json readJsonFile(const std::string& path) {
  return parseJsonString(readBoundedFile(path), path);
}

WorldParams loadWorldParams(const std::string& path) {
  return worldParamsFromJson(readJsonFile(path), path);
}

GeneratorConfig loadGeneratorConfig(const std::string& path) {
  return generatorConfigFromJson(readJsonFile(path), path);
}

std::string defaultConfigDir() {
  if (const char* env = std::getenv("HAMERITT_CONFIG_DIR")) return env;
  return shareDir() + "/config";
}

}  // namespace hameritt::scenario
