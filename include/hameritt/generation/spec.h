#pragma once
// The scenario language (.hspec files): what scenario to generate, as requirements on the
// target, its scene relations, the mission's constraints and the environment. parseSpec() reads
// and type-checks a file (with its imports and --param overrides) against a world's
// vocabulary; docs/reference/scenario-language.md has the grammar.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::generation {

// A syntax, type or name error in a spec: the message starts "file:line:column: " and ends
// with the source line and a caret under the column. Exit code 2, like every bad input.
class SpecError : public scenario::ConfigError {
 public:
  explicit SpecError(const std::string& what) : scenario::ConfigError(what) {}
};

// Where something was written.
struct SourcePos {
  std::string file;
  int line = 1;
  int column = 1;
};

// A number drawn per scenario: a constant, a uniform range, a truncated normal or a weighted
// choice. Every kind maps one uniform variate u in [0, 1) to a value (so that a Halton
// sequence can drive it). `integer`: the value is a whole number (counts).
struct Distribution {
  enum class Kind { kConstant, kRange, kNormal, kChoice };
  Kind kind = Kind::kConstant;
  double a = 0, b = 0;    // constant a; range [a, b]; normal mean a, stddev b
  double lo = 0, hi = 0;  // normal: truncation bounds
  std::vector<std::pair<double, double>> choices;  // (value, weight)
  bool integer = false;

  double draw(double u) const;
  // The value's support: every value draw() can give (within 1e-6, or 1e-3 for rounded
  // outputs when `milli`).
  bool contains(double v, bool milli = true) const;
  double minValue() const;
  double maxValue() const;
  std::string text() const;  // "range(17.5, 19)", "3", ...
};

// A value set for an attribute: `any`, or one of the listed values.
struct AttributeSet {
  std::string key;
  std::vector<std::string> values;  // empty: any
  SourcePos pos;
  bool matches(const scenario::Attributes& a) const;
};

// [related {attributes}] [not] [OPERATOR] target: a requirement on the target's scene.
// `probability` < 1 makes it soft: it holds in that fraction of the scenarios (the others get
// its negation).
struct Requirement {
  std::string text;  // as written, normalized: "garage RIGHT_OF target {color: white}"
  scenario::EntityClass related = scenario::EntityClass::kGarage;
  scenario::RelationOp op = scenario::RelationOp::kNextTo;
  bool eventually = false;
  bool negated = false;
  std::vector<AttributeSet> attributes;
  double probability = 1.0;
  SourcePos pos;
  bool matchesRelated(scenario::EntityClass cls, const scenario::Attributes& a) const;
};

// The target: count, look, parked or moving, where.
struct TargetSpec {
  int count = 0;                         // 0: not stated (the class decides)
  std::vector<AttributeSet> attributes;  // car attributes: vehicle_class, make, model, color
  std::optional<bool> moving;            // unset: the class decides
  std::string block;                     // "in block_07"
  std::string street;                    // "on \"Oak Street\""
  // "within 80 of bus_stop": the parked target's centre lies within this many metres of the
  // nearest landmark, an intersection or a world entity of that class (footprint). 0: none.
  double within = 0;
  std::string within_of;
  SourcePos within_pos;
  SourcePos pos;
};

// What the look-alikes share with the target and what tells them apart:
// confusers { share: [vehicle_class, color], told_apart_by: "garage LEFT_OF target" }.
struct ConfuserSpec {
  bool have_share = false;         // false: the same make, model and colour (the default)
  std::vector<std::string> share;  // of vehicle_class, make, model, color; the others differ
  std::string told_apart_by;       // a requirement's text, as written in the spec
  int told_apart = -1;             // its index in Spec::requirements; -1: none
  SourcePos share_pos, told_pos;
};

// koz PURPOSE over (target | block | street | aoi N | CLASS) {count, size, margin, length,
// alt: [lo, hi], net, nlt}: keep-out zones that every scenario gets, over the target's position
// at t = 0 (a square of `size` m along its heading), the block it is on (grown by `margin` m),
// its street (a band `length` m along it), the N-th AOI (grown by `margin` m) or the `count`
// world entities of CLASS nearest it (their footprints grown by `margin` m). Its numbers are
// settings "<key>.<name>" (key "koz1", "koz2", ...), drawn like the others.
struct KozSpec {
  std::string purpose;  // vantage_denial | access_denial | restricted
  std::string over;     // "target", "block", "street", "aoi" or an entity class of the world
  std::string key;      // "koz1", ...
  int aoi = 0;          // over aoi N: N (1-based)
  SourcePos pos, aoi_pos;
};

// A type-checked spec: everything the compiler needs, with its sources' hash.
struct Spec {
  std::string file;
  std::uint64_t hash = 0;  // FNV-1a of every source text read (imports too) and the overrides
  scenario::ScenarioClass cls = scenario::ScenarioClass::kAreaSearch;
  bool have_class = false;
  TargetSpec target;
  std::vector<Requirement> requirements;
  ConfuserSpec confusers;
  std::vector<KozSpec> kozs;
  // "section.key" -> distribution (mission.time_limit, aois.count, environment.snow, ...), in
  // the order first written.
  std::vector<std::pair<std::string, Distribution>> settings;
  std::map<std::string, Distribution> params;  // named parameters, after overrides

  const Distribution* setting(const std::string& key) const;
};

// Parses `path` (imports are resolved relative to the importing file), applies `overrides`
// ("name=value" from --param: the name must be a declared param, each given once) and checks
// every name against the world's vocabulary. Throws SpecError (syntax, type, names) or
// ConfigError (unreadable file, bad --param).
Spec parseSpec(const std::string& path, const std::vector<std::string>& overrides,
               const scenario::World& world);
// The world type a spec file asks for with `world suburb|city` (its imports included, the last
// one written wins), read before the world is built; "" when it names none or cannot be read
// (parseSpec() then reports why). parseSpec() refuses a spec whose world is not `world`'s.
std::string specWorld(const std::string& path);
// The same from source text named `file` (imports relative to the working directory).
Spec parseSpecText(const std::string& text, const std::string& file,
                   const std::vector<std::string>& overrides, const scenario::World& world);

// The keys each section accepts ("environment" -> time, snow, ...).
const std::map<std::string, std::vector<std::string>>& specSections();

// Edit distance with adjacent swaps (optimal string alignment), case-insensitive, for "did you
// mean".
int editDistance(const std::string& a, const std::string& b);
// The candidates near `name` (distance <= max(1, (|name| + 2) / 4)), nearest first.
std::vector<std::string> nearestNames(const std::string& name,
                                      const std::vector<std::string>& candidates);

}  // namespace hameritt::generation
