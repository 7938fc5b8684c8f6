#pragma once
// Batch generation: many scenarios on several threads, byte-identical whatever the thread
// count, each written atomically, with a manifest.json written last.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hameritt/generation/generator.h"
#include "hameritt/generation/spec_sampler.h"

namespace hameritt::scenario {

struct BatchRequest {
  std::vector<ScenarioClass> classes;  // scenario i has class classes[i % classes.size()]
  int count = 1;
  // Batch index of the first scenario: indices first..first+count-1 of the batch seeded with
  // `seed`, byte-identical to the same indices of the whole batch (sharded generation).
  int first = 0;
  std::uint64_t seed = 1;
  std::string out_dir;
  int jobs = 1;
  bool write_world = true;  // also write DIR/world.json
  // City: write each traffic episode that a scenario uses once, as DIR/traffic_episode_NN.json,
  // and a reference to it in each sim_config.json (off: every scenario self-contained).
  bool share_traffic = false;
  // With share_traffic: each scenario's episode file goes into its own directory
  // (DIR/<id>/traffic_episode_NN.json) and its reference names it there, so that the directory
  // stands alone (hameritt_generate --into).
  bool traffic_inside = false;
  // Use `seed` itself as the scenario seed (count must be 1): regenerates a scenario from the
  // class and seed written in its files.
  bool exact_seed = false;
  // Generate from this compiled spec (its class replaces `classes`), with this sampler.
  const generation::CompiledSpec* spec = nullptr;
  generation::SamplerKind sampler = generation::SamplerKind::kRandom;
  // Called on each scenario before it is written, from the worker threads (unset: none); an
  // exception it throws fails the batch like a generation error.
  std::function<void(const Scenario&)> check;
};

struct ManifestEntry {
  int index = 0;
  std::string id;
  ScenarioClass cls = ScenarioClass::kAreaSearch;
  std::uint64_t seed = 0;
};

// Generates and writes the batch. On any failure nothing that this call created is left
// behind and the error is rethrown (ConfigError, OutputError or GenerationError).
std::vector<ManifestEntry> generateBatch(const World& world, const GeneratorConfig& config,
                                         const BatchRequest& request);

// Tells glibc's allocator to keep freed memory for the process's next scenarios: a batch
// builds and frees tens of MB of small vectors per scenario, and by default the heap's top is
// given back to the kernel past 128 KiB and faulted in again, page by page (about 8 % of a
// 9,000-scenario city batch's CPU). Process-wide (mallopt): for programs whose main work is
// batches (hameritt_generate, bench_generate); the output does not depend on it.
void keepFreedMemoryForBatches();

// Parses "area_search", "route_search", "pursuit", "all" or a comma-separated list.
std::vector<ScenarioClass> parseClassList(const std::string& s);

}  // namespace hameritt::scenario
