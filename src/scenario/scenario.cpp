#include "hameritt/scenario/scenario.h"

#include <utility>

namespace hameritt::scenario {

namespace {
struct ClassName {
  ScenarioClass cls;
  const char* name;
};
constexpr ClassName kClasses[] = {
    {ScenarioClass::kAreaSearch, "area_search"}, {ScenarioClass::kRouteSearch, "route_search"},
    {ScenarioClass::kPursuit, "pursuit"},        {ScenarioClass::kAvoid, "avoid"},
    {ScenarioClass::kFollow, "follow"},          {ScenarioClass::kTrack, "track"}};
struct OpName {
  RelationOp op;
  const char* name;
};
constexpr OpName kOps[] = {
    {RelationOp::kNextTo, "NEXT_TO"},           {RelationOp::kNotNextTo, "NOT_NEXT_TO"},
    {RelationOp::kOnTopOf, "ON_TOP_OF"},        {RelationOp::kNotOnTopOf, "NOT_ON_TOP_OF"},
    {RelationOp::kOrthogonalTo, "ORTHOGONAL_TO"}, {RelationOp::kInFrontOf, "IN_FRONT_OF"},
    {RelationOp::kRightOf, "RIGHT_OF"},         {RelationOp::kLeftOf, "LEFT_OF"},
    {RelationOp::kPartOf, "PART_OF"},
};
constexpr const char* kEventually = "EVENTUALLY_";
}  // namespace

geometry::Polygon kozPolygonAt(const KeepOutZone& k, double t) {
  if (k.motion.empty()) return k.polygon;
  const TrajectoryPoint p = sampleTrajectory(k.motion, t);
  const geometry::Vec2 d(p.x - k.motion.front().x, p.y - k.motion.front().y);
  std::vector<geometry::Vec2> v;
  v.reserve(k.polygon.size());
  for (const auto& q : k.polygon.vertices()) v.push_back(q + d);
  return geometry::Polygon(v);
}

const char* toString(ScenarioClass c) {
  for (const auto& k : kClasses) {
    if (k.cls == c) return k.name;
  }
  return "unknown";
}

namespace {
constexpr std::pair<PhaseType, const char*> kPhaseTypes[] = {{PhaseType::kSearch, "search"},
                                                             {PhaseType::kFollow, "follow"},
                                                             {PhaseType::kTrack, "track"},
                                                             {PhaseType::kAvoid, "avoid"}};
}  // namespace

const char* toString(PhaseType t) {
  for (const auto& [type, name] : kPhaseTypes) {
    if (type == t) return name;
  }
  return "unknown";
}

bool parsePhaseType(const std::string& s, PhaseType* out) {
  for (const auto& [type, name] : kPhaseTypes) {
    if (s == name) {
      *out = type;
      return true;
    }
  }
  return false;
}

bool parseScenarioClass(const std::string& s, ScenarioClass* out) {
  for (const auto& k : kClasses) {
    if (s == k.name) {
      *out = k.cls;
      return true;
    }
  }
  return false;
}

std::string toString(RelationOp op, bool eventually) {
  for (const auto& k : kOps) {
    if (k.op == op) return eventually ? std::string(kEventually) + k.name : std::string(k.name);
  }
  return "UNKNOWN";
}

bool parseRelationOp(const std::string& s, RelationOp* op, bool* eventually) {
  std::string name = s;
  *eventually = false;
  const std::string prefix = kEventually;
  if (name.compare(0, prefix.size(), prefix) == 0) {
    *eventually = true;
    name = name.substr(prefix.size());
    if (name == "PART_OF") return false;  // membership has no temporal form
  }
  for (const auto& k : kOps) {
    if (name == k.name) {
      *op = k.op;
      return true;
    }
  }
  return false;
}

}  // namespace hameritt::scenario
