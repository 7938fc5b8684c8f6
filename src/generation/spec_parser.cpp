// The scenario language: lexer, parser and type checker (docs/reference/scenario-language.md).

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <tuple>

#include "hameritt/generation/spec.h"
#include "hameritt/scenario/catalog.h"
#include "hameritt/scenario/relations.h"

namespace hameritt::generation {

using scenario::ConfigError;
using scenario::EntityClass;

namespace {

std::string fmtNum(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.12g", v);
  return buf;
}

std::string joinList(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ", ") + s;
  return out;
}

// ------------------------------------------------------------------ lexer
enum class Tok { kIdent, kNumber, kString, kPunct, kEnd };

struct Token {
  Tok kind = Tok::kEnd;
  std::string text;
  double number = 0;
  bool integer = false;
  int line = 1, column = 1;
};

struct Source {
  std::string file;
  std::string text;
  std::vector<std::string> lines;
};

[[noreturn]] void fail(const Source& src, int line, int column, const std::string& message) {
  std::string l = line >= 1 && line <= static_cast<int>(src.lines.size())
                      ? src.lines[static_cast<std::size_t>(line - 1)]
                      : std::string();
  std::string caret(static_cast<std::size_t>(std::max(0, column - 1)), ' ');
  for (std::size_t i = 0; i < caret.size() && i < l.size(); ++i) {
    if (l[i] == '\t') caret[i] = '\t';
  }
  throw SpecError(src.file + ":" + std::to_string(line) + ":" + std::to_string(column) +
                  ": error: " + message + "\n  " + l + "\n  " + caret + "^");
}

std::vector<Token> lex(const Source& src) {
  std::vector<Token> out;
  const std::string& s = src.text;
  int line = 1, col = 1;
  std::size_t i = 0;
  auto advance = [&](std::size_t n) {
    for (std::size_t k = 0; k < n && i < s.size(); ++k, ++i) {
      if (s[i] == '\n') {
        ++line;
        col = 1;
      } else {
        ++col;
      }
    }
  };
  while (i < s.size()) {
    const char c = s[i];
    if (c == '#') {
      while (i < s.size() && s[i] != '\n') advance(1);
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
      advance(1);
      continue;
    }
    Token t;
    t.line = line;
    t.column = col;
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      std::size_t j = i;
      while (j < s.size() && (std::isalnum(static_cast<unsigned char>(s[j])) || s[j] == '_')) ++j;
      t.kind = Tok::kIdent;
      t.text = s.substr(i, j - i);
      advance(j - i);
    } else if (std::isdigit(static_cast<unsigned char>(c)) ||
               ((c == '-' || c == '.') && i + 1 < s.size() &&
                std::isdigit(static_cast<unsigned char>(s[i + 1])))) {
      std::size_t j = i + (c == '-' ? 1 : 0);
      bool dot = false;
      while (j < s.size() && (std::isdigit(static_cast<unsigned char>(s[j])) ||
                              (s[j] == '.' && !dot && !(j + 1 < s.size() && s[j + 1] == '.')))) {
        if (s[j] == '.') dot = true;
        ++j;
      }
      t.kind = Tok::kNumber;
      t.text = s.substr(i, j - i);
      if (t.text.size() > 24) fail(src, line, col, "number too long: '" + t.text + "'");
      t.number = std::strtod(t.text.c_str(), nullptr);
      t.integer = !dot;
      if (!std::isfinite(t.number)) fail(src, line, col, "number out of range: '" + t.text + "'");
      advance(j - i);
    } else if (c == '"') {
      std::size_t j = i + 1;
      while (j < s.size() && s[j] != '"' && s[j] != '\n') ++j;
      if (j >= s.size() || s[j] != '"') fail(src, line, col, "unterminated string: expected '\"'");
      t.kind = Tok::kString;
      t.text = s.substr(i + 1, j - i - 1);
      advance(j + 1 - i);
    } else if (c == '.' && i + 1 < s.size() && s[i + 1] == '.') {
      t.kind = Tok::kPunct;
      t.text = "..";
      advance(2);
    } else if (std::string("{}(),:=|[]").find(c) != std::string::npos) {
      t.kind = Tok::kPunct;
      t.text = std::string(1, c);
      advance(1);
    } else {
      const unsigned char uc = static_cast<unsigned char>(c);
      char desc[32];
      if (uc < 32 || uc >= 127) {
        std::snprintf(desc, sizeof(desc), "byte 0x%02x", uc);
      } else {
        std::snprintf(desc, sizeof(desc), "'%c'", c);
      }
      fail(src, line, col, std::string("unexpected character ") + desc);
    }
    out.push_back(t);
  }
  Token end;
  end.line = line;
  end.column = col;
  out.push_back(end);
  return out;
}

std::string describe(const Token& t) {
  switch (t.kind) {
    case Tok::kEnd:
      return "the end of the file";
    case Tok::kString:
      return "\"" + t.text + "\"";
    default:
      return "'" + t.text + "'";
  }
}

// ------------------------------------------------------------------ vocabulary
// Attribute values of each class in this world (world entities, the car catalog, pedestrians).
class Vocabulary {
 public:
  explicit Vocabulary(const scenario::World& world) {
    for (const auto& e : world.entities()) {
      for (const auto& [k, v] : e.attributes.items) add(e.cls, k, valueText(v));
    }
    for (const auto& m : scenario::catalog::carModels()) {
      add(EntityClass::kCar, "vehicle_class", m.vehicle_class);
      add(EntityClass::kCar, "make", m.make);
      add(EntityClass::kCar, "model", m.model);
    }
    for (const auto& c : scenario::catalog::carColors()) add(EntityClass::kCar, "color", c);
    for (const auto& c : scenario::catalog::clothingColors()) {
      add(EntityClass::kPedestrian, "clothing_color", c);
    }
    add(EntityClass::kPedestrian, "activity", "walking");
    add(EntityClass::kPedestrian, "activity", "running");
    add(EntityClass::kPedestrian, "activity", "standing");
  }
  static std::string valueText(const scenario::AttributeValue& v) {
    if (const auto* s = std::get_if<std::string>(&v)) return *s;
    return std::to_string(std::get<std::int64_t>(v));
  }
  std::vector<std::string> keys(EntityClass c) const {
    std::vector<std::string> out;
    auto it = values_.find(c);
    if (it == values_.end()) return out;
    for (const auto& kv : it->second) out.push_back(kv.first);
    return out;
  }
  const std::set<std::string>* values(EntityClass c, const std::string& key) const {
    auto it = values_.find(c);
    if (it == values_.end()) return nullptr;
    auto jt = it->second.find(key);
    return jt == it->second.end() ? nullptr : &jt->second;
  }

 private:
  void add(EntityClass c, const std::string& k, const std::string& v) { values_[c][k].insert(v); }
  std::map<EntityClass, std::map<std::string, std::set<std::string>>> values_;
};

std::vector<std::string> classNames() {
  return {"street", "driveway", "house", "garage", "fence", "tree", "car", "pedestrian"};
}

std::vector<std::string> operatorNames() {
  std::vector<std::string> out;
  for (auto op : {scenario::RelationOp::kNextTo, scenario::RelationOp::kNotNextTo,
                  scenario::RelationOp::kOnTopOf, scenario::RelationOp::kNotOnTopOf,
                  scenario::RelationOp::kOrthogonalTo, scenario::RelationOp::kInFrontOf,
                  scenario::RelationOp::kRightOf, scenario::RelationOp::kLeftOf}) {
    out.push_back(scenario::toString(op));
    out.push_back(scenario::toString(op, true));
  }
  return out;
}

std::string nearestHint(const std::string& name, const std::vector<std::string>& all) {
  const auto near = nearestNames(name, all);
  if (near.empty()) return "";
  std::vector<std::string> q;
  for (std::size_t i = 0; i < near.size() && i < 3; ++i) q.push_back("'" + near[i] + "'");
  return "; did you mean " + joinList(q) + "?";
}

// `s` without spaces, to compare a requirement as written with its normalized text.
std::string squeeze(const std::string& s) {
  std::string out;
  for (char ch : s) {
    if (ch != ' ' && ch != '\t') out += ch;
  }
  return out;
}

// Limits of each section key: [min, max] and whether the value is a whole number.
struct KeyLimits {
  double min, max;
  bool integer;
};

// A koz statement's settings ("koz1.count" -> "count").
const std::map<std::string, KeyLimits>& kozLimits() {
  static const std::map<std::string, KeyLimits> k = {
      {"count", {1, 5, true}},      {"size", {10, 200, false}},   {"margin", {0, 30, false}},
      {"alt_min", {0, 400, false}}, {"alt_max", {5, 500, false}}, {"net", {0, 3600, false}},
      {"nlt", {1, 3600, false}},    {"length", {10, 400, false}},
  };
  return k;
}

const std::map<std::string, KeyLimits>& keyLimits();

const KeyLimits& limitsOf(const std::string& key) {
  if (key.rfind("koz", 0) == 0 && key.size() > 3 &&
      std::isdigit(static_cast<unsigned char>(key[3])))
    return kozLimits().at(key.substr(key.find('.') + 1));
  return keyLimits().at(key);
}

const std::map<std::string, KeyLimits>& keyLimits() {
  static const std::map<std::string, KeyLimits> k = {
      {"mission.time_limit", {60, 3600, false}},
      {"aois.count", {1, 5, true}},
      {"aois.length", {40, 800, false}},
      {"aois.width", {40, 800, false}},
      {"aois.window_probability", {0, 1, false}},
      {"aois.target_offset", {0, 300, false}},
      {"prior.depth", {1, 3, true}},
      {"kozs.count", {1, 5, true}},
      {"kozs.window_probability", {0, 1, false}},
      {"route.edges", {2, 10, true}},
      {"route.band", {20, 200, false}},
      {"confusers.count", {0, 16, true}},
      {"confusers.within", {80, 1000, false}},
      {"traffic.cars", {0, 48, true}},
      {"traffic.pedestrians", {0, 40, true}},
      {"environment.time", {0, 24, false}},
      {"environment.snow", {0, 1, false}},
      {"environment.rain", {0, 1, false}},
      {"environment.dust", {0, 1, false}},
      {"environment.fog", {0, 1, false}},
      {"environment.foliage", {0, 1, false}},
      {"environment.wind", {0, 30, false}},
      {"environment.gusts", {0, 1, false}},
      {"camera.front_pitch", {-10, 90, false}},
      {"camera.front_fov", {20, 150, false}},
      {"camera.down_fov", {20, 150, false}},
      {"camera.noise", {0, 0.5, false}},
      {"camera.salt_pepper", {0, 0.1, false}},
      {"camera.motion_blur", {0, 20, false}},
      {"uav.altitude_min", {2, 300, false}},
      {"uav.altitude_max", {5, 400, false}},
      {"uav.start_within", {200, 600, false}},
  };
  return k;
}

// Named periods of the day for environment.time, in hours.
const std::map<std::string, std::pair<double, double>>& periods() {
  static const std::map<std::string, std::pair<double, double>> k = {
      {"dawn", {5.5, 7.0}}, {"day", {9.0, 16.0}}, {"dusk", {17.5, 19.5}}, {"night", {21.0, 23.5}}};
  return k;
}

// ------------------------------------------------------------------ parser
// A setting's value before parameters are resolved: a distribution or a parameter name.
struct PendingValue {
  Distribution dist;
  std::string param;
  SourcePos pos;
  const Source* src = nullptr;
};

class Parser {
 public:
  Parser(const scenario::World& world) : vocab_(world) {}

  void parseFile(const std::string& path, const SourcePos* from, const Source* from_src) {
    std::error_code ec;
    const std::string canon = std::filesystem::weakly_canonical(path, ec).string();
    if (std::find(stack_.begin(), stack_.end(), canon) != stack_.end()) {
      fail(*from_src, from->line, from->column, "import cycle: '" + path + "' imports itself");
    }
    if (stack_.size() > 16)
      fail(*from_src, from->line, from->column, "imports nested too deep (16)");
    std::ifstream in(path, std::ios::binary);
    if (!in) {
      if (from)
        fail(*from_src, from->line, from->column, "cannot read imported spec '" + path + "'");
      throw ConfigError(path + ": cannot read spec file");
    }
    std::ostringstream ss;
    ss << in.rdbuf();
    if (ss.str().size() > (1u << 20)) throw ConfigError(path + ": spec file larger than 1 MiB");
    stack_.push_back(canon);
    parseText(ss.str(), path);
    stack_.pop_back();
  }

  void parseText(const std::string& text, const std::string& file) {
    auto src = std::make_unique<Source>();
    src->file = file;
    src->text = text;
    std::size_t start = 0;
    for (;;) {
      const std::size_t nl = text.find('\n', start);
      src->lines.push_back(
          text.substr(start, nl == std::string::npos ? std::string::npos : nl - start));
      if (nl == std::string::npos) break;
      start = nl + 1;
    }
    hashText(text);
    const Source* s = src.get();
    sources_.push_back(std::move(src));
    std::vector<Token> toks = lex(*s);
    std::size_t p = 0;
    const Source* saved_src = src_;
    std::vector<Token>* saved_toks = toks_;
    std::size_t* saved_p = p_;
    src_ = s;
    toks_ = &toks;
    p_ = &p;
    while (peek().kind != Tok::kEnd) statement();
    src_ = saved_src;
    toks_ = saved_toks;
    p_ = saved_p;
  }

  Spec finish(const std::vector<std::string>& overrides, const std::string& file) {
    spec_.file = file;
    // --param name=value: each a declared parameter, each given once.
    std::set<std::string> seen;
    for (const auto& o : overrides) {
      hashText("--param " + o);
      const auto eq = o.find('=');
      if (eq == std::string::npos || eq == 0) {
        throw ConfigError("--param: expected NAME=VALUE, got '" + o + "'");
      }
      const std::string name = o.substr(0, eq);
      if (!params_.count(name)) {
        std::vector<std::string> names;
        for (const auto& kv : params_) names.push_back(kv.first);
        throw ConfigError("--param: unknown parameter '" + name + "'" + nearestHint(name, names) +
                          (names.empty() ? "; this spec declares no parameters"
                                         : "; parameters of this spec: " + joinList(names)));
      }
      if (!seen.insert(name).second) {
        throw ConfigError("--param: parameter '" + name + "' given more than once");
      }
      auto src = std::make_unique<Source>();
      src->file = "--param " + name;
      src->text = o.substr(eq + 1);
      src->lines = {src->text};
      std::vector<Token> toks = lex(*src);
      std::size_t p = 0;
      src_ = src.get();
      toks_ = &toks;
      p_ = &p;
      PendingValue v = expression();
      if (peek().kind != Tok::kEnd) error("expected the end of the value, got " + describe(peek()));
      if (!v.param.empty()) error("a --param value is a number or a distribution, not a name");
      params_[name] = v;
      sources_.push_back(std::move(src));
    }
    for (const auto& [name, v] : params_) spec_.params[name] = resolve(v, "");
    for (const auto& [key, v] : settings_) {
      Distribution d = resolve(v, key);
      checkLimits(key, d, v);
      spec_.settings.emplace_back(key, d);
    }
    if (!spec_.have_class) {
      throw SpecError(file +
                      ":1:1: error: missing 'scenario' statement: expected 'scenario "
                      "area_search', 'scenario route_search' or 'scenario pursuit'");
    }
    checkClassRules();
    checkKozs();
    spec_.hash = hash_;
    return std::move(spec_);
  }

 private:
  // ---------------------------------------------------------------- tokens
  const Token& peek(std::size_t k = 0) const {
    const std::size_t i = std::min(*p_ + k, toks_->size() - 1);
    return (*toks_)[i];
  }
  Token take() {
    Token t = peek();
    if (*p_ < toks_->size() - 1) ++*p_;
    return t;
  }
  [[noreturn]] void error(const std::string& message, const Token* at = nullptr) const {
    const Token& t = at ? *at : peek();
    fail(*src_, t.line, t.column, message);
  }
  [[noreturn]] void errorAt(const SourcePos& pos, const Source* src,
                            const std::string& message) const {
    fail(*src, pos.line, pos.column, message);
  }
  SourcePos pos(const Token& t) const { return {src_->file, t.line, t.column}; }
  bool isPunct(const std::string& p, std::size_t k = 0) const {
    return peek(k).kind == Tok::kPunct && peek(k).text == p;
  }
  bool isWord(const std::string& w) const { return peek().kind == Tok::kIdent && peek().text == w; }
  void expectPunct(const std::string& p, const std::string& what) {
    if (!isPunct(p)) error("expected '" + p + "' " + what + ", got " + describe(peek()));
    take();
  }
  Token expectIdent(const std::string& what) {
    if (peek().kind != Tok::kIdent) error("expected " + what + ", got " + describe(peek()));
    return take();
  }
  void hashText(const std::string& s) {
    for (unsigned char c : s) {
      hash_ ^= c;
      hash_ *= 0x100000001b3ULL;
    }
    hash_ ^= 0xff;
    hash_ *= 0x100000001b3ULL;
  }

  // ---------------------------------------------------------------- statements
  void statement() {
    const Token t = peek();
    if (t.kind != Tok::kIdent) {
      error(
          "expected a statement (import, param, scenario, target, require, prefer or a "
          "section name), got " +
          describe(t));
    }
    if (t.text == "import") return importStatement();
    if (t.text == "world") return worldStatement();
    if (t.text == "param") return paramStatement();
    if (t.text == "scenario") return scenarioStatement();
    if (t.text == "target") return targetStatement();
    if (t.text == "require" || t.text == "prefer") return requirement();
    if (t.text == "koz") return kozStatement();
    if (specSections().count(t.text)) return section();
    std::vector<std::string> words = {"import",  "param",  "scenario", "target",
                                      "require", "prefer", "world",    "koz"};
    for (const auto& kv : specSections()) words.push_back(kv.first);
    error("unknown statement '" + t.text + "'" + nearestHint(t.text, words) +
          "; statements: " + joinList(words));
  }

  void importStatement() {
    const Token kw = take();
    if (peek().kind != Tok::kString)
      error("expected the imported file as a \"string\" after 'import', got " + describe(peek()));
    const Token f = take();
    std::filesystem::path p(f.text);
    if (p.is_relative()) p = std::filesystem::path(src_->file).parent_path() / p;
    const SourcePos at = pos(f);
    parseFile(p.string(), &at, src_);
    (void)kw;
  }

  // world suburb|city: the world type the spec is written for. hameritt_generate builds that
  // world (specWorld()); any other world is refused here.
  void worldStatement() {
    take();
    const Token w = expectIdent("a world type after 'world' (suburb, city)");
    scenario::WorldType type;
    if (!scenario::parseWorldType(w.text, &type)) {
      error("unknown world type '" + w.text + "'" + nearestHint(w.text, {"suburb", "city"}) +
                "; world types: suburb, city",
            &w);
    }
    if (type != world_type_) {
      error(std::string("this spec is written for the ") + scenario::toString(type) +
                " world; the world here is " + scenario::toString(world_type_) +
                " (hameritt_generate builds the spec's world; --world must agree)",
            &w);
    }
  }

  void paramStatement() {
    take();
    const Token name = expectIdent("a parameter name after 'param'");
    if (specSections().count(name.text) || name.text == "any" || periods().count(name.text) ||
        name.text == "range" || name.text == "normal" || name.text == "choice") {
      error("'" + name.text + "' is a reserved word and cannot name a parameter", &name);
    }
    expectPunct("=", "after the parameter name");
    PendingValue v = expression();
    if (!v.param.empty()) {
      // A parameter defined from another: copy its current value.
      auto it = params_.find(v.param);
      v = it->second;
    }
    params_[name.text] = v;
  }

  void scenarioStatement() {
    take();
    const Token c =
        expectIdent("a mission class after 'scenario' (area_search, route_search, pursuit)");
    scenario::ScenarioClass cls;
    // Specs describe the three search classes; avoid, follow and track are classes without
    // spec statements.
    if (!scenario::parseScenarioClass(c.text, &cls) || cls == scenario::ScenarioClass::kAvoid ||
        cls == scenario::ScenarioClass::kFollow || cls == scenario::ScenarioClass::kTrack) {
      const std::vector<std::string> all = {"area_search", "route_search", "pursuit"};
      error("unknown mission class '" + c.text + "'" + nearestHint(c.text, all) +
                "; classes: " + joinList(all),
            &c);
    }
    spec_.cls = cls;
    spec_.have_class = true;
    class_pos_ = pos(c);
    class_src_ = src_;
  }

  void targetStatement() {
    const Token kw = take();
    TargetSpec t;
    t.pos = pos(kw);
    target_src_ = src_;
    if (peek().kind == Tok::kNumber) {
      const Token n = take();
      if (!n.integer || n.number < 1 || n.number > 2)
        error("expected a target count of 1 or 2, got " + n.text, &n);
      t.count = static_cast<int>(n.number);
    }
    const Token c = expectIdent("the target's class ('car')");
    if (c.text != "car") {
      error("unknown target class '" + c.text + "'" + nearestHint(c.text, {"car"}) +
                "; targets are of class: car",
            &c);
    }
    if (isPunct("{")) t.attributes = attributes(EntityClass::kCar, "target car");
    for (;;) {
      if (isWord("parked")) {
        take();
        t.moving = false;
      } else if (isWord("moving")) {
        take();
        t.moving = true;
      } else if (isWord("in")) {
        take();
        const Token b = peek();
        if (b.kind != Tok::kIdent && b.kind != Tok::kString)
          error("expected a block name after 'in', got " + describe(b));
        take();
        std::vector<std::string> names;
        for (const auto& blk : world_blocks_) names.push_back(blk);
        if (std::find(names.begin(), names.end(), b.text) == names.end()) {
          error("unknown block '" + b.text + "'" + nearestHint(b.text, names) +
                    "; blocks in this world: " + joinList(names),
                &b);
        }
        t.block = b.text;
      } else if (isWord("within")) {
        const Token w = take();
        const Token d = peek();
        if (d.kind != Tok::kNumber || !(d.number > 0 && d.number <= 2000))
          error("expected a distance in metres in (0, 2000] after 'within', got " + describe(d));
        take();
        if (!isWord("of")) error("expected 'of' after the distance, got " + describe(peek()));
        take();
        const Token l = expectIdent("a landmark (intersection or a class of the world)");
        std::vector<std::string> marks = {"intersection"};
        for (const auto& c : world_classes_) marks.push_back(c);
        if (std::find(marks.begin(), marks.end(), l.text) == marks.end()) {
          error("unknown landmark '" + l.text + "'" + nearestHint(l.text, marks) +
                    "; landmarks in this world: " + joinList(marks),
                &l);
        }
        t.within = d.number;
        t.within_of = l.text;
        t.within_pos = pos(w);
      } else if (isWord("on")) {
        take();
        const Token s = peek();
        if (s.kind != Tok::kString)
          error("expected a street name as a \"string\" after 'on', got " + describe(s));
        take();
        const auto* names = vocab_.values(EntityClass::kStreet, "name");
        std::vector<std::string> all(
            names ? names->begin() : std::set<std::string>::const_iterator(),
            names ? names->end() : std::set<std::string>::const_iterator());
        if (!names || !names->count(s.text)) {
          error("unknown street '" + s.text + "'" + nearestHint(s.text, all) +
                    "; streets in this world: " + joinList(all),
                &s);
        }
        t.street = s.text;
      } else {
        break;
      }
    }
    spec_.target = t;
    have_target_ = true;
  }

  void requirement() {
    const Token kw = take();
    Requirement r;
    r.pos = pos(kw);
    if (kw.text == "prefer") {
      const Token p = peek();
      if (p.kind != Tok::kNumber)
        error("expected a probability after 'prefer' (e.g. prefer 0.3 ...), got " + describe(p));
      take();
      if (!(p.number > 0 && p.number < 1))
        error("expected a probability strictly between 0 and 1, got " + p.text, &p);
      r.probability = p.number;
    }
    if (isWord("not")) {
      take();
      r.negated = true;
    }
    const Token rel = expectIdent("the related entity's class (" + joinList(classNames()) + ")");
    if (!scenario::parseEntityClass(rel.text, &r.related)) {
      error("unknown entity class '" + rel.text + "'" + nearestHint(rel.text, classNames()) +
                "; classes: " + joinList(classNames()),
            &rel);
    }
    const Token op = expectIdent("a relation operator (NEXT_TO, RIGHT_OF, ...)");
    if (!scenario::parseRelationOp(op.text, &r.op, &r.eventually) ||
        r.op == scenario::RelationOp::kPartOf) {
      error("unknown relation operator '" + op.text + "'" + nearestHint(op.text, operatorNames()) +
                "; operators: " + joinList(operatorNames()),
            &op);
    }
    if (!scenario::operatorApplies(r.op, r.related)) {
      std::vector<std::string> ok;
      for (const auto& c : classNames()) {
        EntityClass ec;
        scenario::parseEntityClass(c, &ec);
        if (scenario::operatorApplies(r.op, ec)) ok.push_back(c);
      }
      error(op.text + " does not apply to a " + rel.text + "; it relates: " + joinList(ok), &rel);
    }
    if (!isWord("target")) error("expected 'target' after the operator, got " + describe(peek()));
    take();
    if (isPunct("{")) r.attributes = attributes(r.related, rel.text);
    r.text = std::string(r.negated ? "not " : "") + rel.text + " " + op.text + " target";
    if (!r.attributes.empty()) {
      r.text += " {";
      for (std::size_t i = 0; i < r.attributes.size(); ++i) {
        const auto& a = r.attributes[i];
        r.text += (i ? ", " : "") + a.key + ": " + (a.values.empty() ? std::string("any") : [&] {
                    std::string s;
                    for (const auto& v : a.values) s += (s.empty() ? "" : " | ") + v;
                    return s;
                  }());
      }
      r.text += "}";
    }
    requirement_src_.push_back(src_);
    spec_.requirements.push_back(r);
  }

  std::vector<AttributeSet> attributes(EntityClass cls, const std::string& what) {
    expectPunct("{", "to open the attributes");
    std::vector<AttributeSet> out;
    const std::vector<std::string> keys = vocab_.keys(cls);
    while (!isPunct("}")) {
      const Token k = expectIdent("an attribute name or '}'");
      const auto* values = vocab_.values(cls, k.text);
      if (!values) {
        error("unknown attribute '" + k.text + "' of " + std::string(scenario::toString(cls)) +
                  nearestHint(k.text, keys) + "; attributes of " + scenario::toString(cls) +
                  " in this world: " + (keys.empty() ? std::string("none") : joinList(keys)),
              &k);
      }
      for (const auto& a : out) {
        if (a.key == k.text) error("attribute '" + k.text + "' given twice", &k);
      }
      expectPunct(":", "after the attribute name");
      AttributeSet set;
      set.key = k.text;
      set.pos = pos(k);
      if (isWord("any")) {
        take();
      } else {
        for (;;) {
          const Token v = peek();
          if (v.kind != Tok::kIdent && v.kind != Tok::kString && v.kind != Tok::kNumber) {
            error("expected a value of '" + k.text + "' (or 'any'), got " + describe(v));
          }
          take();
          if (!values->count(v.text)) {
            const std::vector<std::string> all(values->begin(), values->end());
            error("unknown " + k.text + " '" + v.text + "' for " + what + nearestHint(v.text, all) +
                      "; " + k.text + " values of " + scenario::toString(cls) +
                      " in this world: " + joinList(all),
                  &v);
          }
          set.values.push_back(v.text);
          if (!isPunct("|")) break;
          take();
        }
      }
      out.push_back(set);
      if (isPunct(","))
        take();
      else if (!isPunct("}"))
        error("expected ',' or '}' after the attribute value, got " + describe(peek()));
    }
    take();
    (void)what;
    return out;
  }

  void section() {
    const Token name = take();
    expectPunct("{", "after '" + name.text + "'");
    std::vector<std::string> keys = specSections().at(name.text);
    if (name.text == "confusers") {
      keys.push_back("share");
      keys.push_back("told_apart_by");
      std::sort(keys.begin(), keys.end());
    }
    while (!isPunct("}")) {
      const Token k = expectIdent("a setting of '" + name.text + "' or '}'");
      if (name.text == "confusers" && (k.text == "share" || k.text == "told_apart_by")) {
        confuserSetting(k);
        if (isPunct(",")) take();
        continue;
      }
      if (std::find(keys.begin(), keys.end(), k.text) == keys.end()) {
        error("unknown setting '" + k.text + "' in " + name.text + nearestHint(k.text, keys) +
                  "; settings of " + name.text + ": " + joinList(keys),
              &k);
      }
      expectPunct(":", "after '" + k.text + "'");
      const std::string key = name.text + "." + k.text;
      PendingValue v = expression(key == "environment.time");
      bool replaced = false;
      for (auto& kv : settings_) {
        if (kv.first == key) kv.second = v, replaced = true;
      }
      if (!replaced) settings_.emplace_back(key, v);
      if (isPunct(",")) take();
    }
    take();
  }

  // koz PURPOSE over (target | CLASS) { count: N, size: M, margin: M, alt: [LO, HI], net: S,
  // nlt: S }: its settings become "kozN.<name>" (alt: alt_min and alt_max).
  void kozStatement() {
    const Token kw = take();
    KozSpec k;
    k.pos = pos(kw);
    k.key = "koz" + std::to_string(spec_.kozs.size() + 1);
    k.purpose = expectOneOf({"vantage_denial", "access_denial", "restricted"}, "a purpose",
                            "purpose", "purposes")
                    .text;
    if (!isWord("over")) error("expected 'over' after the purpose, got " + describe(peek()));
    take();
    std::vector<std::string> overs = {"target", "block", "aoi"};
    for (const auto& c : world_classes_) {
      if (std::find(overs.begin(), overs.end(), c) == overs.end()) overs.push_back(c);
    }
    if (std::find(overs.begin(), overs.end(), "street") == overs.end()) overs.push_back("street");
    const Token o = expectOneOf(overs, "what the zone covers", "zone cover", "a zone covers");
    k.over = o.text;
    if (o.text == "aoi") {
      // over aoi N: the N-th AOI of the mission (1-based).
      const Token n = peek();
      if (n.kind != Tok::kNumber || !n.integer || n.number < 1 || n.number > 5)
        error("expected the AOI's number (1 to 5) after 'aoi', got " + describe(n), &n);
      take();
      k.aoi = static_cast<int>(n.number);
      k.aoi_pos = pos(n);
    }
    const std::vector<std::string> keys =
        o.text == "target"   ? std::vector<std::string>{"alt", "net", "nlt", "size"}
        : o.text == "street" ? std::vector<std::string>{"alt", "length", "margin", "net", "nlt"}
        : o.text == "block" || o.text == "aoi"
            ? std::vector<std::string>{"alt", "margin", "net", "nlt"}
            : std::vector<std::string>{"alt", "count", "margin", "net", "nlt"};
    if (isPunct("{")) {
      take();
      while (!isPunct("}")) {
        const Token n = expectIdent("a setting of 'koz' or '}'");
        if (std::find(keys.begin(), keys.end(), n.text) == keys.end()) {
          error("unknown setting '" + n.text + "' of a zone over " + o.text +
                    nearestHint(n.text, keys) + "; settings: " + joinList(keys),
                &n);
        }
        expectPunct(":", "after '" + n.text + "'");
        if (n.text == "alt") {
          expectPunct("[", "to open the altitude band: alt: [bottom, top] (m)");
          kozSetting(k.key + ".alt_min", expression());
          expectPunct(",", "between the bottom and the top of the altitude band");
          kozSetting(k.key + ".alt_max", expression());
          expectPunct("]", "to close the altitude band");
        } else {
          kozSetting(k.key + "." + n.text, expression());
        }
        if (isPunct(",")) take();
      }
      take();
    }
    spec_.kozs.push_back(k);
    koz_src_.push_back(src_);
  }

  // A name among `valid`: else "unknown NOUN 'x'; did you mean ...; LIST: ...".
  Token expectOneOf(const std::vector<std::string>& valid, const std::string& what,
                    const std::string& noun, const std::string& list) {
    const Token t = expectIdent(what + " (" + joinList(valid) + ")");
    if (std::find(valid.begin(), valid.end(), t.text) == valid.end()) {
      error("unknown " + noun + " '" + t.text + "'" + nearestHint(t.text, valid) + "; " + list +
                ": " + joinList(valid),
            &t);
    }
    return t;
  }

  void kozSetting(const std::string& key, const PendingValue& v) {
    for (auto& kv : settings_) {
      if (kv.first == key)
        errorAt(v.pos, v.src, "'" + key.substr(key.find('.') + 1) + "' given twice in this koz");
    }
    settings_.emplace_back(key, v);
  }

  // A zone's band and window: the top above the bottom, NLT after NET, whatever is drawn.
  void checkKozs() {
    if (spec_.kozs.size() > 8) {
      errorAt(spec_.kozs[8].pos, koz_src_[8], "at most 8 koz statements per spec");
    }
    auto pending = [&](const std::string& key) -> const PendingValue* {
      for (const auto& kv : settings_) {
        if (kv.first == key) return &kv.second;
      }
      return nullptr;
    };
    for (std::size_t i = 0; i < spec_.kozs.size(); ++i) {
      const KozSpec& k = spec_.kozs[i];
      if (k.over == "aoi") {
        // The AOI must exist in every scenario: an area search with at least that many.
        if (spec_.cls != scenario::ScenarioClass::kAreaSearch) {
          errorAt(k.pos, koz_src_[i], "a zone over an AOI applies to area_search only");
        }
        const Distribution* n = spec_.setting("aois.count");
        if (n && n->minValue() < k.aoi) {
          char buf[160];
          std::snprintf(buf, sizeof(buf),
                        "aoi %d: a scenario of this spec may have %g AOI(s) (aois { count: %s })",
                        k.aoi, n->minValue(), n->text().c_str());
          errorAt(k.aoi_pos, koz_src_[i], buf);
        }
      }
      for (const auto& [lo, hi, what] :
           {std::make_tuple("alt_min", "alt_max",
                            "alt: expected the top of the band above its "
                            "bottom, whatever is drawn"),
            std::make_tuple("net", "nlt", "nlt: expected NLT after NET, whatever is drawn")}) {
        const Distribution* a = spec_.setting(k.key + "." + lo);
        const Distribution* b = spec_.setting(k.key + "." + hi);
        if (a && b && !(b->minValue() > a->maxValue())) {
          const PendingValue* v = pending(k.key + "." + hi);
          errorAt(v->pos, v->src, std::string(what) + " (" + b->text() + " vs " + a->text() + ")");
        }
      }
    }
  }

  // confusers { share: [KEY, ...] } and { told_apart_by: "REQUIREMENT" }.
  void confuserSetting(const Token& k) {
    expectPunct(":", "after '" + k.text + "'");
    ConfuserSpec& c = spec_.confusers;
    if (k.text == "told_apart_by") {
      const Token t = peek();
      if (t.kind != Tok::kString || t.text.empty())
        error(
            "expected a requirement of this spec as a \"string\" after 'told_apart_by' (e.g. "
            "\"garage LEFT_OF target\"), got " +
            describe(t));
      take();
      c.told_apart_by = t.text;
      c.told_pos = pos(t);
      told_src_ = src_;
      return;
    }
    const std::vector<std::string> all = {"vehicle_class", "make", "model", "color"};
    c.share_pos = pos(peek());
    share_src_ = src_;
    expectPunct("[", "to open the list of shared attributes (e.g. [vehicle_class, color])");
    c.share.clear();
    c.have_share = true;
    while (!isPunct("]")) {
      const Token a = expectIdent("an attribute of the target (" + joinList(all) + ") or ']'");
      if (std::find(all.begin(), all.end(), a.text) == all.end()) {
        error("unknown attribute '" + a.text + "' to share" + nearestHint(a.text, all) +
                  "; look-alikes share: " + joinList(all),
              &a);
      }
      if (std::find(c.share.begin(), c.share.end(), a.text) != c.share.end())
        error("attribute '" + a.text + "' given twice", &a);
      c.share.push_back(a.text);
      if (isPunct(",")) take();
    }
    take();
    // A model has one make and one vehicle class: sharing it shares them.
    if (std::find(c.share.begin(), c.share.end(), "model") != c.share.end()) {
      for (const char* implied : {"make", "vehicle_class"}) {
        if (std::find(c.share.begin(), c.share.end(), implied) == c.share.end())
          c.share.push_back(implied);
      }
    }
  }

  // ---------------------------------------------------------------- expressions
  double number(const std::string& what) {
    const Token t = peek();
    if (t.kind == Tok::kNumber) {
      take();
      return t.number;
    }
    if (t.kind == Tok::kIdent && params_.count(t.text)) {
      take();
      const PendingValue& v = params_.at(t.text);
      if (v.dist.kind != Distribution::Kind::kConstant) {
        error("parameter '" + t.text + "' is a distribution; " + what + " needs a number", &t);
      }
      return v.dist.a;
    }
    error("expected " + what + " (a number), got " + describe(t));
  }

  PendingValue expression(bool time = false) {
    PendingValue v;
    const Token t = peek();
    v.pos = pos(t);
    v.src = src_;
    Distribution& d = v.dist;
    if (t.kind == Tok::kNumber) {
      take();
      d.a = d.b = t.number;
      d.integer = t.integer;
      if (isPunct("..")) {
        take();
        const Token u = peek();
        if (u.kind != Tok::kNumber)
          error("expected the upper bound after '..', got " + describe(u));
        take();
        if (!(u.number >= t.number))
          error("expected an upper bound >= " + t.text + ", got " + u.text, &u);
        d.kind = Distribution::Kind::kRange;
        d.b = u.number;
        d.integer = t.integer && u.integer;
      }
      return v;
    }
    if (t.kind != Tok::kIdent)
      error("expected a number, a range (a..b), range(), normal(), choice() or a parameter, got " +
            describe(t));
    take();
    if (t.text == "range") {
      expectPunct("(", "after 'range'");
      d.kind = Distribution::Kind::kRange;
      d.a = number("the lower bound");
      expectPunct(",", "between the bounds of range()");
      d.b = number("the upper bound");
      expectPunct(")", "to close range()");
      if (!(d.b >= d.a)) error("range(): expected the upper bound >= the lower bound", &t);
      return v;
    }
    if (t.text == "normal") {
      expectPunct("(", "after 'normal'");
      d.kind = Distribution::Kind::kNormal;
      d.a = number("the mean");
      expectPunct(",", "after the mean: normal(mean, stddev, min, max)");
      d.b = number("the standard deviation");
      expectPunct(",", "after the standard deviation: normal(mean, stddev, min, max)");
      d.lo = number("the lower truncation bound");
      expectPunct(",", "after the lower bound: normal(mean, stddev, min, max)");
      d.hi = number("the upper truncation bound");
      expectPunct(")", "to close normal()");
      if (!(d.b > 0)) error("normal(): expected a positive standard deviation", &t);
      if (!(d.hi > d.lo)) error("normal(): expected max > min", &t);
      return v;
    }
    if (t.text == "choice") {
      expectPunct("(", "after 'choice'");
      d.kind = Distribution::Kind::kChoice;
      double total = 0;
      for (;;) {
        const double value = number("a choice value");
        expectPunct(":", "between a value and its weight: choice(value: weight, ...)");
        const Token wt = peek();
        const double w = number("a weight");
        if (!(w > 0)) error("choice(): expected a positive weight", &wt);
        d.choices.emplace_back(value, w);
        total += w;
        if (isPunct(",")) {
          take();
          continue;
        }
        expectPunct(")", "to close choice()");
        break;
      }
      if (d.choices.size() > 64) error("choice(): at most 64 values", &t);
      (void)total;
      return v;
    }
    if (time && periods().count(t.text)) {
      d.kind = Distribution::Kind::kRange;
      d.a = periods().at(t.text).first;
      d.b = periods().at(t.text).second;
      return v;
    }
    if (params_.count(t.text)) {
      v.param = t.text;
      return v;
    }
    std::vector<std::string> names;
    for (const auto& kv : params_) names.push_back(kv.first);
    if (time) {
      for (const auto& kv : periods()) names.push_back(kv.first);
    }
    error("unknown name '" + t.text + "'" + nearestHint(t.text, names) +
              (time ? "; periods of the day: dawn, day, dusk, night" : "") +
              (params_.empty() ? ""
                               : "; parameters: " +
                                     [&] {
                                       std::vector<std::string> p;
                                       for (const auto& kv : params_) p.push_back(kv.first);
                                       return joinList(p);
                                     }()),
          &t);
  }

  Distribution resolve(const PendingValue& v, const std::string& key) {
    (void)key;
    if (v.param.empty()) return v.dist;
    return params_.at(v.param).dist;
  }

  void checkLimits(const std::string& key, const Distribution& d, const PendingValue& v) {
    const KeyLimits& lim = limitsOf(key);
    if (d.minValue() < lim.min || d.maxValue() > lim.max) {
      errorAt(v.pos, v.src,
              key + ": expected values within [" + fmtNum(lim.min) + ", " + fmtNum(lim.max) +
                  "], got " + d.text() +
                  (v.param.empty() ? "" : " (from param '" + v.param + "')"));
    }
    if (lim.integer) {
      bool whole = d.kind != Distribution::Kind::kNormal;
      if (d.kind == Distribution::Kind::kChoice) {
        for (const auto& c : d.choices) whole = whole && c.first == std::floor(c.first);
      } else {
        whole = whole && d.a == std::floor(d.a) && d.b == std::floor(d.b);
      }
      if (!whole)
        errorAt(v.pos, v.src,
                key + ": expected a whole number or a range of whole numbers, got " + d.text());
    }
  }

  void checkClassRules() {
    const bool route = spec_.cls == scenario::ScenarioClass::kRouteSearch;
    const bool pursuit = spec_.cls == scenario::ScenarioClass::kPursuit;
    if (have_target_) {
      const TargetSpec& t = spec_.target;
      if (t.moving && route && !*t.moving) {
        errorAt(t.pos, target_src_, "a route_search target drives; expected 'moving'");
      }
      if (t.moving && !route && !pursuit && *t.moving) {
        errorAt(t.pos, target_src_, "an area_search target is parked; expected 'parked'");
      }
      if (t.count == 2 && !route) {
        errorAt(t.pos, target_src_, "expected 1 target: only route_search has a convoy of 2");
      }
      if ((!t.block.empty() || !t.street.empty()) && route) {
        errorAt(t.pos, target_src_,
                "'in' and 'on' place a parked target; route_search targets drive");
      }
      if (t.within > 0 && route) {
        errorAt(t.within_pos, target_src_,
                "'within' places a parked target; route_search targets drive");
      }
      if (!t.street.empty() && !t.block.empty()) {
        errorAt(t.pos, target_src_, "expected one of 'in BLOCK' and 'on \"STREET\"', not both");
      }
    }
    constexpr int kMaxPlaced = 3;
    int placing = 0;
    for (std::size_t i = 0; i < spec_.requirements.size(); ++i) {
      const Requirement& r = spec_.requirements[i];
      const bool mover = r.related == EntityClass::kPedestrian || r.related == EntityClass::kCar;
      if (route && mover) {
        errorAt(r.pos, requirement_src_[i],
                "a route_search target relates to the neighborhood (street, house, building, "
                "...): relations to cars and pedestrians apply to parked targets");
      }
      const bool runners =
          pursuit && r.related == EntityClass::kPedestrian && r.op == scenario::RelationOp::kNextTo;
      if (r.eventually && !route && !pursuit) {
        errorAt(r.pos, requirement_src_[i],
                "EVENTUALLY_* applies to a moving target (route_search, pursuit); an area_search "
                "target is parked: drop EVENTUALLY_");
      }
      if (r.eventually && mover && !runners) {
        errorAt(r.pos, requirement_src_[i],
                "EVENTUALLY_* relates a moving target to the neighborhood (street, house, "
                "building, ...), or a pursuit target to its running pedestrians ('pedestrian "
                "EVENTUALLY_NEXT_TO target')");
      }
      if (r.eventually && (r.negated || r.probability < 1.0)) {
        errorAt(r.pos, requirement_src_[i],
                "EVENTUALLY_* is constructed where the target drives: expected 'require' "
                "without 'not' (a negation or a 'prefer' would have to hold over the whole "
                "drive)");
      }
      if (r.eventually) {
        for (const auto& a : r.attributes) {
          if (a.key == "activity" &&
              std::find(a.values.begin(), a.values.end(), "running") == a.values.end()) {
            errorAt(a.pos, requirement_src_[i],
                    "the pedestrians that reach a pursuit target are running: activity must "
                    "allow 'running'");
          }
        }
      }
      if (!r.eventually &&
          (r.related == EntityClass::kPedestrian || r.related == EntityClass::kCar) && !r.negated) {
        // A positive relation to a car or pedestrian is constructed: the sampler parks a car or
        // stands a pedestrian beside the target, one per such requirement, in the order written
        // (with 'prefer', in the scenarios drawn to meet it); at most kMaxPlaced of them, as the
        // compiler's search for spots that meet them together grows with their power.
        if (++placing > kMaxPlaced) {
          errorAt(r.pos, requirement_src_[i],
                  "at most " + std::to_string(kMaxPlaced) +
                      " requirements per spec place a car or pedestrian beside the target; this "
                      "is one more");
        }
        for (const auto& a : r.attributes) {
          if (a.key == "activity" && !a.values.empty() &&
              std::find(a.values.begin(), a.values.end(), "standing") == a.values.end()) {
            errorAt(a.pos, requirement_src_[i],
                    "the pedestrian placed for a relation to the parked target stands: activity "
                    "must allow 'standing'");
          }
        }
      }
    }
    ConfuserSpec& c = spec_.confusers;
    if (!c.told_apart_by.empty()) {
      std::vector<std::string> hard;
      c.told_apart = -1;
      for (std::size_t i = 0; i < spec_.requirements.size(); ++i) {
        const Requirement& r = spec_.requirements[i];
        if (r.probability < 1.0 || r.eventually || r.related == EntityClass::kCar ||
            r.related == EntityClass::kPedestrian)
          continue;
        hard.push_back(r.text);
        if (squeeze(r.text) == squeeze(c.told_apart_by)) c.told_apart = static_cast<int>(i);
      }
      if (c.told_apart < 0) {
        errorAt(c.told_pos, told_src_,
                "told_apart_by: '" + c.told_apart_by +
                    "' is not a hard requirement on the neighborhood of this spec; " +
                    (hard.empty() ? std::string("it has none")
                                  : "its requirements: " + joinList(hard)));
      }
    }
    if ((c.have_share || !c.told_apart_by.empty()) && route) {
      errorAt(c.have_share ? c.share_pos : c.told_pos, c.have_share ? share_src_ : told_src_,
              "share and told_apart_by apply to the look-alikes of a parked target (area_search, "
              "pursuit)");
    }
    for (const auto& kv : settings_) {
      if (kv.first == "confusers.within" && route) {
        errorAt(kv.second.pos, kv.second.src, kv.first + " applies to area_search and pursuit");
      }
      if (kv.first == "aois.target_offset" && spec_.cls != scenario::ScenarioClass::kAreaSearch) {
        errorAt(kv.second.pos, kv.second.src, kv.first + " applies to area_search only");
      }
    }
    const std::string route_keys[] = {"route.edges", "route.band"};
    for (const auto& k : route_keys) {
      for (const auto& kv : settings_) {
        if (kv.first == k && !route) {
          errorAt(kv.second.pos, kv.second.src, k + " applies to route_search only");
        }
      }
    }
  }

  Vocabulary vocab_;
  std::vector<std::string> world_blocks_;
  std::vector<std::string> world_classes_;  // classes of the world's entities (landmarks)
  const Source* told_src_ = nullptr;
  const Source* share_src_ = nullptr;
  scenario::WorldType world_type_ = scenario::WorldType::kSuburb;
  std::vector<std::unique_ptr<Source>> sources_;
  const Source* src_ = nullptr;
  std::vector<Token>* toks_ = nullptr;
  std::size_t* p_ = nullptr;
  std::vector<std::string> stack_;
  std::map<std::string, PendingValue> params_;
  std::vector<std::pair<std::string, PendingValue>> settings_;
  std::vector<const Source*> requirement_src_;
  std::vector<const Source*> koz_src_;
  const Source* target_src_ = nullptr;
  const Source* class_src_ = nullptr;
  SourcePos class_pos_;
  bool have_target_ = false;
  std::uint64_t hash_ = 0xcbf29ce484222325ULL;
  Spec spec_;

 public:
  void setBlocks(const scenario::World& world) {
    for (const auto& b : world.blocks()) world_blocks_.push_back(b.name);
    std::set<std::string> classes;
    for (const auto& e : world.entities()) classes.insert(scenario::toString(e.cls));
    world_classes_.assign(classes.begin(), classes.end());
    world_type_ = world.params().type;
  }
};

double inverseNormalCdf(double p) {
  // Bisection on the CDF (0.5 erfc(-x / sqrt 2)): monotone, exact to 1e-12 in 80 steps.
  double lo = -40, hi = 40;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p)
      lo = mid;
    else
      hi = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

// ------------------------------------------------------------------ public
const std::map<std::string, std::vector<std::string>>& specSections() {
  static const std::map<std::string, std::vector<std::string>> k = [] {
    std::map<std::string, std::vector<std::string>> m;
    for (const auto& kv : keyLimits()) {
      const auto dot = kv.first.find('.');
      m[kv.first.substr(0, dot)].push_back(kv.first.substr(dot + 1));
    }
    return m;
  }();
  return k;
}

double Distribution::draw(double u) const {
  u = std::clamp(u, 0.0, std::nextafter(1.0, 0.0));
  switch (kind) {
    case Kind::kConstant:
      return a;
    case Kind::kRange:
      if (integer) return std::min(b, std::floor(a + (b - a + 1) * u));
      return a + (b - a) * u;
    case Kind::kNormal: {
      const double pa = 0.5 * std::erfc(-(lo - a) / (b * std::sqrt(2.0)));
      const double pb = 0.5 * std::erfc(-(hi - a) / (b * std::sqrt(2.0)));
      return std::clamp(a + b * inverseNormalCdf(pa + (pb - pa) * u), lo, hi);
    }
    case Kind::kChoice: {
      double total = 0;
      for (const auto& c : choices) total += c.second;
      double acc = 0;
      for (const auto& c : choices) {
        acc += c.second;
        if (u * total < acc) return c.first;
      }
      return choices.back().first;
    }
  }
  return a;
}

bool Distribution::contains(double v, bool milli) const {
  const double eps = milli ? 1e-3 + 1e-9 : 1e-6;
  switch (kind) {
    case Kind::kConstant:
      return std::abs(v - a) <= eps;
    case Kind::kRange:
      return v >= a - eps && v <= b + eps;
    case Kind::kNormal:
      return v >= lo - eps && v <= hi + eps;
    case Kind::kChoice:
      for (const auto& c : choices) {
        if (std::abs(v - c.first) <= eps) return true;
      }
      return false;
  }
  return false;
}

double Distribution::minValue() const {
  switch (kind) {
    case Kind::kNormal:
      return lo;
    case Kind::kChoice: {
      double m = choices.front().first;
      for (const auto& c : choices) m = std::min(m, c.first);
      return m;
    }
    default:
      return a;
  }
}

double Distribution::maxValue() const {
  switch (kind) {
    case Kind::kConstant:
      return a;
    case Kind::kNormal:
      return hi;
    case Kind::kChoice: {
      double m = choices.front().first;
      for (const auto& c : choices) m = std::max(m, c.first);
      return m;
    }
    default:
      return b;
  }
}

std::string Distribution::text() const {
  switch (kind) {
    case Kind::kConstant:
      return fmtNum(a);
    case Kind::kRange:
      return integer ? fmtNum(a) + ".." + fmtNum(b) : "range(" + fmtNum(a) + ", " + fmtNum(b) + ")";
    case Kind::kNormal:
      return "normal(" + fmtNum(a) + ", " + fmtNum(b) + ", " + fmtNum(lo) + ", " + fmtNum(hi) + ")";
    case Kind::kChoice: {
      std::string s = "choice(";
      for (std::size_t i = 0; i < choices.size(); ++i) {
        s += (i ? ", " : "") + fmtNum(choices[i].first) + ": " + fmtNum(choices[i].second);
      }
      return s + ")";
    }
  }
  return "";
}

bool AttributeSet::matches(const scenario::Attributes& attrs) const {
  if (values.empty()) return attrs.has(key);
  for (const auto& [k, v] : attrs.items) {
    if (k != key) continue;
    const std::string s = Vocabulary::valueText(v);
    return std::find(values.begin(), values.end(), s) != values.end();
  }
  return false;
}

bool Requirement::matchesRelated(scenario::EntityClass cls, const scenario::Attributes& a) const {
  if (cls != related) return false;
  for (const auto& s : attributes) {
    if (!s.matches(a)) return false;
  }
  return true;
}

const Distribution* Spec::setting(const std::string& key) const {
  for (const auto& kv : settings) {
    if (kv.first == key) return &kv.second;
  }
  return nullptr;
}

int editDistance(const std::string& a, const std::string& b) {
  // Optimal string alignment (Damerau): insertions, deletions, substitutions and swaps of two
  // adjacent characters each cost 1; case is ignored.
  auto lc = [](char c) { return std::tolower(static_cast<unsigned char>(c)); };
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<int>> d(n + 1, std::vector<int>(m + 1));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = static_cast<int>(i);
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = static_cast<int>(j);
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const int cost = lc(a[i - 1]) == lc(b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && lc(a[i - 1]) == lc(b[j - 2]) && lc(a[i - 2]) == lc(b[j - 1])) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[n][m];
}

std::vector<std::string> nearestNames(const std::string& name,
                                      const std::vector<std::string>& candidates) {
  const int limit = std::max(1, (static_cast<int>(name.size()) + 2) / 4);
  std::vector<std::pair<int, std::string>> scored;
  for (const auto& c : candidates) {
    const int d = editDistance(name, c);
    if (d <= limit) scored.emplace_back(d, c);
  }
  std::stable_sort(scored.begin(), scored.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<std::string> out;
  for (const auto& s : scored) out.push_back(s.second);
  return out;
}

Spec parseSpec(const std::string& path, const std::vector<std::string>& overrides,
               const scenario::World& world) {
  Parser p(world);
  p.setBlocks(world);
  p.parseFile(path, nullptr, nullptr);
  return p.finish(overrides, path);
}

namespace {
// specWorld() on one file and its imports; `depth` bounds import cycles.
void scanWorld(const std::string& path, int depth, std::string* out) {
  if (depth > 16) return;
  std::ifstream in(path, std::ios::binary);
  if (!in) return;
  std::ostringstream ss;
  ss << in.rdbuf();
  if (ss.str().size() > (1u << 20)) return;
  Source src;
  src.file = path;
  src.text = ss.str();
  std::vector<Token> toks;
  try {
    toks = lex(src);
  } catch (const SpecError&) {
    return;  // the parse reports it
  }
  for (std::size_t i = 0; i + 1 < toks.size(); ++i) {
    if (toks[i].kind != Tok::kIdent ||
        (i > 0 && toks[i - 1].kind == Tok::kPunct && toks[i - 1].text == ":"))
      continue;
    if (toks[i].text == "import" && toks[i + 1].kind == Tok::kString) {
      std::filesystem::path p(toks[i + 1].text);
      if (p.is_relative()) p = std::filesystem::path(path).parent_path() / p;
      scanWorld(p.string(), depth + 1, out);
    } else if (toks[i].text == "world" && toks[i + 1].kind == Tok::kIdent) {
      *out = toks[i + 1].text;
    }
  }
}
}  // namespace

std::string specWorld(const std::string& path) {
  std::string out;
  scanWorld(path, 0, &out);
  return out;
}

Spec parseSpecText(const std::string& text, const std::string& file,
                   const std::vector<std::string>& overrides, const scenario::World& world) {
  Parser p(world);
  p.setBlocks(world);
  p.parseText(text, file);
  return p.finish(overrides, file);
}

}  // namespace hameritt::generation
