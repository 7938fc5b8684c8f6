// hameritt_check_path: checks a timed UAV path against a mission's keep-out zones, exactly
// (the path between samples is the straight segment with linear time), and reports the time
// spent in each area of interest.
//   hameritt_check_path --mission mission.json --path path.csv [--out report.json]
// Prints the JSON report on stdout (and writes it atomically to --out).
// Exit codes: 0 no violation, 3 at least one violation, 2 bad arguments or input (nothing
// written).

#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "hameritt/adk/constraint_monitor.h"
#include "hameritt/adk/path_csv.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/scenario_io.h"

namespace {

constexpr const char* kUsage =
    "usage: hameritt_check_path --mission mission.json --path path.csv [--out report.json]\n";

struct Args {
  std::string mission, path, out;
};

Args parseArgs(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (k == "--help" || k == "-h") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    }
    std::string* dst = nullptr;
    if (k == "--mission") {
      dst = &a.mission;
    } else if (k == "--path") {
      dst = &a.path;
    } else if (k == "--out") {
      dst = &a.out;
    } else {
      throw hameritt::scenario::ConfigError("unknown argument '" + k + "'");
    }
    if (i + 1 >= argc) throw hameritt::scenario::ConfigError(k + ": expected a value");
    *dst = argv[++i];
  }
  if (a.mission.empty()) throw hameritt::scenario::ConfigError("--mission is required");
  if (a.path.empty()) throw hameritt::scenario::ConfigError("--path is required");
  return a;
}

}  // namespace

int main(int argc, char** argv) {
  using hameritt::adk::ConstraintMonitor;
  using nlohmann::ordered_json;
  Args args;
  try {
    args = parseArgs(argc, argv);
  } catch (const hameritt::scenario::ConfigError& e) {
    std::fprintf(stderr, "hameritt_check_path: %s\n%s", e.what(), kUsage);
    return 2;
  }
  try {
    const hameritt::scenario::Mission mission = hameritt::scenario::loadMission(args.mission);
    const std::vector<hameritt::adk::PathSample> path = hameritt::adk::readPathCsv(args.path);
    ConstraintMonitor monitor(mission);
    for (std::size_t i = 0; i < path.size(); ++i) {
      try {
        monitor.add(path[i].t, path[i].p);
      } catch (const hameritt::adk::InputError& e) {
        throw hameritt::scenario::ConfigError(args.path + ": " + e.what());
      }
    }
    ordered_json r;
    r["mission"] = mission.scenario_id;
    r["mission_file"] = args.mission;
    r["path_file"] = args.path;
    r["samples"] = path.size();
    r["t_start"] = path.front().t;
    r["t_end"] = path.back().t;
    r["duration"] = path.back().t - path.front().t;
    ordered_json list = ordered_json::array();
    for (const auto& v : monitor.violations()) {
      ordered_json o;
      o["zone"] = v.zone_id;
      o["purpose"] = v.purpose;
      o["t_enter"] = v.t_enter;
      o["t_exit"] = v.t_exit;
      o["duration"] = v.duration();
      list.push_back(o);
    }
    r["violations"] = list;
    r["violation_count"] = monitor.violationCount();
    r["violation_duration"] = monitor.violationDuration();
    ordered_json aoi = ordered_json::array();
    for (const auto& a : monitor.areas()) {
      ordered_json o;
      o["id"] = a.id;
      o["time_inside"] = a.time_inside;
      o["time_inside_active"] = a.time_inside_active;
      o["entries"] = a.entries;
      aoi.push_back(o);
    }
    r["aoi_time"] = aoi;
    const std::string text = r.dump(2) + "\n";
    if (!args.out.empty()) hameritt::scenario::writeFileAtomic(args.out, text);
    std::fputs(text.c_str(), stdout);
    return monitor.violationCount() > 0 ? 3 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hameritt_check_path: %s\n", e.what());
    return 2;
  }
}
