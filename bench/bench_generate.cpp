// Benchmark: scenarios per second, all relations computed and files written.
//   bench_generate [--count N] [--jobs J] [--out DIR]
// Default: 9000 scenarios of all three classes on every core, into a temporary directory
// that is removed afterwards. Prints one line per figure.

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>

#include "hameritt/generation/batch.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/scenario_io.h"

using namespace hameritt::scenario;
namespace fs = std::filesystem;

namespace {

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::uintmax_t dirBytes(const std::string& dir) {
  std::uintmax_t total = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) total += e.file_size();
  }
  return total;
}

}  // namespace

int main(int argc, char** argv) {
  int count = 9000;
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::string out;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--count") count = std::stoi(argv[i + 1]);
    else if (a == "--jobs") jobs = std::stoi(argv[i + 1]);
    else if (a == "--out") out = argv[i + 1];
  }
  const bool temp = out.empty();
  if (temp) out = fs::temp_directory_path().string() + "/hameritt_bench_" + std::to_string(::getpid());

  const WorldParams wp = loadWorldParams(defaultConfigDir() + "/world.json");
  const GeneratorConfig gc = loadGeneratorConfig(defaultConfigDir() + "/generator.json");
  auto t0 = std::chrono::steady_clock::now();
  const World world = generateWorld(wp);
  const double world_s = seconds(t0);

  BatchRequest req;
  req.classes = parseClassList("all");
  req.count = count;
  req.seed = 2026;
  req.jobs = jobs;
  // One timed batch into `dir`; returns wall seconds and the bytes written.
  auto timedBatch = [&](const std::string& dir, std::uintmax_t* bytes) {
    req.out_dir = dir;
    const auto start = std::chrono::steady_clock::now();
    generateBatch(world, gc, req);
    const double s = seconds(start);
    *bytes = dirBytes(dir);
    return s;
  };
  std::uintmax_t bytes = 0, shm_bytes = 0;
  const double batch_s = timedBatch(out, &bytes);
  if (temp) fs::remove_all(out);
  // The same batch into memory-backed storage, to separate the generator from the disk.
  double shm_s = -1;
  if (fs::is_directory("/dev/shm")) {
    const std::string shm = "/dev/shm/hameritt_bench_" + std::to_string(::getpid());
    shm_s = timedBatch(shm, &shm_bytes);
    fs::remove_all(shm);
  }

  // Generation and serialization alone (no files), on one thread.
  const int solo = std::min(count, 900);
  std::size_t json_bytes = 0;
  t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < solo; ++i) {
    const Scenario s = generateScenario(world, gc, req.classes[static_cast<std::size_t>(i) % 3], batchSeed(7, i));
    json_bytes += missionJson(s.mission).size() + simConfigJson(s.sim).size();
  }
  const double solo_s = seconds(t0);

  std::printf("machine_threads            %u\n", std::thread::hardware_concurrency());
  std::printf("world_entities             %zu\n", world.entities().size());
  std::printf("world_generation_ms        %.1f\n", world_s * 1e3);
  std::printf("batch_scenarios            %d (all classes, %d jobs)\n", count, jobs);
  std::printf("disk_batch_wall_s          %.3f (%s)\n", batch_s, out.c_str());
  std::printf("disk_scenarios_per_s       %.0f\n", count / batch_s);
  std::printf("output_mb                  %.1f (%.1f KB per scenario)\n", bytes / 1e6, bytes / 1e3 / count);
  if (shm_s > 0) {
    std::printf("tmpfs_batch_wall_s         %.3f (/dev/shm)\n", shm_s);
    std::printf("tmpfs_scenarios_per_s      %.0f\n", count / shm_s);
  }
  std::printf("generate_json_per_s_1core  %.0f (%d scenarios, %.1f KB JSON each, no files)\n",
              solo / solo_s, solo, json_bytes / 1e3 / solo);
  if (count == 9000) {
    std::printf("target_9000_under_5s       disk %s, tmpfs %s\n", batch_s < 5.0 ? "met" : "NOT met",
                shm_s > 0 && shm_s < 5.0 ? "met" : "NOT met");
  }
  return 0;
}
