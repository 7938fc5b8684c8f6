#include "hameritt/sim/quadrotor.h"

#include <tinyxml2.h>
#include <urdf_model/model.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/share_dir.h"

namespace hameritt::sim {

using scenario::ConfigError;

namespace {

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", v);
  return buf;
}

Eigen::Quaterniond toEigen(const urdf::Rotation& r) { return {r.w, r.x, r.y, r.z}; }
Vec3 toEigen(const urdf::Vector3& v) { return {v.x, v.y, v.z}; }

// Accumulates the composite mass, first moment and inertia (about the base_link origin) of the
// subtree under `link`, whose frame is (R, t) in base_link.
void accumulate(const urdf::LinkConstSharedPtr& link, const Eigen::Matrix3d& r, const Vec3& t,
                double* mass, Eigen::Matrix3d* inertia) {
  if (link->inertial) {
    const urdf::Inertial& in = *link->inertial;
    const Eigen::Matrix3d ri = r * toEigen(in.origin.rotation).toRotationMatrix();
    const Vec3 c = t + r * toEigen(in.origin.position);
    Eigen::Matrix3d ic;
    ic << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
    // Rotate into base_link, then the parallel-axis theorem.
    *inertia += ri * ic * ri.transpose() +
                in.mass * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
    *mass += in.mass;
  }
  for (const auto& child : link->child_links) {
    const urdf::JointConstSharedPtr& j = child->parent_joint;
    const urdf::Pose& o = j->parent_to_joint_origin_transform;
    accumulate(child, r * toEigen(o.rotation).toRotationMatrix(), t + r * toEigen(o.position), mass,
               inertia);
  }
}

double attrDouble(const tinyxml2::XMLElement* e, const char* name, const std::string& where) {
  double v = 0;
  if (e->QueryDoubleAttribute(name, &v) != tinyxml2::XML_SUCCESS || !std::isfinite(v)) {
    throw ConfigError(where + ": expected a number attribute '" + name + "'");
  }
  return v;
}

Vec3 attrVec3(const tinyxml2::XMLElement* e, const char* name, const std::string& where) {
  const char* s = e->Attribute(name);
  Vec3 v;
  if (!s) throw ConfigError(where + ": expected an attribute '" + name + "' of 3 numbers");
  std::istringstream in(s);
  std::string extra;
  if (!(in >> v.x() >> v.y() >> v.z()) || (in >> extra)) {
    throw ConfigError(where + ": attribute '" + name + "': expected 3 numbers, got \"" + s + "\"");
  }
  return v;
}

}  // namespace

double QuadrotorParams::hoverSpeed() const {
  return std::sqrt(mass * 9.80665 / (static_cast<double>(rotors.size()) * kf));
}

void QuadrotorParams::validate() const {
  auto bad = [](const std::string& field, const std::string& what) {
    throw ConfigError("quadrotor." + field + ": " + what);
  };
  if (!(mass > 0)) bad("mass", "expected a positive mass, got " + num(mass));
  const Eigen::LLT<Eigen::Matrix3d> llt(inertia);
  if (!inertia.allFinite() || llt.info() != Eigen::Success)
    bad("inertia", "expected a positive-definite inertia");
  if (rotors.size() != 4) bad("rotors", "expected 4 rotors, got " + std::to_string(rotors.size()));
  if (!(kf > 0) || !(km > 0)) bad("rotor_model", "expected positive kf and km");
  if (!(min_speed >= 0 && max_speed > min_speed)) {
    bad("rotor_model", "expected 0 <= min_speed < max_speed");
  }
  if (!(tau_up > 0 && tau_down > 0)) bad("rotor_model", "expected positive time constants");
  if (!(maxThrust() > 1.5 * mass * 9.80665)) {
    bad("rotor_model",
        "expected a thrust-to-weight ratio above 1.5, got " + num(maxThrust() / (mass * 9.80665)));
  }
  if (!(drag_linear.minCoeff() >= 0 && drag_quadratic.minCoeff() >= 0)) {
    bad("drag", "expected non-negative drag coefficients");
  }
  if (!(collision_size.minCoeff() > 0)) bad("collision", "expected a positive collision box");
  if (!(max_tilt > 0 && max_tilt < 1.4)) bad("limits.max_tilt_deg", "expected (0, 80) degrees");
  if (!(max_horizontal_speed > 0 && max_climb > 0 && max_descent > 0 && max_yaw_rate > 0)) {
    bad("limits", "expected positive speed and rate limits");
  }
}

QuadrotorParams loadQuadrotorUrdf(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open file");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string xml = ss.str();

  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(xml);
  if (!model) throw ConfigError(path + ": <robot>: not a valid URDF (urdfdom parse failed)");
  const urdf::LinkConstSharedPtr base = model->getLink("base_link");
  if (!base) throw ConfigError(path + ": <link name=\"base_link\">: missing");

  QuadrotorParams p;
  p.name = model->getName();
  p.mass = 0;
  p.inertia.setZero();
  accumulate(base, Eigen::Matrix3d::Identity(), Vec3::Zero(), &p.mass, &p.inertia);
  if (!(p.mass > 0)) throw ConfigError(path + ": <inertial>: expected links with positive mass");

  // Collision box of base_link.
  if (!base->collision || !base->collision->geometry ||
      base->collision->geometry->type != urdf::Geometry::BOX) {
    throw ConfigError(path + ": <link name=\"base_link\"><collision>: expected a <box>");
  }
  p.collision_size = toEigen(static_cast<const urdf::Box&>(*base->collision->geometry).dim);

  // Rotors and cameras from the joints of base_link, in joint-name order.
  std::map<std::string, urdf::JointConstSharedPtr> joints(model->joints_.begin(),
                                                          model->joints_.end());
  p.rotors.clear();
  for (const auto& [name, j] : joints) {
    const std::string where = path + ": <joint name=\"" + name + "\">";
    if (name.rfind("rotor_", 0) == 0) {
      if (j->type != urdf::Joint::CONTINUOUS || j->parent_link_name != "base_link") {
        throw ConfigError(where + ": expected a continuous joint from base_link");
      }
      Rotor r;
      r.joint = name;
      r.position = toEigen(j->parent_to_joint_origin_transform.position);
      r.direction = 0;  // set from <hameritt><rotor>
      p.rotors.push_back(r);
    } else if (name.rfind("camera_", 0) == 0) {
      const std::string suffix = "_joint";
      if (j->type != urdf::Joint::FIXED || j->parent_link_name != "base_link" ||
          name.size() <= 7 + suffix.size() ||
          name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) {
        throw ConfigError(where + ": expected a fixed joint camera_<name>_joint from base_link");
      }
      CameraMount c;
      c.name = name.substr(7, name.size() - 7 - suffix.size());
      c.xyz = toEigen(j->parent_to_joint_origin_transform.position);
      double r, pi, y;
      j->parent_to_joint_origin_transform.rotation.getRPY(r, pi, y);
      c.rpy = {r, pi, y};
      p.cameras.push_back(c);
    }
  }

  // The <hameritt> extension element.
  tinyxml2::XMLDocument doc;
  if (doc.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS) {
    throw ConfigError(path + ": malformed XML: " + doc.ErrorStr());
  }
  const tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  const tinyxml2::XMLElement* ext = robot ? robot->FirstChildElement("hameritt") : nullptr;
  if (!ext) throw ConfigError(path + ": <robot><hameritt>: missing");
  const std::string hw = path + ": <hameritt>";
  for (const auto* e = ext->FirstChildElement("rotor"); e; e = e->NextSiblingElement("rotor")) {
    const char* joint = e->Attribute("joint");
    const char* dir = e->Attribute("direction");
    const std::string where = hw + "<rotor joint=\"" + (joint ? joint : "") + "\">";
    auto it = std::find_if(p.rotors.begin(), p.rotors.end(),
                           [&](const Rotor& r) { return joint && r.joint == joint; });
    if (it == p.rotors.end()) throw ConfigError(where + ": no such rotor_<i>_joint");
    if (dir && std::string(dir) == "ccw")
      it->direction = 1;
    else if (dir && std::string(dir) == "cw")
      it->direction = -1;
    else
      throw ConfigError(where + ": expected direction=\"ccw\" or \"cw\"");
  }
  for (const auto& r : p.rotors) {
    if (r.direction == 0) {
      throw ConfigError(hw + "<rotor joint=\"" + r.joint + "\">: missing (spin direction)");
    }
  }
  const auto* rm = ext->FirstChildElement("rotor_model");
  if (!rm) throw ConfigError(hw + "<rotor_model>: missing");
  const std::string rw = hw + "<rotor_model>";
  p.kf = attrDouble(rm, "kf", rw);
  p.km = attrDouble(rm, "km", rw);
  p.min_speed = attrDouble(rm, "min_speed", rw);
  p.max_speed = attrDouble(rm, "max_speed", rw);
  p.tau_up = attrDouble(rm, "tau_up", rw);
  p.tau_down = attrDouble(rm, "tau_down", rw);
  const auto* drag = ext->FirstChildElement("drag");
  if (!drag) throw ConfigError(hw + "<drag>: missing");
  p.drag_linear = attrVec3(drag, "linear", hw + "<drag>");
  p.drag_quadratic = attrVec3(drag, "quadratic", hw + "<drag>");
  const auto* lim = ext->FirstChildElement("limits");
  if (!lim) throw ConfigError(hw + "<limits>: missing");
  const std::string lw = hw + "<limits>";
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  p.max_tilt = attrDouble(lim, "max_tilt_deg", lw) * kDeg;
  p.max_horizontal_speed = attrDouble(lim, "max_speed", lw);
  p.max_climb = attrDouble(lim, "max_climb", lw);
  p.max_descent = attrDouble(lim, "max_descent", lw);
  p.max_yaw_rate = attrDouble(lim, "max_yaw_rate_deg", lw) * kDeg;

  try {
    p.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(path + ": " + e.what());
  }
  for (const auto& r : p.rotors) {
    if (std::abs(r.position.z()) > 0.5 || r.position.head<2>().norm() < 0.02) {
      throw ConfigError(path + ": <joint name=\"" + r.joint +
                        "\"><origin>: expected a rotor hub off the centre, within 0.5 m");
    }
  }
  return p;
}

RotorLayout quadXLayout(const QuadrotorParams& p) {
  // (front?, right?, direction) per output.
  const struct {
    bool front, right;
    int direction;
    const char* name;
  } want[4] = {{true, true, 1, "front-right ccw"},
               {false, false, 1, "rear-left ccw"},
               {true, false, -1, "front-left cw"},
               {false, true, -1, "rear-right cw"}};
  RotorLayout layout{-1, -1, -1, -1};
  for (int o = 0; o < 4; ++o) {
    for (std::size_t i = 0; i < p.rotors.size(); ++i) {
      const Rotor& r = p.rotors[i];
      // FLU: front is +x, right is -y.
      if ((r.position.x() > 0) == want[o].front && (r.position.y() < 0) == want[o].right &&
          r.direction == want[o].direction) {
        layout[static_cast<std::size_t>(o)] = static_cast<int>(i);
      }
    }
    if (layout[static_cast<std::size_t>(o)] < 0) {
      throw ConfigError("quadrotor.rotors: expected a quad-X layout, no " +
                        std::string(want[o].name) + " rotor for motor output " +
                        std::to_string(o + 1));
    }
  }
  return layout;
}

RotorLayout parseRotorLayout(const std::string& text, const std::string& field) {
  RotorLayout layout{-1, -1, -1, -1};
  std::istringstream in(text);
  std::string item;
  int n = 0;
  bool seen[4] = {false, false, false, false};
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const long v = std::strtol(item.c_str(), &end, 10);
    if (n >= 4 || end == item.c_str() || *end != '\0' || v < 0 || v > 3 || seen[v]) {
      throw ConfigError(field +
                        ": expected a permutation of 0,1,2,3 (the model's rotor for "
                        "each motor output), got \"" +
                        text + "\"");
    }
    seen[v] = true;
    layout[static_cast<std::size_t>(n++)] = static_cast<int>(v);
  }
  if (n != 4) {
    throw ConfigError(field +
                      ": expected a permutation of 0,1,2,3 (the model's rotor for each "
                      "motor output), got \"" +
                      text + "\"");
  }
  return layout;
}

std::string defaultQuadrotorUrdf() { return scenario::shareDir() + "/models/sentinel.urdf"; }

// ------------------------------------------------------------------------------------ Mixer

Mixer::Mixer(const QuadrotorParams& p) : kf_(p.kf) {
  a_.setZero();
  for (int i = 0; i < 4; ++i) {
    const Rotor& r = p.rotors[static_cast<std::size_t>(i)];
    a_(0, i) = 1.0;
    a_(1, i) = r.position.y();
    a_(2, i) = -r.position.x();
    a_(3, i) = -r.direction * p.km / p.kf;
  }
  a_inv_ = a_.inverse();
  f_min_ = p.kf * p.min_speed * p.min_speed;
  f_max_ = p.kf * p.max_speed * p.max_speed;
}

Eigen::Vector4d Mixer::mix(double thrust, const Vec3& torque) const {
  const Eigen::Vector4d f_rp = a_inv_ * Eigen::Vector4d(thrust, torque.x(), torque.y(), 0.0);
  const Eigen::Vector4d f_yaw = a_inv_.col(3) * torque.z();
  // Largest yaw scale in [0, 1] keeping each thrust within limits (when f_rp itself is).
  double s = 1.0;
  for (int i = 0; i < 4; ++i) {
    const double fy = f_yaw[i];
    if (fy > 0 && f_rp[i] + fy > f_max_) s = std::min(s, std::max(0.0, (f_max_ - f_rp[i]) / fy));
    if (fy < 0 && f_rp[i] + fy < f_min_) s = std::min(s, std::max(0.0, (f_min_ - f_rp[i]) / fy));
  }
  Eigen::Vector4d f = f_rp + s * f_yaw;
  // Shift the collective to bring the thrusts back into range (attitude before thrust).
  const double hi = f.maxCoeff(), lo = f.minCoeff();
  if (hi > f_max_ && lo > f_min_)
    f.array() -= std::min(hi - f_max_, lo - f_min_);
  else if (lo < f_min_ && hi < f_max_)
    f.array() += std::min(f_min_ - lo, f_max_ - hi);
  Eigen::Vector4d w;
  for (int i = 0; i < 4; ++i) w[i] = std::sqrt(std::clamp(f[i], f_min_, f_max_) / kf_);
  return w;
}

void Mixer::wrench(const Eigen::Vector4d& w, double* thrust, Vec3* torque) const {
  const Eigen::Vector4d f = kf_ * w.cwiseProduct(w);
  const Eigen::Vector4d u = a_ * f;
  *thrust = u[0];
  *torque = u.tail<3>();
}

// ------------------------------------------------------------------------- CascadedController

CascadedController::CascadedController(const QuadrotorParams& p, const ControllerGains& g)
    : p_(p), g_(g), mixer_(p), max_xy_speed_(p.max_horizontal_speed) {}

void CascadedController::reset() {
  vel_int_.setZero();
  rate_int_.setZero();
  yaw_sp_valid_ = false;
  thrust_cmd_ = 0.0;
  att_sp_ = Quat::Identity();
}

namespace {

double yawOf(const Quat& q) {
  const Eigen::Matrix3d r = q.toRotationMatrix();
  return std::atan2(r(1, 0), r(0, 0));
}

double wrapPi(double a) {
  constexpr double kTwoPi = 6.283185307179586;
  a = std::fmod(a + 3.141592653589793, kTwoPi);
  if (a < 0) a += kTwoPi;
  return a - 3.141592653589793;
}

// Attitude whose body z is `z` (unit) and whose heading is `yaw` (PX4 bodyzToAttitude).
Quat attitudeFromZ(const Vec3& z, double yaw) {
  const Vec3 x_c(std::cos(yaw), std::sin(yaw), 0.0);
  Vec3 y = z.cross(x_c);
  if (y.squaredNorm() < 1e-12) y = Vec3(-std::sin(yaw), std::cos(yaw), 0.0);
  y.normalize();
  const Vec3 x = y.cross(z);
  Eigen::Matrix3d r;
  r.col(0) = x;
  r.col(1) = y;
  r.col(2) = z;
  return Quat(r).normalized();
}

// The shortest rotation taking unit vector a onto unit vector b.
Quat rotationBetween(const Vec3& a, const Vec3& b) {
  const double c = a.dot(b);
  if (c < -1.0 + 1e-12) {
    Vec3 axis = a.cross(Vec3::UnitX());
    if (axis.squaredNorm() < 1e-12) axis = a.cross(Vec3::UnitY());
    axis.normalize();
    return Quat(0.0, axis.x(), axis.y(), axis.z());
  }
  const Vec3 v = a.cross(b);
  return Quat(1.0 + c, v.x(), v.y(), v.z()).normalized();
}

}  // namespace

Eigen::Vector4d CascadedController::update(const ControllerInput& s, const ControlSetpoint& sp,
                                           double dt) {
  if (sp.mode == ControlMode::kIdle) {
    reset();
    return Eigen::Vector4d::Zero();
  }
  constexpr double kG = 9.80665;
  const bool freeze = s.landed;
  if (!yaw_sp_valid_) {
    yaw_sp_ = yawOf(s.orientation);
    yaw_sp_valid_ = true;
  }

  double thrust;
  if (sp.mode == ControlMode::kAttitude) {
    att_sp_ = sp.attitude.normalized();
    thrust = sp.thrust;
    yaw_sp_ = yawOf(att_sp_);
  } else {
    // Position -> velocity setpoint (P), limited like PX4 (horizontal norm, climb, descent).
    Vec3 v_sp;
    if (sp.mode == ControlMode::kPosition) {
      const Vec3 e = sp.position - s.position;
      v_sp = Vec3(g_.pos_p_xy * e.x(), g_.pos_p_xy * e.y(), g_.pos_p_z * e.z());
      yaw_sp_ = sp.yaw;
    } else {
      v_sp = sp.velocity;
      const double rate = std::clamp(sp.yaw_rate, -p_.max_yaw_rate, p_.max_yaw_rate);
      yaw_sp_ = wrapPi(yaw_sp_ + rate * dt);
    }
    const double vxy = v_sp.head<2>().norm();
    if (vxy > max_xy_speed_) v_sp.head<2>() *= max_xy_speed_ / vxy;
    v_sp.z() = std::clamp(v_sp.z(), -p_.max_descent, p_.max_climb);

    // Velocity PI -> acceleration setpoint.
    const Vec3 ev = v_sp - s.velocity;
    if (!freeze) {
      vel_int_.x() += g_.vel_i_xy * ev.x() * dt;
      vel_int_.y() += g_.vel_i_xy * ev.y() * dt;
      vel_int_.z() += g_.vel_i_z * ev.z() * dt;
      vel_int_ = vel_int_.cwiseMax(-g_.vel_i_limit).cwiseMin(g_.vel_i_limit);
    }
    const Vec3 acc(g_.vel_p_xy * ev.x() + vel_int_.x(), g_.vel_p_xy * ev.y() + vel_int_.y(),
                   g_.vel_p_z * ev.z() + vel_int_.z());

    // Thrust vector with vertical priority, tilt and total thrust limits.
    const double t_max = 0.9 * p_.maxThrust();
    double fz = std::clamp(p_.mass * (acc.z() + kG), 0.1 * p_.mass * kG, t_max);
    Eigen::Vector2d fxy = p_.mass * acc.head<2>();
    const double fxy_max =
        std::min(fz * std::tan(p_.max_tilt), std::sqrt(std::max(0.0, t_max * t_max - fz * fz)));
    if (fxy.norm() > fxy_max) fxy *= fxy_max / fxy.norm();
    const Vec3 f(fxy.x(), fxy.y(), fz);
    thrust = f.norm();
    att_sp_ = attitudeFromZ(f / thrust, yaw_sp_);
    // Collective along the current body z (PX4 projects the thrust vector onto body z).
    const Vec3 zb = s.orientation * Vec3::UnitZ();
    thrust = std::max(0.0, f.dot(zb));
  }
  thrust_cmd_ = thrust;

  // Attitude P on the quaternion error (tilt first, then yaw with its own gain).
  const Quat q = s.orientation;
  const Vec3 zb = q * Vec3::UnitZ();
  const Vec3 zd = att_sp_ * Vec3::UnitZ();
  const Quat q_tilt = rotationBetween(zb, zd) * q;  // reduced attitude setpoint
  Quat e_tilt = q.conjugate() * q_tilt;
  Quat e_full = q.conjugate() * att_sp_;
  if (e_tilt.w() < 0) e_tilt.coeffs() *= -1;
  if (e_full.w() < 0) e_full.coeffs() *= -1;
  Vec3 rate_sp = 2.0 * g_.att_p_rp * e_tilt.vec();
  rate_sp.z() = 0.0;
  rate_sp += Vec3(0, 0, 2.0 * g_.att_p_yaw * e_full.z());
  for (int i = 0; i < 2; ++i) rate_sp[i] = std::clamp(rate_sp[i], -g_.max_rate_rp, g_.max_rate_rp);
  if (sp.mode == ControlMode::kVelocity) {
    rate_sp.z() += std::clamp(sp.yaw_rate, -p_.max_yaw_rate, p_.max_yaw_rate);
  }
  rate_sp.z() = std::clamp(rate_sp.z(), -p_.max_yaw_rate, p_.max_yaw_rate);

  // Body-rate PI with gyroscopic compensation -> torques.
  const Vec3& w = s.angular_velocity;
  const Vec3 er = rate_sp - w;
  if (!freeze) {
    rate_int_.x() += g_.rate_i_rp * er.x() * dt;
    rate_int_.y() += g_.rate_i_rp * er.y() * dt;
    rate_int_.z() += g_.rate_i_yaw * er.z() * dt;
    rate_int_ = rate_int_.cwiseMax(-g_.rate_i_limit).cwiseMin(g_.rate_i_limit);
  } else {
    rate_int_.setZero();
  }
  const Vec3 alpha(g_.rate_p_rp * er.x() + rate_int_.x(), g_.rate_p_rp * er.y() + rate_int_.y(),
                   g_.rate_p_yaw * er.z() + rate_int_.z());
  const Vec3 torque = p_.inertia * alpha + w.cross(p_.inertia * w);
  return mixer_.mix(thrust, torque);
}

}  // namespace hameritt::sim
