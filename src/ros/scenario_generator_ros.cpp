#include "hameritt/ros/scenario_generator_ros.h"

#include <memory>
#include <thread>

#include "hameritt/generation/batch.h"
#include "hameritt/generation/spec_sampler.h"
#include "hameritt/scenario/error.h"

namespace hameritt::ros_wrappers {

ScenarioGeneratorRos::ScenarioGeneratorRos(ros::NodeHandle& nh) {
  const std::string dir = scenario::defaultConfigDir();
  std::string world_cfg, gen_cfg;
  nh.param<std::string>("world_config", world_cfg, dir + "/world.json");
  nh.param<std::string>("generator_config", gen_cfg, dir + "/generator.json");
  nh.param("jobs", jobs_, static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  if (jobs_ < 1) throw scenario::ConfigError("~jobs: expected at least 1, got " + std::to_string(jobs_));
  world_params_ = scenario::loadWorldParams(world_cfg);
  generator_config_ = scenario::loadGeneratorConfig(gen_cfg);
  world_ = std::make_unique<scenario::World>(scenario::generateWorld(world_params_));
  service_ = nh.advertiseService("generate", &ScenarioGeneratorRos::generate, this);
  ROS_INFO("scenario_generator: world of %zu entities ready; service %s",
           world_->entities().size(), service_.getService().c_str());
}

const scenario::World& ScenarioGeneratorRos::worldFor(std::uint64_t world_seed) {
  const std::uint64_t seed = world_seed == 0 ? world_params_.seed : world_seed;
  if (world_->params().seed != seed) {
    scenario::WorldParams p = world_params_;
    p.seed = seed;
    world_ = std::make_unique<scenario::World>(scenario::generateWorld(p));
  }
  return *world_;
}

bool ScenarioGeneratorRos::generate(hameritt::GenerateScenario::Request& req,
                                    hameritt::GenerateScenario::Response& res) {
  // No exception leaves the callback: every outcome is a response code.
  try {
    scenario::BatchRequest batch;
    std::unique_ptr<generation::CompiledSpec> spec;
    if (!req.spec.empty()) {
      if (!req.scenario_class.empty()) {
        throw scenario::ConfigError(
            "scenario_class: a spec names its class; give one or the other");
      }
      if (!req.sampler.empty() && !generation::parseSampler(req.sampler, &batch.sampler)) {
        throw scenario::ConfigError("sampler: expected random or halton, got '" + req.sampler +
                                    "'");
      }
      const scenario::World& world = worldFor(req.world_seed);
      spec = std::make_unique<generation::CompiledSpec>(
          generation::parseSpec(req.spec, req.params, world), world, generator_config_);
      batch.spec = spec.get();
    } else {
      if (!req.params.empty() || !req.sampler.empty()) {
        throw scenario::ConfigError("params, sampler: need a spec");
      }
      batch.classes = scenario::parseClassList(req.scenario_class);
    }
    batch.count = static_cast<int>(req.count);
    if (req.count > 100000) throw scenario::ConfigError("count: expected at most 100000");
    batch.seed = req.seed;
    batch.out_dir = req.out_dir;
    batch.jobs = jobs_;
    const auto entries = scenario::generateBatch(worldFor(req.world_seed), generator_config_, batch);
    for (const auto& e : entries) {
      res.scenario_ids.push_back(e.id);
      res.scenario_dirs.push_back(req.out_dir + "/" + e.id);
    }
    res.success = true;
    res.code = 0;
    res.message = "generated " + std::to_string(entries.size()) + " scenarios in " + req.out_dir;
  } catch (const scenario::ConfigError& e) {
    res.success = false;
    res.code = 2;
    res.message = e.what();
  } catch (const scenario::OutputError& e) {
    res.success = false;
    res.code = 2;
    res.message = e.what();
  } catch (const std::exception& e) {
    res.success = false;
    res.code = 1;
    res.message = e.what();
  }
  if (!res.success) ROS_WARN("scenario_generator: %s", res.message.c_str());
  return true;
}

}  // namespace hameritt::ros_wrappers
