#pragma once
// The ROS-free simulator core. Design: the UAV's rigid-body dynamics (rotor thrust kf*w^2 and
// drag torque km*w^2 with first-order motor lag, body drag against the air-relative velocity,
// gravity) are integrated here with a fixed-step RK4 scheme; Bullet is used for collision
// detection only: the static neighborhood (houses, garages, fences, tree trunks and canopies,
// parked cars as oriented boxes) and the scenario's moving vehicles, pedestrians and aircraft
// (kinematic collision objects that follow their sim_config trajectories exactly) live in a
// btCollisionWorld with a btDbvtBroadphase, and the UAV's collision box is tested against the
// broadphase candidates each step. Single-threaded and wall-clock free: the same scenario and
// command sequence give the same trajectory bit for bit.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"
#include "hameritt/sim/quadrotor.h"

namespace hameritt::sim {

// Fixed-step settings (the node's parameters).
struct SimSettings {
  double physics_rate_hz = 500.0;
  bool wind = true;        // mean wind + turbulence from sim_config
  bool collisions = true;  // UAV-vs-scenery crash detection (ground contact is always handled)

  // Throws scenario::ConfigError naming the field ("sim.physics_rate_hz") and the bad value.
  void validate() const;
};

// The UAV's state at the current step.
struct UavState {
  double t = 0.0;
  Vec3 position{0, 0, 0};                    // ENU, base_link origin
  Quat orientation{1, 0, 0, 0};              // body FLU to ENU
  Vec3 velocity{0, 0, 0};                    // world frame
  Vec3 angular_velocity{0, 0, 0};            // body frame
  Vec3 specific_force{0, 0, 0};              // body frame, what an accelerometer reads (m/s^2)
  Eigen::Vector4d rotor_speeds{0, 0, 0, 0};  // rad/s
  bool landed = true;
  bool crashed = false;
  std::string crashed_into;  // entity id (or "ground" for a hard ground impact)
  double crash_time = 0.0;
};

// Ground truth of a scenario entity at the current step.
struct EntityState {
  std::string id;
  scenario::EntityClass cls = scenario::EntityClass::kCar;
  // scenario role (target, confuser, traffic, pedestrian, vignette, hostile), or "aircraft"
  // for an avoid scenario's aircraft (SimConfig::aircraft, moved like the other movers)
  std::string role;
  geometry::OrientedBox box;
  Vec3 velocity{0, 0, 0};
  double yaw_rate = 0.0;
};

class Simulator {
 public:
  // The world is the static neighborhood (its solid entities become collision boxes; the ground
  // is the plane z = 0); `config` adds the scenario's entities, wind and the UAV start (the UAV
  // starts landed, its collision box resting on the ground at uav.start, heading uav.start.yaw).
  Simulator(const scenario::World& world, const scenario::SimConfig& config,
            const QuadrotorParams& uav, const SimSettings& settings);
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  // Advances one fixed physics step (1 / physics_rate_hz).
  void step();
  void step(int n);
  // Simulation time: steps taken * dt (no accumulation error).
  double time() const;
  double dt() const;
  std::int64_t stepCount() const;

  // Setpoints (map/ENU frame). A velocity setpoint replaces a position setpoint and vice versa;
  // the first setpoint arms the UAV. Velocities are limited to the model's and the scenario's
  // max speed, climb and descent rates.
  void setVelocitySetpoint(const Vec3& velocity, double yaw_rate);
  void setPositionSetpoint(const Vec3& position, double yaw);
  // Attitude + collective thrust (N), bypassing the position and velocity loops.
  void setAttitudeSetpoint(const Quat& attitude, double thrust);
  // Rotor speed commands (rad/s, model rotor order, clamped to [0, max_speed]) from an
  // external autopilot, bypassing the controller; the motors follow with their time constants.
  void setRotorCommands(const Eigen::Vector4d& speeds);
  // Stops the rotors (disarm).
  void disarm();

  // Back to t = 0 with the same seed: the same commands give the same trajectory again.
  void reset();

  const UavState& uav() const;
  const QuadrotorParams& params() const;
  // Scenario entities (moving vehicles and pedestrians at the current time, and parked ones).
  std::vector<EntityState> scenarioEntities() const;
  // The wind velocity acting on the UAV at the current step (mean + turbulence), ENU m/s.
  Vec3 wind() const;
  // Number of static collision objects (world occluder boxes + parked scenario entities) and
  // of kinematic movers.
  int staticObjectCount() const;
  int moverCount() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hameritt::sim
