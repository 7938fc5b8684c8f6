#pragma once
// The UAV model: quadrotor parameters read from a URDF (models/sentinel.urdf), the rotor and
// motor model, the control allocation (mixer) and a PX4-style cascaded controller. ROS-free.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

namespace hameritt::sim {

using Vec3 = Eigen::Vector3d;
using Quat = Eigen::Quaterniond;

// One rotor: hub position in base_link (FLU) and spin direction (+1 ccw seen from above, whose
// reaction torque is -km*w^2 about +z; -1 cw).
struct Rotor {
  std::string joint;
  Vec3 position{0, 0, 0};
  int direction = 1;
};

// A camera mount on base_link (from a fixed joint camera_<name>_joint).
struct CameraMount {
  std::string name;
  Vec3 xyz{0, 0, 0};  // metres, body frame FLU
  Vec3 rpy{0, 0, 0};  // radians, roll-pitch-yaw; positive pitch looks down
};

// Physical and controller-limit parameters of a quadrotor (defaults: the shipped sentinel).
struct QuadrotorParams {
  std::string name = "sentinel";
  double mass = 1.04;  // kg, composite of all links
  Eigen::Matrix3d inertia = Eigen::Vector3d(0.00544, 0.00544, 0.0100).asDiagonal();  // kg m^2
  std::vector<Rotor> rotors;
  // Rotor model: thrust kf*w^2 [N], drag torque km*w^2 [N m]; first-order motor lag.
  double kf = 1.3e-6;
  double km = 2.08e-8;
  double min_speed = 150.0;   // rad/s while armed in flight
  double max_speed = 2600.0;  // rad/s
  double tau_up = 0.02;       // s, spin-up time constant
  double tau_down = 0.035;    // s, spin-down time constant
  // Body drag against the air-relative velocity, body frame: -(linear .* v + quadratic .* |v| v).
  Vec3 drag_linear{0.2, 0.2, 0.3};
  Vec3 drag_quadratic{0.0123, 0.0123, 0.0368};
  Vec3 collision_size{0.34, 0.34, 0.10};  // box around frame and props, metres
  // Controller limits.
  double max_tilt = 35.0 * 3.14159265358979323846 / 180.0;       // rad
  double max_horizontal_speed = 12.0;                            // m/s
  double max_climb = 3.0;                                        // m/s
  double max_descent = 2.0;                                      // m/s
  double max_yaw_rate = 120.0 * 3.14159265358979323846 / 180.0;  // rad/s
  std::vector<CameraMount> cameras;

  // The maximum total thrust (N) and the hover rotor speed (rad/s).
  double maxThrust() const {
    return static_cast<double>(rotors.size()) * kf * max_speed * max_speed;
  }
  double hoverSpeed() const;
  // Throws scenario::ConfigError naming the field when a value is out of range.
  void validate() const;
};

// Parses a quadrotor URDF (urdfdom for links, joints and inertials; the <hameritt> element for
// rotor directions, rotor model, drag and limits; see models/sentinel.urdf for the conventions).
// Throws scenario::ConfigError naming the file and the offending element.
QuadrotorParams loadQuadrotorUrdf(const std::string& path);

// The shipped model: models/sentinel.urdf in the package's data (scenario::shareDir()).
std::string defaultQuadrotorUrdf();

// Which model rotor each autopilot motor output drives: layout[i] is the model's rotor index
// for motor output i.
using RotorLayout = std::array<int, 4>;

// The layout of PX4's (and ArduPilot's) quad-X: output 1 front-right ccw, 2 rear-left ccw,
// 3 front-left cw, 4 rear-right cw (PX4 "Quadrotor x" airframe reference), found from the
// model's rotor positions and spin directions. Throws scenario::ConfigError when the model
// has no rotor in one of those places.
RotorLayout quadXLayout(const QuadrotorParams& p);

// Parses a comma-separated permutation of 0..3 ("2,0,3,1"); throws scenario::ConfigError
// naming `field` for anything else.
RotorLayout parseRotorLayout(const std::string& text, const std::string& field);

// Control allocation for a planar rotor layout: [T, tau_x, tau_y, tau_z] = A * f with rotor
// thrusts f (thrust along body +z at the hubs; yaw from the km/kf reaction torques).
class Mixer {
 public:
  explicit Mixer(const QuadrotorParams& p);
  // Rotor speed commands (rad/s) for a collective thrust (N) and body torques (N m). Saturation
  // keeps roll/pitch first: yaw torque is scaled down, then the collective is shifted (as in
  // PX4's mixer desaturation), then the thrusts are clipped to the rotor limits.
  Eigen::Vector4d mix(double thrust, const Vec3& torque) const;
  // Collective thrust and body torques produced by rotor speeds w (rad/s).
  void wrench(const Eigen::Vector4d& w, double* thrust, Vec3* torque) const;

 private:
  Eigen::Matrix4d a_;
  Eigen::Matrix4d a_inv_;
  double kf_, f_min_, f_max_;
};

// What the client commands.
enum class ControlMode {
  kIdle,      // disarmed: rotors stopped
  kPosition,  // position + yaw
  kVelocity,  // velocity + yaw rate
  kAttitude,  // attitude + collective thrust (bypasses the position/velocity loops)
  kRotors,    // rotor speed commands from an external autopilot (bypasses the controller)
};

struct ControlSetpoint {
  ControlMode mode = ControlMode::kIdle;
  Vec3 position{0, 0, 0};
  double yaw = 0.0;
  Vec3 velocity{0, 0, 0};
  double yaw_rate = 0.0;
  Quat attitude{1, 0, 0, 0};
  double thrust = 0.0;  // N
  Eigen::Vector4d rotor_speeds{0, 0, 0, 0};  // rad/s, model rotor order (kRotors)
};

// Gains of the cascaded controller (PX4 mc_pos_control / mc_att_control / mc_rate_control
// structure, in physical units: accelerations in m/s^2 per m/s, rates in rad/s per rad, angular
// accelerations in rad/s^2 per rad/s).
struct ControllerGains {
  double pos_p_xy = 0.95, pos_p_z = 1.0;   // PX4 MPC_XY_P, MPC_Z_P
  double vel_p_xy = 1.8, vel_i_xy = 0.4;   // PX4 MPC_XY_VEL_P_ACC, _I_ACC
  double vel_p_z = 4.0, vel_i_z = 2.0;     // PX4 MPC_Z_VEL_P_ACC, _I_ACC
  double vel_i_limit = 4.0;                // m/s^2 of integral authority
  double att_p_rp = 6.5, att_p_yaw = 2.8;  // PX4 MC_ROLL_P/MC_PITCH_P, MC_YAW_P
  double max_rate_rp = 3.8;                // rad/s (PX4 MC_ROLLRATE_MAX 220 deg/s)
  double rate_p_rp = 22.0, rate_p_yaw = 10.0;
  double rate_i_rp = 8.0, rate_i_yaw = 4.0;
  double rate_i_limit = 10.0;  // rad/s^2
};

// State the controller reads (ENU world frame; body rates in FLU).
struct ControllerInput {
  Vec3 position{0, 0, 0};
  Vec3 velocity{0, 0, 0};
  Quat orientation{1, 0, 0, 0};
  Vec3 angular_velocity{0, 0, 0};
  bool landed = true;
};

// Cascaded P/PID controller: position P -> velocity PI -> thrust vector with tilt, climb and
// thrust limits -> attitude P (quaternion error, tilt prioritized over yaw) -> body-rate PI with
// gyroscopic feed-forward -> mixer. Integrators freeze while landed.
class CascadedController {
 public:
  CascadedController(const QuadrotorParams& p, const ControllerGains& g = ControllerGains());

  void reset();
  // Horizontal speed limit (the smaller of the model's and the scenario's).
  void setMaxHorizontalSpeed(double v) { max_xy_speed_ = v; }
  // Rotor speed commands (rad/s) for one control step of dt seconds.
  Eigen::Vector4d update(const ControllerInput& s, const ControlSetpoint& sp, double dt);
  // Last collective thrust command (N) and attitude setpoint.
  double thrustCommand() const { return thrust_cmd_; }
  const Quat& attitudeSetpoint() const { return att_sp_; }

 private:
  QuadrotorParams p_;
  ControllerGains g_;
  Mixer mixer_;
  double max_xy_speed_;
  Vec3 vel_int_{0, 0, 0};
  Vec3 rate_int_{0, 0, 0};
  double yaw_sp_ = 0.0;
  bool yaw_sp_valid_ = false;
  double thrust_cmd_ = 0.0;
  Quat att_sp_{1, 0, 0, 0};
};

}  // namespace hameritt::sim
