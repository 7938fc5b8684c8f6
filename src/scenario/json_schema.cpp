// The JSON Schema checker (the subset of draft 2020-12 the shipped schemas use) and JSON pointers.
#include "validation_internal.h"

namespace hameritt::scenario {

namespace {

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

}  // namespace hameritt::scenario
