#include "hameritt/generation/batch.h"

#include <malloc.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <exception>
#include <filesystem>
#include <mutex>
#include <set>
#include <thread>

#include "hameritt/scenario/city_traffic.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/json_writer.h"
#include "hameritt/scenario/scenario_io.h"

namespace hameritt::scenario {

namespace fs = std::filesystem;

std::vector<ScenarioClass> parseClassList(const std::string& s) {
  if (s == "all") {
    return {ScenarioClass::kAreaSearch, ScenarioClass::kRouteSearch, ScenarioClass::kPursuit};
  }
  std::vector<ScenarioClass> out;
  std::size_t start = 0;
  while (start <= s.size()) {
    const std::size_t comma = s.find(',', start);
    const std::string name =
        s.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    ScenarioClass c;
    if (!parseScenarioClass(name, &c)) {
      throw ConfigError(
          "--class: expected area_search, route_search, pursuit, avoid, follow, track, all or a "
          "comma-separated list of them, got '" +
          name + "'");
    }
    out.push_back(c);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

namespace {

std::string manifestJson(const World& world, const BatchRequest& req,
                         const std::vector<ManifestEntry>& entries) {
  JsonWriter w;
  w.beginObject();
  w.key("schema").value("hameritt/manifest");
  w.key("schema_version").value(kSchemaVersion);
  w.key("seed").value(req.seed);
  w.key("count").value(req.count);
  if (req.first != 0) w.key("first").value(req.first);
  w.key("classes").beginArray();
  if (req.spec) w.value(toString(req.spec->spec().cls));
  for (auto c : req.classes) w.value(toString(c));
  w.endArray();
  w.key("world").beginObject();
  w.key("fingerprint").value(hex64(world.fingerprint()));
  w.key("file").value(req.write_world ? "world.json" : "");
  w.endObject();
  w.key("scenarios").beginArray();
  for (const auto& e : entries) {
    w.beginObject();
    w.key("index").value(e.index).key("id").value(e.id).key("class").value(toString(e.cls));
    w.key("seed").value(e.seed).key("path").value(e.id);
    w.endObject();
  }
  w.endArray();
  w.endObject();
  return w.take();
}

}  // namespace

std::vector<ManifestEntry> generateBatch(const World& world, const GeneratorConfig& config,
                                         const BatchRequest& req) {
  if (req.classes.empty() && !req.spec)
    throw ConfigError("--class: at least one scenario class is required");
  if (req.count < 1)
    throw ConfigError("--count: expected a positive number of scenarios, got " +
                      std::to_string(req.count));
  if (req.jobs < 1)
    throw ConfigError("--jobs: expected at least 1, got " + std::to_string(req.jobs));
  if (req.out_dir.empty()) throw ConfigError("--out: an output directory is required");
  if (req.first < 0) {
    throw ConfigError("--first: expected a non-negative index, got " + std::to_string(req.first));
  }
  if (req.exact_seed && req.first != 0) {
    throw ConfigError("--first: cannot be combined with --scenario-seed");
  }
  if (req.exact_seed && req.count != 1) {
    throw ConfigError("--scenario-seed: generates exactly one scenario; --count must be 1");
  }
  std::error_code ec;
  fs::create_directories(req.out_dir, ec);
  if (ec || !fs::is_directory(req.out_dir)) {
    throw OutputError(req.out_dir + ": cannot create output directory: " +
                      (ec ? ec.message() : std::string("not a directory")));
  }
  if (::access(req.out_dir.c_str(), W_OK) != 0) {
    throw OutputError(req.out_dir + ": output directory is not writable: " + std::strerror(errno));
  }

  std::vector<ManifestEntry> entries(static_cast<std::size_t>(req.count));
  std::vector<char> written(entries.size(), 0);
  std::atomic<int> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  int error_index = -1;
  std::mutex mu;
  // Traffic episode files: each written once, by the first scenario that uses it.
  std::mutex episode_mu;
  std::set<int> episodes_done;
  std::vector<std::string> episodes_created;  // removed again on failure
  auto writeEpisode = [&](const TrafficEpisodeRef& ref) {
    std::lock_guard<std::mutex> lock(episode_mu);
    if (!episodes_done.insert(ref.episode).second) return;
    const std::string path = req.out_dir + "/" + trafficEpisodeFileName(ref.episode);
    if (!fs::exists(path)) episodes_created.push_back(path);
    writeFileAtomic(path, *ref.text);
  };
  // The city's traffic episodes that the batch's scenarios draw, simulated first by every job
  // side by side: each is simulated once per process, and a scenario that draws one still being
  // simulated waits for it, which left the other job idle at a batch's start. (A scenario longer
  // than half an episode draws one and simulates its own cars instead.)
  std::vector<int> episodes;
  if (world.params().type == WorldType::kCity) {
    std::vector<char> drawn(static_cast<std::size_t>(world.params().city.traffic_episodes), 0);
    for (int i = 0; i < req.count; ++i) {
      const std::uint64_t seed =
          req.exact_seed ? req.seed : batchSeed(req.seed, static_cast<std::uint64_t>(req.first + i));
      drawn.at(static_cast<std::size_t>(cityScenarioEpisode(world, seed))) = 1;
    }
    for (std::size_t k = 0; k < drawn.size(); ++k) {
      if (drawn[k]) episodes.push_back(static_cast<int>(k));
    }
  }
  std::atomic<std::size_t> next_episode{0};
  auto work = [&]() {
    for (std::size_t k; (k = next_episode.fetch_add(1)) < episodes.size();) {
      try {
        cityTrafficEpisode(world, episodes[k]);
      } catch (...) {
        // Not simulated: the first scenario that draws it tries again and reports the error.
      }
    }
    for (;;) {
      const int i = next.fetch_add(1);
      if (i >= req.count || failed.load()) return;
      try {
        ManifestEntry& e = entries[static_cast<std::size_t>(i)];
        const int index = req.first + i;  // index in the whole batch
        e.index = index;
        if (!req.spec) e.cls = req.classes[static_cast<std::size_t>(index) % req.classes.size()];
        e.seed = req.exact_seed ? req.seed : batchSeed(req.seed, static_cast<std::uint64_t>(index));
        Scenario s;
        // Written by reference, a city scenario's shared traffic needs no trajectories in
        // memory; a check of the whole scene (--verify) gets them all.
        const bool lean = req.share_traffic && !req.check;
        if (req.spec) {
          e.cls = req.spec->spec().cls;
          const generation::ScenarioDraw d =
              req.spec->draw(e.seed, static_cast<std::uint64_t>(index), req.seed, req.sampler);
          s = generateScenario(world, d.config, e.cls, e.seed, &d.plan, lean);
        } else {
          s = generateScenario(world, config, e.cls, e.seed, nullptr, lean);
        }
        e.id = s.mission.scenario_id;
        if (req.check) req.check(s);
        const bool by_reference = req.share_traffic && s.sim.traffic && s.sim.traffic->text;
        if (by_reference && req.traffic_inside) {
          s.sim.traffic->file = trafficEpisodeFileName(s.sim.traffic->episode);
          const std::string dir = writeScenarioDir(req.out_dir, s, by_reference);
          writeFileAtomic(dir + "/" + s.sim.traffic->file, *s.sim.traffic->text);
        } else {
          if (by_reference) writeEpisode(*s.sim.traffic);
          writeScenarioDir(req.out_dir, s, by_reference);
        }
        written[static_cast<std::size_t>(i)] = 1;
      } catch (...) {
        std::lock_guard<std::mutex> lock(mu);
        // Keep the lowest failing index so the reported error does not depend on timing.
        if (!error || i < error_index) {
          error = std::current_exception();
          error_index = i;
        }
        failed.store(true);
      }
    }
  };
  const int jobs = std::min(req.jobs, req.count);
  std::vector<std::thread> threads;
  for (int j = 1; j < jobs; ++j) threads.emplace_back(work);
  work();
  for (auto& t : threads) t.join();

  try {
    if (!error) {
      // Two seeds mapping to one id would overwrite a scenario: refuse rather than lose one.
      std::vector<std::string> ids;
      for (const auto& e : entries) ids.push_back(e.id);
      std::sort(ids.begin(), ids.end());
      if (std::adjacent_find(ids.begin(), ids.end()) != ids.end()) {
        throw GenerationError("two scenarios of the batch share an id");
      }
      if (req.write_world) writeFileAtomic(req.out_dir + "/world.json", worldJson(world));
      writeFileAtomic(req.out_dir + "/manifest.json", manifestJson(world, req, entries));
    }
  } catch (...) {
    error = std::current_exception();
  }
  if (error) {
    // Roll back: remove every scenario directory this call wrote.
    for (std::size_t i = 0; i < entries.size(); ++i) {
      if (written[i]) fs::remove_all(req.out_dir + "/" + entries[i].id, ec);
    }
    for (const auto& path : episodes_created) fs::remove(path, ec);
    std::rethrow_exception(error);
  }
  return entries;
}

void keepFreedMemoryForBatches() {
  // Trim the heap's top only past 256 MiB, grow it 64 MiB at a time, and serve blocks up to
  // 32 MiB from the heap (no mmap/munmap round trip per large vector).
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  mallopt(M_TOP_PAD, 64 << 20);
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
}

}  // namespace hameritt::scenario
