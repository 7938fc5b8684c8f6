#include "hameritt/scenario/validation.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <unordered_map>
#include <utility>

#include "hameritt/geometry/polygon.h"
#include "hameritt/scenario/bounded_json.h"
#include "hameritt/scenario/params_table.h"
#include "hameritt/scenario/scenario_io.h"

namespace hameritt::scenario {

using geometry::Polygon;
using geometry::Vec2;
using nlohmann::json;

namespace {

// ------------------------------------------------------------------ small helpers

const std::set<std::string> kAnnotations = {"$schema",     "$id",     "$comment", "title",
                                            "description", "default", "examples", "definitions"};
const std::set<std::string> kKeywords = {"type",
                                         "properties",
                                         "required",
                                         "additionalProperties",
                                         "items",
                                         "minItems",
                                         "maxItems",
                                         "uniqueItems",
                                         "minLength",
                                         "maxLength",
                                         "minimum",
                                         "maximum",
                                         "exclusiveMinimum",
                                         "exclusiveMaximum",
                                         "enum",
                                         "const",
                                         "pattern",
                                         "$ref",
                                         "anyOf",
                                         "oneOf"};
const std::set<std::string> kTypes = {"null",   "boolean", "object", "array",
                                      "number", "integer", "string"};

// A value for a message, shortened.
std::string brief(const json& v) {
  std::string s = v.dump();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

std::string num(double v) {
  std::ostringstream os;
  os.precision(12);
  os << v;
  return os.str();
}

bool isInteger(const json& v) {
  if (v.is_number_integer()) return true;
  if (!v.is_number_float()) return false;
  const double d = v.get<double>();
  return std::isfinite(d) && std::floor(d) == d;
}

bool typeMatches(const json& v, const std::string& t) {
  if (t == "null") return v.is_null();
  if (t == "boolean") return v.is_boolean();
  if (t == "object") return v.is_object();
  if (t == "array") return v.is_array();
  if (t == "number") return v.is_number();
  if (t == "integer") return isInteger(v);
  if (t == "string") return v.is_string();
  return false;
}

// The JSON Schema type name of a value ("integer" for integral numbers).
std::string typeOf(const json& v) {
  if (v.is_number()) return isInteger(v) ? "integer" : "number";
  return v.type_name();
}

// Length in Unicode code points of a UTF-8 string.
std::size_t codePoints(const std::string& s) {
  std::size_t n = 0;
  for (unsigned char c : s) {
    if ((c & 0xC0) != 0x80) ++n;
  }
  return n;
}

bool isNonNegativeInteger(const json& v) { return isInteger(v) && v.get<double>() >= 0; }

// v as a T when it is an integer (integer-valued floats included) that T holds exactly;
// nullopt otherwise (a fraction, 1e300, 2^64, or a negative for an unsigned T). Converting an
// out-of-range double is undefined behaviour, so every integer read goes through here.
template <typename T>
std::optional<T> integerAs(const json& v) {
  using Limits = std::numeric_limits<T>;
  if (v.is_number_unsigned()) {
    const auto u = v.get<std::uint64_t>();
    if (u > static_cast<std::uint64_t>(Limits::max())) return std::nullopt;
    return static_cast<T>(u);
  }
  if (v.is_number_integer()) {
    const auto i = v.get<std::int64_t>();
    if (i < 0 && !Limits::is_signed) return std::nullopt;
    if (Limits::is_signed && (i < static_cast<std::int64_t>(Limits::min()) ||
                              i > static_cast<std::int64_t>(Limits::max()))) {
      return std::nullopt;
    }
    return static_cast<T>(i);
  }
  if (!isInteger(v)) return std::nullopt;
  const double d = v.get<double>();
  const double limit = std::ldexp(1.0, Limits::digits);  // 2^bits: the first value T lacks
  if (d >= limit || d < (Limits::is_signed ? -limit : 0.0)) return std::nullopt;
  return static_cast<T>(d);
}

}  // namespace

std::string jsonPointerAppend(const std::string& pointer, const std::string& token) {
  std::string out = pointer + "/";
  for (char c : token) {
    if (c == '~')
      out += "~0";
    else if (c == '/')
      out += "~1";
    else
      out += c;
  }
  return out;
}

std::string jsonPointerAppend(const std::string& pointer, std::size_t index) {
  return pointer + "/" + std::to_string(index);
}

// ------------------------------------------------------------------ JsonSchema

JsonSchema::JsonSchema(json schema, std::string name)
    : schema_(std::move(schema)), name_(std::move(name)) {
  compile(schema_, "");
}

JsonSchema JsonSchema::load(const std::string& path) {
  return JsonSchema(readJsonFile(path), path);
}

void JsonSchema::compile(const json& s, const std::string& spath) {
  auto fail = [&](const std::string& where, const std::string& what) {
    throw SchemaError(name_ + ": " + (where.empty() ? std::string("(root)") : where) + ": " + what,
                      where);
  };
  if (s.is_boolean()) return;
  if (!s.is_object()) fail(spath, "a schema must be an object or a boolean, got " + brief(s));
  const bool has_ref = s.contains("$ref");
  for (auto it = s.begin(); it != s.end(); ++it) {
    const std::string& k = it.key();
    const json& v = it.value();
    const std::string at = jsonPointerAppend(spath, k);
    if (kAnnotations.count(k)) {
      if (k == "definitions") {
        if (!v.is_object()) fail(at, "expected an object of schemas");
        for (auto d = v.begin(); d != v.end(); ++d)
          compile(d.value(), jsonPointerAppend(at, d.key()));
      }
      continue;
    }
    if (!kKeywords.count(k)) fail(at, "unsupported keyword '" + k + "'");
    if (has_ref && k != "$ref") {
      fail(at,
           "'" + k +
               "' next to $ref would be ignored (draft-07); move it into the referenced schema");
    }
    if (k == "$ref") {
      if (!v.is_string()) fail(at, "expected a string");
      resolve(v.get<std::string>(), at);
    } else if (k == "type") {
      std::vector<json> names =
          v.is_array() ? std::vector<json>(v.begin(), v.end()) : std::vector<json>{v};
      if (names.empty()) fail(at, "expected a type name or a non-empty array of them");
      for (const auto& n : names) {
        if (!n.is_string() || !kTypes.count(n.get<std::string>()))
          fail(at, "unknown type " + brief(n));
      }
    } else if (k == "properties") {
      if (!v.is_object()) fail(at, "expected an object of schemas");
      for (auto p = v.begin(); p != v.end(); ++p)
        compile(p.value(), jsonPointerAppend(at, p.key()));
    } else if (k == "required") {
      if (!v.is_array()) fail(at, "expected an array of key names");
      for (const auto& n : v) {
        if (!n.is_string()) fail(at, "expected an array of key names");
      }
    } else if (k == "additionalProperties" || k == "items") {
      if (v.is_array()) fail(at, "an array of schemas (tuple validation) is not supported");
      compile(v, at);
    } else if (k == "minItems" || k == "maxItems" || k == "minLength" || k == "maxLength") {
      if (!integerAs<std::size_t>(v)) fail(at, "expected a non-negative integer below 2^64");
    } else if (k == "uniqueItems") {
      if (!v.is_boolean()) fail(at, "expected a boolean");
    } else if (k == "minimum" || k == "maximum" || k == "exclusiveMinimum" ||
               k == "exclusiveMaximum") {
      if (!v.is_number()) fail(at, "expected a number (draft-07 form)");
    } else if (k == "enum") {
      if (!v.is_array() || v.empty()) fail(at, "expected a non-empty array");
    } else if (k == "pattern") {
      if (!v.is_string()) fail(at, "expected a string");
      try {
        patterns_.emplace(v.get<std::string>(),
                          std::regex(v.get<std::string>(), std::regex::ECMAScript));
      } catch (const std::regex_error& e) {
        fail(at, std::string("invalid regular expression: ") + e.what());
      }
    } else if (k == "anyOf" || k == "oneOf") {
      if (!v.is_array() || v.empty()) fail(at, "expected a non-empty array of schemas");
      for (std::size_t i = 0; i < v.size(); ++i) compile(v[i], jsonPointerAppend(at, i));
    }
    // "const" accepts any value.
  }
}

const json& JsonSchema::resolve(const std::string& ref, const std::string& spath) const {
  if (ref == "#") return schema_;
  if (ref.size() < 2 || ref.compare(0, 2, "#/") != 0) {
    throw SchemaError(name_ + ": " + spath +
                          ": only local references (\"#/...\") are supported, got '" + ref + "'",
                      spath);
  }
  try {
    return schema_.at(json::json_pointer(ref.substr(1)));
  } catch (const json::exception&) {
    throw SchemaError(name_ + ": " + spath + ": unresolvable $ref '" + ref + "'", spath);
  }
}

void JsonSchema::validate(const json& doc, const std::string& file,
                          std::vector<ValidationIssue>* issues) const {
  check(doc, schema_, "", 0, file, issues);
}

std::vector<ValidationIssue> JsonSchema::validate(const json& doc) const {
  std::vector<ValidationIssue> out;
  validate(doc, "", &out);
  return out;
}

void JsonSchema::check(const json& doc, const json& s, const std::string& path, int depth,
                       const std::string& file, std::vector<ValidationIssue>* out) const {
  auto issue = [&](const std::string& p, const std::string& rule, const std::string& msg) {
    out->push_back({file, p, rule, msg});
  };
  if (depth > 256) {
    issue(path, "schema", name_ + ": $ref recursion deeper than 256 levels");
    return;
  }
  if (s.is_boolean()) {
    if (!s.get<bool>()) issue(path, "false", "no value is allowed here");
    return;
  }
  if (auto r = s.find("$ref"); r != s.end()) {
    check(doc, resolve(r->get<std::string>(), ""), path, depth + 1, file, out);
    return;
  }
  if (auto t = s.find("type"); t != s.end()) {
    bool ok = false;
    std::string names;
    const std::vector<json> ts =
        t->is_array() ? std::vector<json>(t->begin(), t->end()) : std::vector<json>{*t};
    for (const auto& n : ts) {
      ok = ok || typeMatches(doc, n.get<std::string>());
      names += (names.empty() ? "" : " or ") + n.get<std::string>();
    }
    if (!ok) {
      issue(path, "type", "expected " + names + ", got " + typeOf(doc) + " " + brief(doc));
      return;  // the other keywords would only repeat the mismatch
    }
  }
  if (auto c = s.find("const"); c != s.end() && doc != *c) {
    issue(path, "const", "expected " + brief(*c) + ", got " + brief(doc));
  }
  if (auto e = s.find("enum"); e != s.end() && std::find(e->begin(), e->end(), doc) == e->end()) {
    std::string opts;
    for (const auto& o : *e) opts += (opts.empty() ? "" : ", ") + o.dump();
    issue(path, "enum", "expected one of " + opts + "; got " + brief(doc));
  }
  if (doc.is_number()) {
    const double d = doc.get<double>();
    if (auto m = s.find("minimum"); m != s.end() && !(d >= m->get<double>())) {
      issue(path, "minimum", "expected >= " + m->dump() + ", got " + doc.dump());
    }
    if (auto m = s.find("maximum"); m != s.end() && !(d <= m->get<double>())) {
      issue(path, "maximum", "expected <= " + m->dump() + ", got " + doc.dump());
    }
    if (auto m = s.find("exclusiveMinimum"); m != s.end() && !(d > m->get<double>())) {
      issue(path, "exclusiveMinimum", "expected > " + m->dump() + ", got " + doc.dump());
    }
    if (auto m = s.find("exclusiveMaximum"); m != s.end() && !(d < m->get<double>())) {
      issue(path, "exclusiveMaximum", "expected < " + m->dump() + ", got " + doc.dump());
    }
  }
  if (doc.is_string()) {
    const std::string& str = doc.get_ref<const std::string&>();
    const std::size_t n = codePoints(str);
    if (auto m = s.find("minLength"); m != s.end() && n < *integerAs<std::size_t>(*m)) {
      issue(path, "minLength", "expected at least " + m->dump() + " characters, got " + brief(doc));
    }
    if (auto m = s.find("maxLength"); m != s.end() && n > *integerAs<std::size_t>(*m)) {
      issue(path, "maxLength", "expected at most " + m->dump() + " characters, got " + brief(doc));
    }
    if (auto p = s.find("pattern"); p != s.end()) {
      const auto& re = patterns_.at(p->get<std::string>());
      if (!std::regex_search(str, re)) {
        issue(path, "pattern", "expected a string matching " + p->dump() + ", got " + brief(doc));
      }
    }
  }
  if (doc.is_array()) {
    if (auto m = s.find("minItems"); m != s.end() && doc.size() < *integerAs<std::size_t>(*m)) {
      issue(path, "minItems",
            "expected at least " + m->dump() + " items, got " + std::to_string(doc.size()));
    }
    if (auto m = s.find("maxItems"); m != s.end() && doc.size() > *integerAs<std::size_t>(*m)) {
      issue(path, "maxItems",
            "expected at most " + m->dump() + " items, got " + std::to_string(doc.size()));
    }
    if (auto u = s.find("uniqueItems"); u != s.end() && u->get<bool>()) {
      for (std::size_t i = 1; i < doc.size(); ++i) {
        for (std::size_t j = 0; j < i; ++j) {
          if (doc[i] == doc[j]) {
            issue(jsonPointerAppend(path, i), "uniqueItems",
                  "item " + brief(doc[i]) + " repeats item " + std::to_string(j));
            break;
          }
        }
      }
    }
    if (auto it = s.find("items"); it != s.end()) {
      for (std::size_t i = 0; i < doc.size(); ++i) {
        check(doc[i], *it, jsonPointerAppend(path, i), depth + 1, file, out);
      }
    }
  }
  if (doc.is_object()) {
    if (auto r = s.find("required"); r != s.end()) {
      for (const auto& k : *r) {
        if (!doc.contains(k.get<std::string>())) {
          issue(path, "required", "missing required key '" + k.get<std::string>() + "'");
        }
      }
    }
    const auto props = s.find("properties");
    const auto extra = s.find("additionalProperties");
    for (auto m = doc.begin(); m != doc.end(); ++m) {
      const std::string p = jsonPointerAppend(path, m.key());
      if (props != s.end() && props->contains(m.key())) {
        check(m.value(), props->at(m.key()), p, depth + 1, file, out);
      } else if (extra != s.end()) {
        if (extra->is_boolean() && !extra->get<bool>()) {
          issue(p, "additionalProperties", "unknown key '" + m.key() + "'");
        } else {
          check(m.value(), *extra, p, depth + 1, file, out);
        }
      }
    }
  }
  for (const char* k : {"anyOf", "oneOf"}) {
    auto alts = s.find(k);
    if (alts == s.end()) continue;
    int matched = 0;
    std::string first_reason;
    for (const auto& alt : *alts) {
      std::vector<ValidationIssue> sub;
      check(doc, alt, path, depth + 1, file, &sub);
      if (sub.empty())
        ++matched;
      else if (first_reason.empty())
        first_reason = sub.front().path + ": " + sub.front().message;
    }
    const std::string n = std::to_string(alts->size());
    if (matched == 0) {
      issue(path, k, "matches none of the " + n + " alternatives (first: " + first_reason + ")");
    } else if (std::string(k) == "oneOf" && matched > 1) {
      issue(path, k,
            "matches " + std::to_string(matched) + " of the " + n +
                " alternatives, expected exactly one");
    }
  }
}

// ------------------------------------------------------------------ document kinds

namespace {

struct KindName {
  DocumentKind kind;
  const char* schema;
  const char* file;
};
constexpr KindName kKinds[] = {
    {DocumentKind::kMission, "hameritt/mission", "mission"},
    {DocumentKind::kSimConfig, "hameritt/sim_config", "sim_config"},
    {DocumentKind::kWorld, "hameritt/world", "world"},
    {DocumentKind::kManifest, "hameritt/manifest", "manifest"},
};

// ------------------------------------------------------------------ semantic checks

const json* member(const json& j, const char* key) {
  if (!j.is_object()) return nullptr;
  auto it = j.find(key);
  return it == j.end() ? nullptr : &*it;
}

const json& arrayOrEmpty(const json& j, const char* key) {
  static const json kEmpty = json::array();
  const json* m = member(j, key);
  return m && m->is_array() ? *m : kEmpty;
}

std::optional<double> numberAt(const json& j, const char* key) {
  const json* m = member(j, key);
  if (!m || !m->is_number()) return std::nullopt;
  return m->get<double>();
}

std::optional<std::string> stringAt(const json& j, const char* key) {
  const json* m = member(j, key);
  if (!m || !m->is_string()) return std::nullopt;
  return m->get<std::string>();
}

bool toPoint(const json& j, Vec2* out) {
  if (!j.is_array() || j.size() != 2 || !j[0].is_number() || !j[1].is_number()) return false;
  *out = Vec2(j[0].get<double>(), j[1].get<double>());
  return true;
}

bool toPoints(const json& j, std::vector<Vec2>* out) {
  if (!j.is_array()) return false;
  out->clear();
  for (const auto& p : j) {
    Vec2 v;
    if (!toPoint(p, &v)) return false;
    out->push_back(v);
  }
  return true;
}

class Semantics {
 public:
  Semantics(const json& doc, std::string file, const std::vector<ValidationIssue>& schema_issues,
            std::vector<ValidationIssue>* out)
      : doc_(doc), file_(std::move(file)), schema_issues_(schema_issues), out_(out) {}

  void run(DocumentKind kind) {
    switch (kind) {
      case DocumentKind::kMission:
        mission();
        break;
      case DocumentKind::kSimConfig:
        simConfig();
        break;
      case DocumentKind::kWorld:
        world();
        break;
      case DocumentKind::kManifest:
        manifest();
        break;
    }
  }

 private:
  // Ids of one namespace: reports a repeated id at its position.
  class IdSet {
   public:
    IdSet(Semantics* s, std::string what) : s_(s), what_(std::move(what)) {}
    // Notes item[key] (a string) found at item_path; false when it repeats.
    bool note(const json& item, const std::string& item_path, const char* key = "id") {
      const auto id = stringAt(item, key);
      if (!id) return true;
      const std::string p = jsonPointerAppend(item_path, key);
      auto [it, fresh] = first_.emplace(*id, p);
      if (!fresh) {
        s_->add(p, "unique_id",
                "duplicate " + what_ + " '" + *id + "' (first at " + it->second + ")");
      }
      return fresh;
    }
    bool has(const std::string& id) const { return first_.count(id) > 0; }

   private:
    Semantics* s_;
    std::string what_;
    std::unordered_map<std::string, std::string> first_;
  };

  void add(const std::string& path, const std::string& rule, const std::string& message) {
    out_->push_back({file_, path, rule, message});
  }

  // True when the schema reported something at or below `path`.
  bool schemaFlagged(const std::string& path) const {
    for (const auto& i : schema_issues_) {
      if (i.path == path || i.path.compare(0, path.size() + 1, path + "/") == 0) return true;
    }
    return false;
  }

  // A simple polygon from j, or nullopt (reported when the points are there but the ring is
  // not simple; malformed point lists are the schema's to report).
  std::optional<Polygon> polygon(const json& j, const std::string& path) {
    std::vector<Vec2> pts;
    if (!toPoints(j, &pts) || pts.size() < 3) return std::nullopt;
    if (pts.size() > 3 && pts.front() == pts.back()) {
      add(path, "polygon_simple",
          "the first vertex is repeated as the last; rings close implicitly, "
          "so this ring has a zero-length edge");
      return std::nullopt;
    }
    Polygon p(pts);
    if (!p.isSimple()) {
      add(path, "polygon_simple",
          "polygon of " + std::to_string(pts.size()) +
              " vertices is not simple (edges cross or touch, a vertex "
              "repeats, or the area is zero)");
      return std::nullopt;
    }
    return p;
  }

  void timeWindow(const json& owner, const std::string& owner_path) {
    const json* tw = member(owner, "time_window");
    if (!tw) return;
    const auto net = numberAt(*tw, "net"), nlt = numberAt(*tw, "nlt");
    if (net && nlt && *net > *nlt) {
      add(jsonPointerAppend(owner_path, "time_window"), "time_window",
          "net " + num(*net) + " is later than nlt " + num(*nlt));
    }
  }

  void altitude(const json& alt, const std::string& path) {
    const auto lo = numberAt(alt, "min"), hi = numberAt(alt, "max");
    if (lo && hi && *lo > *hi) {
      add(path, "altitude", "min " + num(*lo) + " is above max " + num(*hi));
    }
  }

  // scenario_id must be "<class>-<16 hex digits of seed>".
  void scenarioId(const json& entry, const std::string& path) {
    const auto id = stringAt(entry, "id") ? stringAt(entry, "id") : stringAt(entry, "scenario_id");
    const auto cls = stringAt(entry, "class");
    const json* seed = member(entry, "seed");
    if (!id || !cls || !seed || !isNonNegativeInteger(*seed)) return;
    const auto seed_value = integerAs<std::uint64_t>(*seed);
    if (!seed_value) {
      add(path, "scenario_id", "expected a seed below 2^64, got " + seed->dump());
      return;
    }
    const std::string want = *cls + "-" + hex64(*seed_value);
    if (*id != want) {
      add(path, "scenario_id",
          "expected '" + want + "' for class " + *cls + " and seed " + seed->dump() + ", got '" +
              *id + "'");
    }
  }

  // World parameters at `path` (present) must load like config/world.json does.
  void worldParams(const std::string& path) {
    if (schemaFlagged(path)) return;  // the schema already said what is wrong
    const json& params = doc_.at(json::json_pointer(path));
    try {
      worldParamsFromJson(params, file_);
    } catch (const ConfigError& e) {
      std::string msg = e.what();
      const std::string prefix = file_ + ": ";
      while (msg.compare(0, prefix.size(), prefix) == 0) msg = msg.substr(prefix.size());
      add(path, "world_params", msg);
    }
  }

  bool exists(const std::string& path) const {
    try {
      return doc_.contains(json::json_pointer(path));
    } catch (const json::exception&) {
      return false;
    }
  }

  // ---------------------------------------------------------------- mission.json
  void mission() {
    scenarioId(doc_, "/scenario_id");

    IdSet targets(this, "objective target id");
    if (const json* obj = member(doc_, "objective")) {
      const json& ts = arrayOrEmpty(*obj, "targets");
      for (std::size_t i = 0; i < ts.size(); ++i)
        targets.note(ts[i], "/objective/targets/" + std::to_string(i));
    }

    IdSet aoi_ids(this, "area of interest id");
    std::map<std::string, Polygon> aois;
    const json& aoi_list = arrayOrEmpty(doc_, "areas_of_interest");
    for (std::size_t i = 0; i < aoi_list.size(); ++i) {
      const std::string p = jsonPointerAppend("/areas_of_interest", i);
      aoi_ids.note(aoi_list[i], p);
      const json* poly = member(aoi_list[i], "polygon");
      std::optional<Polygon> pg = poly ? polygon(*poly, p + "/polygon") : std::nullopt;
      if (pg && stringAt(aoi_list[i], "id")) aois.emplace(*stringAt(aoi_list[i], "id"), *pg);
      timeWindow(aoi_list[i], p);
    }

    IdSet koz_ids(this, "keep-out zone id");
    const json& kozs = arrayOrEmpty(doc_, "keep_out_zones");
    for (std::size_t i = 0; i < kozs.size(); ++i) {
      const std::string p = jsonPointerAppend("/keep_out_zones", i);
      koz_ids.note(kozs[i], p);
      if (const json* poly = member(kozs[i], "polygon")) polygon(*poly, p + "/polygon");
      if (const json* alt = member(kozs[i], "altitude")) altitude(*alt, p + "/altitude");
      timeWindow(kozs[i], p);
    }

    priors(aoi_ids, aois);

    IdSet route_ids(this, "route id");
    const json& routes = arrayOrEmpty(doc_, "routes");
    for (std::size_t i = 0; i < routes.size(); ++i) {
      const std::string p = jsonPointerAppend("/routes", i);
      route_ids.note(routes[i], p);
      if (const json* band = member(routes[i], "band_polygon")) polygon(*band, p + "/band_polygon");
      std::vector<Vec2> line;
      if (const json* pl = member(routes[i], "polyline"); pl && toPoints(*pl, &line)) {
        for (std::size_t k = 1; k < line.size(); ++k) {
          if (line[k] == line[k - 1]) {
            add(jsonPointerAppend(p + "/polyline", k), "route_polyline",
                "point repeats the previous one");
          }
        }
      }
    }

    relations(targets);
  }

  void priors(const IdSet& aoi_ids, const std::map<std::string, Polygon>& aois) {
    IdSet cell_ids(this, "prior cell id");
    std::set<std::string> covered;
    const json& priors = arrayOrEmpty(doc_, "area_priors");
    for (std::size_t i = 0; i < priors.size(); ++i) {
      const json& pr = priors[i];
      const std::string p = jsonPointerAppend("/area_priors", i);
      const auto aoi_id = stringAt(pr, "aoi_id");
      const Polygon* aoi = nullptr;
      if (aoi_id) {
        if (!aoi_ids.has(*aoi_id)) {
          add(p + "/aoi_id", "prior_aoi", "no area of interest has id '" + *aoi_id + "'");
        } else if (!covered.insert(*aoi_id).second) {
          add(p + "/aoi_id", "prior_aoi", "a second prior for area of interest '" + *aoi_id + "'");
        }
        if (auto it = aois.find(*aoi_id); it != aois.end()) aoi = &it->second;
      }
      const json* depth = member(pr, "depth");
      const json& cells = arrayOrEmpty(pr, "cells");
      long n = -1;
      if (depth && isInteger(*depth) && depth->get<double>() >= 0 && depth->get<double>() <= 8) {
        n = 1L << depth->get<int>();
        if (static_cast<long>(cells.size()) != n * n) {
          add(p + "/cells", "prior_cells",
              "expected " + std::to_string(n * n) + " cells (" + std::to_string(n) + " x " +
                  std::to_string(n) + " for depth " + depth->dump() + "), got " +
                  std::to_string(cells.size()));
        }
      }
      std::set<std::pair<long, long>> places;
      double sum = 0.0;
      bool all_numbers = !cells.empty();
      for (std::size_t c = 0; c < cells.size(); ++c) {
        const json& cell = cells[c];
        const std::string cp = jsonPointerAppend(p + "/cells", c);
        cell_ids.note(cell, cp);
        const json* row = member(cell, "row");
        const json* col = member(cell, "col");
        const auto row_value = row ? integerAs<long>(*row) : std::nullopt;
        const auto col_value = col ? integerAs<long>(*col) : std::nullopt;
        if (row && col && isInteger(*row) && isInteger(*col) && !(row_value && col_value)) {
          add(cp, "prior_cells", "row " + row->dump() + ", col " + col->dump() +
                                     " lies outside the grid");
        } else if (row_value && col_value) {
          const long r = *row_value, k = *col_value;
          if (n > 0 && (r < 0 || r >= n || k < 0 || k >= n)) {
            add(cp, "prior_cells",
                "row " + std::to_string(r) + ", col " + std::to_string(k) + " lies outside the " +
                    std::to_string(n) + " x " + std::to_string(n) + " grid");
          } else if (!places.insert({r, k}).second) {
            add(cp, "prior_cells",
                "a second cell at row " + std::to_string(r) + ", col " + std::to_string(k));
          }
        }
        if (const json* poly = member(cell, "polygon")) {
          const auto pg = polygon(*poly, cp + "/polygon");
          if (pg && aoi) {
            for (const Vec2& v : pg->vertices()) {
              if (aoi->distance(v) > 0.01) {
                add(cp + "/polygon", "prior_cells",
                    "vertex (" + num(v.x()) + ", " + num(v.y()) +
                        ") lies outside area of interest '" + *aoi_id + "'");
                break;
              }
            }
          }
        }
        if (const auto prob = numberAt(cell, "probability"))
          sum += *prob;
        else
          all_numbers = false;
      }
      if (all_numbers && std::abs(sum - 1.0) > 1e-6) {
        add(p + "/cells", "prior_sum",
            "cell probabilities sum to " + num(sum) + ", expected 1 (within 1e-6)");
      }
    }
  }

  void relations(const IdSet& targets) {
    const json& rels = arrayOrEmpty(doc_, "scene_relations");
    for (std::size_t i = 0; i < rels.size(); ++i) {
      const json& r = rels[i];
      const std::string p = jsonPointerAppend("/scene_relations", i);
      if (const auto t = stringAt(r, "target"); t && !targets.has(*t)) {
        add(p + "/target", "relation_target",
            "'" + *t + "' is not among the objective's target ids");
      }
      const auto op_name = stringAt(r, "operator");
      RelationOp op;
      bool eventually = false;
      if (!op_name || !parseRelationOp(*op_name, &op, &eventually)) continue;  // schema: enum
      const bool part_of = op == RelationOp::kPartOf;
      const json* related = member(r, "related");
      const auto related_cls = related ? stringAt(*related, "class") : std::nullopt;
      if (related_cls && part_of != (*related_cls == "group")) {
        add(p + "/operator", "relation_operator",
            part_of
                ? "PART_OF relates the target to a group, but the related class is '" +
                      *related_cls + "'"
                : *op_name + " relates the target to an entity, but the related class is 'group'");
      }
      const json* ev = member(r, "evidence");
      if (!ev || !ev->is_object()) continue;
      const std::string ep = p + "/evidence";
      for (const char* k : {"distance", "bearing_deg", "dz", "line_of_sight"}) {
        if (part_of && ev->contains(k)) {
          add(ep, "relation_evidence",
              "PART_OF has no geometric evidence, but '" + std::string(k) + "' is given");
        } else if (!part_of && !ev->contains(k)) {
          add(ep, "relation_evidence",
              *op_name + " needs '" + std::string(k) + "' in its evidence");
        }
      }
      if (eventually && !ev->contains("time")) {
        add(ep, "relation_evidence", *op_name + " needs 'time', the first time it holds");
      } else if (!eventually && ev->contains("time")) {
        add(ep, "relation_evidence",
            "'time' is only given for EVENTUALLY_* operators, not " + *op_name);
      }
    }
  }

  // ---------------------------------------------------------------- sim_config.json
  void simConfig() {
    scenarioId(doc_, "/scenario_id");
    if (exists("/world/params")) worldParams("/world/params");

    IdSet ids(this, "entity id");
    bool has_target = false;
    const json& ents = arrayOrEmpty(doc_, "entities");
    for (std::size_t i = 0; i < ents.size(); ++i) {
      const std::string p = jsonPointerAppend("/entities", i);
      ids.note(ents[i], p);
      has_target = has_target || stringAt(ents[i], "role") == std::optional<std::string>("target");
      trajectoryOrder(arrayOrEmpty(ents[i], "trajectory"), p + "/trajectory");
    }
    if (!ents.empty() && !has_target)
      add("/entities", "role_target", "no entity has role 'target'");

    IdSet group_ids(this, "group id");
    const json& groups = arrayOrEmpty(doc_, "groups");
    for (std::size_t i = 0; i < groups.size(); ++i) {
      const std::string p = jsonPointerAppend("/groups", i);
      group_ids.note(groups[i], p);
      const json& members = arrayOrEmpty(groups[i], "members");
      for (std::size_t k = 0; k < members.size(); ++k) {
        if (members[k].is_string() && !ids.has(members[k].get<std::string>())) {
          add(jsonPointerAppend(p + "/members", k), "group_member",
              "'" + members[k].get<std::string>() + "' is not an entity of this scenario");
        }
      }
    }
    if (exists("/uav/altitude"))
      altitude(doc_.at(json::json_pointer("/uav/altitude")), "/uav/altitude");
    if (exists("/uav/perception_path")) perceptionPath(ents);
  }

  // Samples [t, x, y, z, yaw] of a timed path at `pointer`: t >= 0 and strictly increasing
  // (malformed samples are the schema's to report).
  void trajectoryOrder(const json& traj, const std::string& pointer) {
    double prev = 0.0;
    for (std::size_t k = 0; k < traj.size(); ++k) {
      if (!traj[k].is_array() || traj[k].empty() || !traj[k][0].is_number()) break;
      const double t = traj[k][0].get<double>();
      const std::string sp = jsonPointerAppend(pointer, k);
      if (k == 0 && t < 0) {
        add(sp, "trajectory_order", "t = " + num(t) + " is before the mission start");
      } else if (k > 0 && !(t > prev)) {
        add(sp, "trajectory_order",
            "t = " + num(t) + " does not increase on the previous sample's t = " + num(prev));
      }
      prev = t;
    }
  }

  // The perception-only flight: strictly increasing times from t >= 0, and every target it
  // claims to see is a target entity of this scenario.
  void perceptionPath(const json& ents) {
    const std::string base = "/uav/perception_path";
    const json& pp = doc_.at(json::json_pointer(base));
    trajectoryOrder(arrayOrEmpty(pp, "trajectory"), base + "/trajectory");
    std::set<std::string> targets;
    for (const auto& e : ents) {
      if (stringAt(e, "role") == std::optional<std::string>("target")) {
        if (auto id = stringAt(e, "id")) targets.insert(*id);
      }
    }
    const json& seen = arrayOrEmpty(pp, "targets_seen");
    for (std::size_t k = 0; k < seen.size(); ++k) {
      if (seen[k].is_string() && !targets.count(seen[k].get<std::string>())) {
        add(jsonPointerAppend(base + "/targets_seen", k), "reference",
            "'" + seen[k].get<std::string>() + "' is not a target of this scenario");
      }
    }
  }

  // ---------------------------------------------------------------- world.json
  void world() {
    if (exists("/params")) worldParams("/params");
    if (const json* b = member(doc_, "bounds")) {
      Vec2 lo, hi;
      const json* mn = member(*b, "min");
      const json* mx = member(*b, "max");
      if (mn && mx && toPoint(*mn, &lo) && toPoint(*mx, &hi) &&
          (lo.x() > hi.x() || lo.y() > hi.y())) {
        add("/bounds", "bounds", "min is not below max");
      }
    }
    // Entities first: edges and slots refer to them.
    IdSet ids(this, "entity id");
    std::unordered_map<std::string, std::string> classes;
    const json& ents = arrayOrEmpty(doc_, "entities");
    for (std::size_t i = 0; i < ents.size(); ++i) {
      const std::string p = jsonPointerAppend("/entities", i);
      if (ids.note(ents[i], p)) {
        if (const auto id = stringAt(ents[i], "id"))
          classes[*id] = stringAt(ents[i], "class").value_or("");
      }
    }
    const json& blocks = arrayOrEmpty(doc_, "blocks");
    for (std::size_t i = 0; i < ents.size(); ++i) {
      const json* b = member(ents[i], "block");
      if (b && isInteger(*b) && b->get<double>() >= static_cast<double>(blocks.size())) {
        add(jsonPointerAppend("/entities", i) + "/block", "reference",
            "block index " + b->dump() + " but there are " + std::to_string(blocks.size()) +
                " blocks");
      }
    }
    static const json kNone = json::object();
    const json* streets = member(doc_, "streets");
    const std::size_t n_nodes = arrayOrEmpty(streets ? *streets : kNone, "nodes").size();
    {
      const json& edges = arrayOrEmpty(streets ? *streets : kNone, "edges");
      for (std::size_t i = 0; i < edges.size(); ++i) {
        const std::string p = jsonPointerAppend("/streets/edges", i);
        const json* a = member(edges[i], "a");
        const json* b = member(edges[i], "b");
        for (const json* e : {a, b}) {
          if (e && isInteger(*e) && e->get<double>() >= static_cast<double>(n_nodes)) {
            add(p + (e == a ? "/a" : "/b"), "reference",
                "node index " + e->dump() + " but there are " + std::to_string(n_nodes) + " nodes");
          }
        }
        if (a && b && *a == *b)
          add(p, "reference", "the edge starts and ends at node " + a->dump());
        if (const auto ent = stringAt(edges[i], "entity")) {
          auto it = classes.find(*ent);
          if (it == classes.end() || it->second != "street") {
            add(p + "/entity", "reference", "'" + *ent + "' is not a street entity of this world");
          }
        }
      }
    }
    IdSet names(this, "block name");
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      const std::string p = jsonPointerAppend("/blocks", i);
      names.note(blocks[i], p, "name");
      if (const json* o = member(blocks[i], "outline")) polygon(*o, p + "/outline");
      std::vector<Vec2> ring;
      if (const json* sw = member(blocks[i], "sidewalk");
          sw && toPoints(*sw, &ring) && ring.size() >= 4) {
        if (ring.front() != ring.back()) {
          add(p + "/sidewalk", "sidewalk_ring", "the sidewalk ring must end at its first point");
        } else {
          ring.pop_back();
          if (!Polygon(ring).isSimple())
            add(p + "/sidewalk", "polygon_simple", "the sidewalk ring is not simple");
        }
      }
    }
    const json& slots = arrayOrEmpty(doc_, "parking_slots");
    for (std::size_t i = 0; i < slots.size(); ++i) {
      if (const auto occ = stringAt(slots[i], "occupant"); occ && !ids.has(*occ)) {
        add(jsonPointerAppend("/parking_slots", i) + "/occupant", "reference",
            "'" + *occ + "' is not an entity of this world");
      }
    }
  }

  // ---------------------------------------------------------------- manifest.json
  void manifest() {
    const json& scen = arrayOrEmpty(doc_, "scenarios");
    const json* count = member(doc_, "count");
    if (count && isInteger(*count) && count->get<double>() != static_cast<double>(scen.size())) {
      add("/scenarios", "manifest_count",
          "count is " + count->dump() + " but " + std::to_string(scen.size()) +
              " scenarios are listed");
    }
    const json& classes = arrayOrEmpty(doc_, "classes");
    IdSet ids(this, "scenario id");
    for (std::size_t i = 0; i < scen.size(); ++i) {
      const json& e = scen[i];
      const std::string p = jsonPointerAppend("/scenarios", i);
      ids.note(e, p);
      const json* index = member(e, "index");
      if (index && isInteger(*index) && index->get<double>() != static_cast<double>(i)) {
        add(p + "/index", "manifest_index",
            "expected index " + std::to_string(i) + ", got " + index->dump());
      }
      const auto cls = stringAt(e, "class");
      if (cls && !classes.empty() && classes[i % classes.size()] != *cls) {
        add(p + "/class", "manifest_class",
            "scenario " + std::to_string(i) + " should have class " +
                classes[i % classes.size()].dump() + " (classes[" + std::to_string(i) + " % " +
                std::to_string(classes.size()) + "])");
      }
      scenarioId(e, p + "/id");
      const auto id = stringAt(e, "id"), path = stringAt(e, "path");
      if (id && path && *id != *path) {
        add(p + "/path", "manifest_path",
            "expected the scenario directory '" + *id + "', got '" + *path + "'");
      }
    }
  }

  const json& doc_;
  std::string file_;
  const std::vector<ValidationIssue>& schema_issues_;
  std::vector<ValidationIssue>* out_;
};

}  // namespace

const char* schemaName(DocumentKind kind) {
  for (const auto& k : kKinds) {
    if (k.kind == kind) return k.schema;
  }
  return "";
}

std::string schemaFile(const std::string& schema_dir, DocumentKind kind) {
  for (const auto& k : kKinds) {
    if (k.kind == kind) return schema_dir + "/" + k.file + ".schema.json";
  }
  return "";
}

std::vector<ValidationIssue> validateDocument(const json& doc, const std::string& file,
                                              const std::string& schema_dir) {
  std::vector<ValidationIssue> issues;
  std::string known;
  for (const auto& k : kKinds) known += (known.empty() ? "" : ", ") + std::string(k.schema);
  if (!doc.is_object()) {
    issues.push_back({file, "", "schema_kind",
                      "expected a JSON object with a \"schema\" field (" + known + "), got " +
                          std::string(doc.type_name())});
    return issues;
  }
  const json* kind_field = member(doc, "schema");
  if (!kind_field) {
    issues.push_back(
        {file, "", "schema_kind", "missing \"schema\" field; expected one of " + known});
    return issues;
  }
  const KindName* kind = nullptr;
  for (const auto& k : kKinds) {
    if (kind_field->is_string() && kind_field->get<std::string>() == k.schema) kind = &k;
  }
  if (!kind) {
    issues.push_back(
        {file, "/schema", "schema_kind",
         "unknown document kind " + brief(*kind_field) + "; expected one of " + known});
    return issues;
  }
  const std::string schema_path = schemaFile(schema_dir, kind->kind);
  std::optional<JsonSchema> schema;
  try {
    schema.emplace(JsonSchema::load(schema_path));
  } catch (const SchemaError& e) {
    issues.push_back({schema_path, e.path(), "schema", e.what()});
    return issues;
  } catch (const ConfigError& e) {
    issues.push_back({schema_path, "", "schema", e.what()});
    return issues;
  }
  schema->validate(doc, file, &issues);
  const std::vector<ValidationIssue> schema_issues = issues;
  Semantics(doc, file, schema_issues, &issues).run(kind->kind);
  return issues;
}

bool parseJsonText(const std::string& text, const std::string& file, json* out,
                   ValidationIssue* issue) {
  try {
    checkJsonText(text, file);
  } catch (const ConfigError& e) {
    *issue = {file, "", "limit", std::string(e.what()).substr(file.size() + 2)};
    return false;
  }
  // Tracks the JSON Pointer of the value being parsed, to report duplicate keys.
  struct Frame {
    bool array = false;
    std::size_t next = 0;
    std::string pointer;
    std::set<std::string> keys;
    std::string key;
  };
  std::vector<Frame> stack;
  std::string duplicate;
  auto child = [&]() -> std::string {
    if (stack.empty()) return "";
    Frame& f = stack.back();
    return f.array ? jsonPointerAppend(f.pointer, f.next++) : jsonPointerAppend(f.pointer, f.key);
  };
  json::parser_callback_t cb = [&](int, json::parse_event_t ev, json& parsed) {
    switch (ev) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start: {
        Frame f;
        f.array = ev == json::parse_event_t::array_start;
        f.pointer = child();
        stack.push_back(std::move(f));
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        if (!stack.empty()) stack.pop_back();
        break;
      case json::parse_event_t::key:
        if (!stack.empty()) {
          Frame& f = stack.back();
          f.key = parsed.get<std::string>();
          if (!f.keys.insert(f.key).second && duplicate.empty()) {
            duplicate = jsonPointerAppend(f.pointer, f.key);
          }
        }
        break;
      case json::parse_event_t::value:
        child();
        break;
    }
    return true;
  };
  try {
    *out = json::parse(text, cb);
  } catch (const json::parse_error& e) {
    const std::size_t end = std::min<std::size_t>(e.byte > 0 ? e.byte - 1 : 0, text.size());
    std::size_t line = 1, col = 1;
    for (std::size_t i = 0; i < end; ++i) {
      if (text[i] == '\n')
        ++line, col = 1;
      else
        ++col;
    }
    std::string what = e.what();
    const auto at = what.find(": ", what.find("parse error"));
    if (at != std::string::npos) what = what.substr(at + 2);
    *issue = {file, "", "json",
              "malformed JSON at line " + std::to_string(line) + ", column " + std::to_string(col) +
                  ": " + what};
    return false;
  }
  if (!duplicate.empty()) {
    *issue = {file, duplicate, "json", "duplicate object key (a reader would keep only one value)"};
    return false;
  }
  return true;
}

std::vector<ValidationIssue> validateFile(const std::string& path, const std::string& schema_dir) {
  std::string text;
  try {
    text = readBoundedFile(path);
  } catch (const ConfigError& e) {
    // "PATH: cannot open file", "PATH: N bytes, more than the limit ...".
    const std::string what = std::string(e.what()).substr(path.size() + 2);
    return {{path, "", what.rfind("cannot", 0) == 0 ? "io" : "limit", what}};
  }
  json doc;
  ValidationIssue issue;
  if (!parseJsonText(text, path, &doc, &issue)) return {issue};
  return validateDocument(doc, path, schema_dir);
}

std::string formatIssue(const ValidationIssue& issue) {
  return issue.file + ": " + (issue.path.empty() ? std::string("(root)") : issue.path) + ": " +
         issue.rule + ": " + issue.message;
}

}  // namespace hameritt::scenario
