// Validation of a scenario document: its kind, schema and semantic checks, issues and their text.
#include "hameritt/scenario/validation.h"

#include "validation_internal.h"

namespace hameritt::scenario {

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
  } catch (const json::exception& e) {  // e.g. out_of_range 406: a number beyond a double
    *issue = {file, "", "json", std::string("malformed JSON: ") + e.what()};
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
    // "PATH: cannot open file", "PATH: is a directory, ...", "PATH: N bytes, more than the
    // limit ...".
    const std::string what = std::string(e.what()).substr(path.size() + 2);
    const bool io = what.rfind("cannot", 0) == 0 || what.rfind("is a directory", 0) == 0;
    return {{path, "", io ? "io" : "limit", what}};
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
