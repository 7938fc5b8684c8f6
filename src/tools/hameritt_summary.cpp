// hameritt_summary: a human-readable summary of a scenario directory (mission.json and
// sim_config.json): objective, constraints, relations, entities and environment.
//   hameritt_summary SCENARIO_DIR
// Exit codes: 0 success, 2 unreadable or malformed input.

#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/params_table.h"

using nlohmann::json;
using hameritt::scenario::ConfigError;

namespace {

std::string window(const json& w) {
  std::string s;
  if (w.contains("net")) s += "NET " + w["net"].dump() + " s";
  if (w.contains("nlt")) s += std::string(s.empty() ? "" : ", ") + "NLT " + w["nlt"].dump() + " s";
  return s.empty() ? "always" : s;
}

void summarize(const std::string& dir) {
  const json m = hameritt::scenario::readJsonFile(dir + "/mission.json");
  const json s = hameritt::scenario::readJsonFile(dir + "/sim_config.json");
  std::printf("scenario   %s (%s, seed %s)\n", m.at("scenario_id").get<std::string>().c_str(),
              m.at("class").get<std::string>().c_str(), m.at("seed").dump().c_str());
  std::printf("objective  %s\n", m.at("objective").at("text").get<std::string>().c_str());
  std::printf("time limit %s s\n", m.at("time_limit").dump().c_str());
  for (const auto& a : m.at("areas_of_interest")) {
    std::printf("AOI        %s, %zu vertices, %s\n", a.at("id").get<std::string>().c_str(),
                a.at("polygon").size(), window(a.at("time_window")).c_str());
  }
  for (const auto& p : m.at("area_priors")) {
    double best = 0;
    std::string best_id;
    for (const auto& c : p.at("cells")) {
      if (c.at("probability").get<double>() > best) {
        best = c.at("probability").get<double>();
        best_id = c.at("id").get<std::string>();
      }
    }
    std::printf("prior      %s: %zu cells, highest %s (%.4f)\n", p.at("aoi_id").get<std::string>().c_str(),
                p.at("cells").size(), best_id.c_str(), best);
  }
  for (const auto& k : m.at("keep_out_zones")) {
    const auto& alt = k.at("altitude");
    std::printf("KOZ        %s (%s), altitude %s..%s m, %s\n", k.at("id").get<std::string>().c_str(),
                k.at("purpose").get<std::string>().c_str(),
                alt.contains("min") ? alt["min"].dump().c_str() : "-inf",
                alt.contains("max") ? alt["max"].dump().c_str() : "inf",
                window(k.at("time_window")).c_str());
  }
  for (const auto& r : m.at("routes")) {
    std::string streets;
    for (const auto& st : r.at("streets")) streets += (streets.empty() ? "" : ", ") + st.get<std::string>();
    std::printf("route      %s: %zu points along %s, band %s m\n", r.at("id").get<std::string>().c_str(),
                r.at("polyline").size(), streets.c_str(), r.at("band_width").dump().c_str());
  }
  for (const auto& r : m.at("scene_relations")) {
    std::printf("relation   %s\n", r.at("text").get<std::string>().c_str());
  }
  std::map<std::string, int> roles;
  for (const auto& e : s.at("entities")) roles[e.at("role").get<std::string>()]++;
  std::string counts;
  for (const auto& [role, n] : roles) counts += (counts.empty() ? "" : ", ") + std::to_string(n) + " " + role;
  std::printf("entities   %s\n", counts.c_str());
  const auto& env = s.at("environment");
  std::printf("weather    time %s h, snow %s, rain %s, dust %s, fog %s, foliage %s, wind %s m/s\n",
              env.at("time_of_day").dump().c_str(), env.at("snow").dump().c_str(),
              env.at("rain").dump().c_str(), env.at("dust").dump().c_str(), env.at("fog").dump().c_str(),
              env.at("foliage").dump().c_str(), env.at("wind").at("mean").dump().c_str());
  const auto& uav = s.at("uav");
  std::printf("uav        start (%s, %s), altitude %s..%s m, %zu cameras\n", uav.at("start").at("x").dump().c_str(),
              uav.at("start").at("y").dump().c_str(), uav.at("altitude").at("min").dump().c_str(),
              uav.at("altitude").at("max").dump().c_str(), uav.at("payload").at("cameras").size());
  if (uav.contains("perception_path")) {
    const auto& pp = uav.at("perception_path");
    const auto& traj = pp.at("trajectory");
    std::printf("perception %s path, %zu samples over %s s, sees %zu target(s)\n",
                pp.at("status").get<std::string>().c_str(), traj.size(),
                traj.empty() ? "0" : traj.back().at(0).dump().c_str(), pp.at("targets_seen").size());
  }
}

}  // namespace

int main(int argc, char** argv) {
  const char* usage = "usage: hameritt_summary SCENARIO_DIR\n";
  if (argc == 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::fputs(usage, stdout);
    return 0;
  }
  if (argc != 2) {
    std::fputs(usage, stderr);
    return 2;
  }
  try {
    summarize(argv[1]);
    return 0;
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "hameritt_summary: error: %s\n", e.what());
    return 2;
  } catch (const json::exception& e) {
    std::fprintf(stderr, "hameritt_summary: error: %s: unexpected content: %s\n", argv[1], e.what());
    return 2;
  }
}
