#include "hameritt/sim/simulator.h"

#include <btBulletCollisionCommon.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "hameritt/geometry/types.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/rng.h"
#include "hameritt/scenario/trajectory.h"
#include "hameritt/sim/wind.h"

namespace hameritt::sim {

using scenario::ConfigError;

namespace {

constexpr double kG = 9.80665;
constexpr std::uint64_t kWindStream = 0x57494E44;  // "WIND"
// Touchdown limits: slower than this vertically and horizontally, and this upright, is a landing.
constexpr double kMaxTouchdownSpeed = 2.5;    // m/s (a small quad's landing gear)
constexpr double kMaxTouchdownLateral = 2.0;  // m/s
const double kMinTouchdownCosTilt = std::cos(30.0 * geometry::kPi / 180.0);
constexpr float kStaticMargin = 0.005f;

// Rigid-body state integrated by RK4.
struct Body {
  Vec3 p, v;
  Eigen::Vector4d q;  // w, x, y, z
  Vec3 w;
};

struct BodyRate {
  Vec3 dp, dv;
  Eigen::Vector4d dq;
  Vec3 dw;
};

Quat toQuat(const Eigen::Vector4d& q) { return Quat(q[0], q[1], q[2], q[3]); }

btTransform boxTransform(const Vec3& c, double yaw) {
  btTransform t;
  t.setIdentity();
  t.setOrigin(btVector3(static_cast<btScalar>(c.x()), static_cast<btScalar>(c.y()),
                        static_cast<btScalar>(c.z())));
  t.setRotation(btQuaternion(btVector3(0, 0, 1), static_cast<btScalar>(yaw)));
  return t;
}

// Collects broadphase candidates overlapping the UAV's AABB.
struct AabbCollector : public btBroadphaseAabbCallback {
  std::vector<btCollisionObject*>* out;
  bool process(const btBroadphaseProxy* proxy) override {
    out->push_back(static_cast<btCollisionObject*>(proxy->m_clientObject));
    return true;
  }
};

// True when any contact point penetrates.
struct PenetrationCallback : public btCollisionWorld::ContactResultCallback {
  bool hit = false;
  bool needsCollision(btBroadphaseProxy*) const override { return true; }
  btScalar addSingleResult(btManifoldPoint& cp, const btCollisionObjectWrapper*, int, int,
                           const btCollisionObjectWrapper*, int, int) override {
    if (cp.getDistance() < 0) hit = true;
    return 0;
  }
};

// Velocity and yaw rate of a trajectory at t (the segment's constant rates; zero outside).
void trajectoryRates(const scenario::Trajectory& traj, double t, Vec3* vel, double* yaw_rate) {
  *vel = Vec3::Zero();
  *yaw_rate = 0.0;
  if (traj.size() < 2 || t < traj.front().t || t >= traj.back().t) return;
  const auto it =
      std::upper_bound(traj.begin(), traj.end(), t,
                       [](double v, const scenario::TrajectoryPoint& p) { return v < p.t; });
  const auto& b = *it;
  const auto& a = *(it - 1);
  const double span = b.t - a.t;
  if (span <= 0) return;
  *vel = Vec3(b.x - a.x, b.y - a.y, b.z - a.z) / span;
  *yaw_rate = geometry::wrapPi(b.yaw - a.yaw) / span;
}

}  // namespace

void SimSettings::validate() const {
  if (!(physics_rate_hz >= 50.0 && physics_rate_hz <= 10000.0)) {
    throw ConfigError("sim.physics_rate_hz: expected a rate in [50, 10000] Hz, got " +
                      std::to_string(physics_rate_hz));
  }
}

namespace {
// The scenario's entities followed by its aircraft (scenario::aircraftEntities).
std::vector<scenario::ScenarioEntity> withAircraft(const scenario::SimConfig& c) {
  std::vector<scenario::ScenarioEntity> out = c.entities;
  for (auto& a : scenario::aircraftEntities(c)) out.push_back(std::move(a));
  return out;
}
}  // namespace

struct Simulator::Impl {
  struct Mover {
    std::size_t entity;
    btCollisionObject* object;
    scenario::TrajectoryPoint pose;
  };

  Impl(const scenario::World& world, const scenario::SimConfig& config, const QuadrotorParams& uav,
       const SimSettings& s)
      : params(uav),
        settings(s),
        dt(1.0 / s.physics_rate_hz),
        entities(withAircraft(config)),
        start(config.uav.start),
        controller(uav),
        mixer(uav),
        wind(config.environment.wind_mean, config.environment.gust_intensity,
             scenario::deriveSeed(config.seed, kWindStream), s.wind),
        dispatcher(&collision_config),
        collision_world(&dispatcher, &broadphase, &collision_config),
        uav_shape(btVector3(static_cast<btScalar>(0.5 * uav.collision_size.x()),
                            static_cast<btScalar>(0.5 * uav.collision_size.y()),
                            static_cast<btScalar>(0.5 * uav.collision_size.z()))) {
    controller.setMaxHorizontalSpeed(std::min(uav.max_horizontal_speed, config.uav.max_speed));
    inertia_inv = params.inertia.inverse();
    alpha_up = 1.0 - std::exp(-dt / params.tau_up);
    alpha_down = 1.0 - std::exp(-dt / params.tau_down);
    half = 0.5 * params.collision_size;
    broadphase.m_deferedcollide = true;  // no pair finding: only the UAV is tested
    uav_shape.setMargin(kStaticMargin);
    uav_object.setCollisionShape(&uav_shape);

    // Static scenery: every solid world entity's occluder boxes, and parked scenario entities.
    auto addStatic = [&](const geometry::OrientedBox& b, const std::string& id) {
      const Vec3 h = 0.5 * b.size;
      if (!(h.minCoeff() > 0)) return;
      auto shape = std::make_unique<btBoxShape>(btVector3(static_cast<btScalar>(h.x()),
                                                          static_cast<btScalar>(h.y()),
                                                          static_cast<btScalar>(h.z())));
      shape->setMargin(std::min(kStaticMargin, static_cast<float>(h.minCoeff())));
      auto obj = std::make_unique<btCollisionObject>();
      obj->setCollisionShape(shape.get());
      obj->setWorldTransform(boxTransform(b.center, b.yaw));
      obj->setUserIndex(static_cast<int>(names.size()));
      names.push_back(id);
      collision_world.addCollisionObject(obj.get(), btBroadphaseProxy::StaticFilter, 0);
      shapes.push_back(std::move(shape));
      objects.push_back(std::move(obj));
      return;
    };
    for (const auto& e : world.entities()) {
      for (const auto& b : scenario::occluderBoxes(e)) addStatic(b, e.id);
    }
    for (std::size_t i = 0; i < entities.size(); ++i) {
      const auto& se = entities[i];
      if (se.trajectory.empty()) {
        for (const auto& b : scenario::occluderBoxes(se.entity)) addStatic(b, se.entity.id);
      }
    }
    static_count = static_cast<int>(objects.size());
    // Kinematic movers: one box each, moved along the trajectory.
    for (std::size_t i = 0; i < entities.size(); ++i) {
      const auto& se = entities[i];
      if (se.trajectory.empty()) continue;
      const Vec3 h = 0.5 * se.entity.box.size;
      auto shape = std::make_unique<btBoxShape>(btVector3(static_cast<btScalar>(h.x()),
                                                          static_cast<btScalar>(h.y()),
                                                          static_cast<btScalar>(h.z())));
      shape->setMargin(std::min(kStaticMargin, static_cast<float>(h.minCoeff())));
      auto obj = std::make_unique<btCollisionObject>();
      obj->setCollisionShape(shape.get());
      obj->setCollisionFlags(obj->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
      obj->setUserIndex(static_cast<int>(names.size()));
      names.push_back(se.entity.id);
      const auto pose = scenario::sampleTrajectory(se.trajectory, 0.0);
      obj->setWorldTransform(boxTransform(Vec3(pose.x, pose.y, pose.z + h.z()), pose.yaw));
      collision_world.addCollisionObject(obj.get(), btBroadphaseProxy::KinematicFilter, 0);
      movers.push_back({i, obj.get(), pose});
      shapes.push_back(std::move(shape));
      objects.push_back(std::move(obj));
    }
    broadphase.optimize();
    resetState();
  }

  void resetState() {
    steps = 0;
    sp = ControlSetpoint();
    controller.reset();
    wind.reset();
    s = UavState();
    s.position = Vec3(start.x, start.y, start.z + half.z());
    s.orientation = Quat(Eigen::AngleAxisd(start.yaw, Vec3::UnitZ()));
    s.landed = true;
    s.specific_force = Vec3(0, 0, kG);
    for (auto& m : movers) moveTo(m, 0.0, true);
  }

  void moveTo(Mover& m, double t, bool force) {
    const auto& se = entities[m.entity];
    const auto p = scenario::sampleTrajectory(se.trajectory, t);
    if (!force && p.x == m.pose.x && p.y == m.pose.y && p.z == m.pose.z && p.yaw == m.pose.yaw) {
      m.pose.t = t;
      return;  // not moving: no broadphase update
    }
    m.pose = p;
    m.object->setWorldTransform(
        boxTransform(Vec3(p.x, p.y, p.z + 0.5 * se.entity.box.size.z()), p.yaw));
    collision_world.updateSingleAabb(m.object);
  }

  // Forces and torques from the rotors (held over the step) plus drag and gravity.
  BodyRate derivative(const Body& b, double thrust, const Vec3& torque, const Vec3& air) const {
    BodyRate d;
    const Quat q = toQuat(b.q);
    const Eigen::Matrix3d r = q.toRotationMatrix();
    const Vec3 vb = r.transpose() * (b.v - air);
    const Vec3 drag = -(params.drag_linear.cwiseProduct(vb) +
                        params.drag_quadratic.cwiseProduct(vb.cwiseAbs().cwiseProduct(vb)));
    const Vec3 fb = Vec3(0, 0, thrust) + drag;
    d.dp = b.v;
    d.dv = r * fb / params.mass - Vec3(0, 0, kG);
    const Vec3& w = b.w;
    d.dq = 0.5 * Eigen::Vector4d(-b.q[1] * w.x() - b.q[2] * w.y() - b.q[3] * w.z(),
                                 b.q[0] * w.x() + b.q[2] * w.z() - b.q[3] * w.y(),
                                 b.q[0] * w.y() + b.q[3] * w.x() - b.q[1] * w.z(),
                                 b.q[0] * w.z() + b.q[1] * w.y() - b.q[2] * w.x());
    d.dw = inertia_inv * (torque - w.cross(params.inertia * w));
    return d;
  }

  static Body advance(const Body& b, const BodyRate& d, double h) {
    return {b.p + h * d.dp, b.v + h * d.dv, b.q + h * d.dq, b.w + h * d.dw};
  }

  void crash(const std::string& id) {
    s.crashed = true;
    s.crashed_into = id;
    s.crash_time = steps * dt;
    s.velocity.setZero();
    s.angular_velocity.setZero();
    s.rotor_speeds.setZero();
    s.specific_force.setZero();
    sp = ControlSetpoint();
  }

  void step() {
    if (!s.crashed) stepUav();
    ++steps;
    const double t = steps * dt;
    s.t = t;
    for (auto& m : movers) moveTo(m, t, false);
    if (!s.crashed && !s.landed) checkContacts();
  }

  void stepUav() {
    wind.step(dt, s.position.z(), s.velocity);
    ControllerInput in;
    in.position = s.position;
    in.velocity = s.velocity;
    in.orientation = s.orientation;
    in.angular_velocity = s.angular_velocity;
    in.landed = s.landed;
    const Eigen::Vector4d cmd =
        sp.mode == ControlMode::kRotors ? sp.rotor_speeds : controller.update(in, sp, dt);
    // Motors: exact discretization of the first-order lag, then the speed limits.
    for (int i = 0; i < 4; ++i) {
      const double w = s.rotor_speeds[i];
      const double c = std::clamp(cmd[i], 0.0, params.max_speed);
      s.rotor_speeds[i] = w + (c - w) * (c > w ? alpha_up : alpha_down);
    }
    double thrust;
    Vec3 torque;
    mixer.wrench(s.rotor_speeds, &thrust, &torque);
    const Eigen::Matrix3d r0 = s.orientation.toRotationMatrix();
    if (s.landed) {
      // On the ground until the thrust lifts the weight.
      if (thrust * r0(2, 2) <= params.mass * kG) {
        s.velocity.setZero();
        s.angular_velocity.setZero();
        s.specific_force = r0.transpose() * Vec3(0, 0, kG);
        return;
      }
      s.landed = false;
    }
    const Vec3 air = wind.wind();
    Body b{
        s.position, s.velocity,
        Eigen::Vector4d(s.orientation.w(), s.orientation.x(), s.orientation.y(), s.orientation.z()),
        s.angular_velocity};
    const BodyRate k1 = derivative(b, thrust, torque, air);
    const BodyRate k2 = derivative(advance(b, k1, 0.5 * dt), thrust, torque, air);
    const BodyRate k3 = derivative(advance(b, k2, 0.5 * dt), thrust, torque, air);
    const BodyRate k4 = derivative(advance(b, k3, dt), thrust, torque, air);
    const double h6 = dt / 6.0;
    b.p += h6 * (k1.dp + 2.0 * k2.dp + 2.0 * k3.dp + k4.dp);
    b.v += h6 * (k1.dv + 2.0 * k2.dv + 2.0 * k3.dv + k4.dv);
    b.q += h6 * (k1.dq + 2.0 * k2.dq + 2.0 * k3.dq + k4.dq);
    b.w += h6 * (k1.dw + 2.0 * k2.dw + 2.0 * k3.dw + k4.dw);
    b.q.normalize();
    s.position = b.p;
    s.velocity = b.v;
    s.orientation = toQuat(b.q);
    s.angular_velocity = b.w;
    const Eigen::Matrix3d r = s.orientation.toRotationMatrix();
    const Vec3 vb = r.transpose() * (s.velocity - air);
    const Vec3 drag = -(params.drag_linear.cwiseProduct(vb) +
                        params.drag_quadratic.cwiseProduct(vb.cwiseAbs().cwiseProduct(vb)));
    s.specific_force = (Vec3(0, 0, thrust) + drag) / params.mass;
  }

  // Ground contact (landing or crash), then the scenery.
  void checkContacts() {
    const Eigen::Matrix3d r = s.orientation.toRotationMatrix();
    const double reach =
        std::abs(r(2, 0)) * half.x() + std::abs(r(2, 1)) * half.y() + std::abs(r(2, 2)) * half.z();
    if (s.position.z() - reach <= 0.0 && s.velocity.z() > 0.0) {
      s.position.z() = reach;  // lifting off: the ground pushes, nothing more
    } else if (s.position.z() - reach <= 0.0) {
      const bool soft = s.velocity.z() >= -kMaxTouchdownSpeed &&
                        s.velocity.head<2>().norm() <= kMaxTouchdownLateral &&
                        r(2, 2) >= kMinTouchdownCosTilt;
      if (!soft) {
        s.position.z() = reach;
        crash("ground");
        return;
      }
      // Settle upright on the ground, keeping the heading.
      const double yaw = std::atan2(r(1, 0), r(0, 0));
      s.orientation = Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ()));
      s.position.z() = half.z();
      s.velocity.setZero();
      s.angular_velocity.setZero();
      s.specific_force = Vec3(0, 0, kG);
      s.landed = true;
      return;
    }
    if (!settings.collisions) return;
    btTransform tr;
    tr.setOrigin(btVector3(static_cast<btScalar>(s.position.x()),
                           static_cast<btScalar>(s.position.y()),
                           static_cast<btScalar>(s.position.z())));
    tr.setRotation(btQuaternion(
        static_cast<btScalar>(s.orientation.x()), static_cast<btScalar>(s.orientation.y()),
        static_cast<btScalar>(s.orientation.z()), static_cast<btScalar>(s.orientation.w())));
    uav_object.setWorldTransform(tr);
    btVector3 lo, hi;
    uav_shape.getAabb(tr, lo, hi);
    candidates.clear();
    AabbCollector collector;
    collector.out = &candidates;
    broadphase.aabbTest(lo, hi, collector);
    if (candidates.empty()) return;
    std::sort(candidates.begin(), candidates.end(),
              [](const btCollisionObject* a, const btCollisionObject* b) {
                return a->getUserIndex() < b->getUserIndex();
              });
    for (btCollisionObject* obj : candidates) {
      PenetrationCallback cb;
      collision_world.contactPairTest(&uav_object, obj, cb);
      if (cb.hit) {
        crash(names[static_cast<std::size_t>(obj->getUserIndex())]);
        return;
      }
    }
  }

  QuadrotorParams params;
  SimSettings settings;
  double dt;
  std::vector<scenario::ScenarioEntity> entities;
  scenario::TrajectoryPoint start;
  CascadedController controller;
  Mixer mixer;
  WindModel wind;
  ControlSetpoint sp;
  UavState s;
  std::int64_t steps = 0;
  Eigen::Matrix3d inertia_inv;
  double alpha_up = 0, alpha_down = 0;
  Vec3 half;

  // Declared before the collision world, so that they outlive it (its destructor releases the
  // objects' broadphase proxies).
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btCollisionObject>> objects;
  btDefaultCollisionConfiguration collision_config;
  btCollisionDispatcher dispatcher;
  btDbvtBroadphase broadphase;
  btCollisionWorld collision_world;
  btBoxShape uav_shape;
  btCollisionObject uav_object;
  std::vector<std::string> names;
  std::vector<Mover> movers;
  std::vector<btCollisionObject*> candidates;
  int static_count = 0;
};

Simulator::Simulator(const scenario::World& world, const scenario::SimConfig& config,
                     const QuadrotorParams& uav, const SimSettings& settings) {
  settings.validate();
  uav.validate();
  impl_ = std::make_unique<Impl>(world, config, uav, settings);
}

Simulator::~Simulator() = default;

void Simulator::step() { impl_->step(); }
void Simulator::step(int n) {
  for (int i = 0; i < n; ++i) impl_->step();
}
double Simulator::time() const { return impl_->steps * impl_->dt; }
double Simulator::dt() const { return impl_->dt; }
std::int64_t Simulator::stepCount() const { return impl_->steps; }

void Simulator::setVelocitySetpoint(const Vec3& velocity, double yaw_rate) {
  if (impl_->s.crashed) return;
  impl_->sp.mode = ControlMode::kVelocity;
  impl_->sp.velocity = velocity;
  impl_->sp.yaw_rate = yaw_rate;
}

void Simulator::setPositionSetpoint(const Vec3& position, double yaw) {
  if (impl_->s.crashed) return;
  impl_->sp.mode = ControlMode::kPosition;
  impl_->sp.position = position;
  impl_->sp.yaw = yaw;
}

void Simulator::setAttitudeSetpoint(const Quat& attitude, double thrust) {
  if (impl_->s.crashed) return;
  impl_->sp.mode = ControlMode::kAttitude;
  impl_->sp.attitude = attitude;
  impl_->sp.thrust = thrust;
}

void Simulator::setRotorCommands(const Eigen::Vector4d& speeds) {
  if (impl_->s.crashed) return;
  impl_->sp.mode = ControlMode::kRotors;
  for (int i = 0; i < 4; ++i) {
    const double w = speeds[i];
    impl_->sp.rotor_speeds[i] =
        std::isfinite(w) ? std::clamp(w, 0.0, impl_->params.max_speed) : 0.0;
  }
}

void Simulator::disarm() { impl_->sp = ControlSetpoint(); }

void Simulator::reset() { impl_->resetState(); }

const UavState& Simulator::uav() const { return impl_->s; }
const QuadrotorParams& Simulator::params() const { return impl_->params; }

std::vector<EntityState> Simulator::scenarioEntities() const {
  std::vector<EntityState> out;
  out.reserve(impl_->entities.size());
  const double t = time();
  for (const auto& se : impl_->entities) {
    EntityState st;
    st.id = se.entity.id;
    st.cls = se.entity.cls;
    st.role = se.role;
    st.box = se.entity.box;
    if (!se.trajectory.empty()) {
      st.box = scenario::poseBox(se.entity.box, scenario::sampleTrajectory(se.trajectory, t));
      trajectoryRates(se.trajectory, t, &st.velocity, &st.yaw_rate);
    }
    out.push_back(std::move(st));
  }
  return out;
}

Vec3 Simulator::wind() const { return impl_->wind.wind(); }
int Simulator::staticObjectCount() const { return impl_->static_count; }
int Simulator::moverCount() const { return static_cast<int>(impl_->movers.size()); }

}  // namespace hameritt::sim
