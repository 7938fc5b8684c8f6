#pragma once
// ROS wrapper of the scenario generator: the GenerateScenario service over the same batch
// generation as hameritt_generate.

#include <memory>
#include <string>

#include <ros/ros.h>

#include "hameritt/GenerateScenario.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/world.h"

namespace hameritt::ros_wrappers {

// Owns the world and generator config; answers ~generate requests. Parameters:
// ~world_config, ~generator_config (paths; default: the package's config/), ~jobs.
class ScenarioGeneratorRos {
 public:
  // Throws scenario::ConfigError for bad configuration (the node exits with ROS_FATAL).
  explicit ScenarioGeneratorRos(ros::NodeHandle& private_nh);

 private:
  bool generate(hameritt::GenerateScenario::Request& req, hameritt::GenerateScenario::Response& res);
  // The world for a request's world_seed (0: the configured one); regenerated only on change.
  const scenario::World& worldFor(std::uint64_t world_seed);

  scenario::WorldParams world_params_;
  scenario::GeneratorConfig generator_config_;
  std::unique_ptr<scenario::World> world_;
  int jobs_ = 1;
  ros::ServiceServer service_;
};

}  // namespace hameritt::ros_wrappers
