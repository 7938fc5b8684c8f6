#pragma once
// Validation of scenario documents (mission.json, sim_config.json, world.json, manifest.json):
// a JSON Schema (draft-07 subset) validator over nlohmann::json driven by config/schema/, plus
// semantic checks that a schema cannot express (simple polygons, unique ids, ordered time
// windows, priors summing to 1, references that resolve, ordered trajectories).

#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "hameritt/scenario/error.h"

namespace hameritt::scenario {

// One problem found in a document. `path` is a JSON Pointer (RFC 6901) into the document, ""
// for the document itself; `rule` names the failed check: a schema keyword ("type",
// "required", "additionalProperties", "enum", ...) or a semantic rule ("polygon_simple",
// "unique_id", "time_window", "prior_sum", ...), "json" for malformed JSON, "limit" for a
// document beyond the size or nesting limit (bounded_json.h), "schema_kind" for an unknown or
// missing "schema" field, "schema" for an unusable schema file.
struct ValidationIssue {
  std::string file;
  std::string path;
  std::string rule;
  std::string message;
};

// An unusable schema (unsupported keyword, bad keyword value, unresolvable $ref). `path()` is
// the JSON Pointer of the offending place inside the schema.
class SchemaError : public ConfigError {
 public:
  SchemaError(const std::string& message, std::string path)
      : ConfigError(message), path_(std::move(path)) {}
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// A compiled JSON Schema supporting the draft-07 keywords that config/schema/ uses: type
// (incl. "integer" and type arrays), properties, required, additionalProperties (bool or
// schema), items (one schema), minItems, maxItems, uniqueItems, minLength, maxLength, minimum,
// maximum, exclusiveMinimum, exclusiveMaximum, enum, const, pattern (ECMAScript, unanchored),
// $ref to local JSON pointers ("#/definitions/..."), anyOf and oneOf, plus boolean schemas and
// the annotations $schema, $id, $comment, title, description, default, examples and
// definitions. Any other keyword, and $ref next to a validation keyword, is a SchemaError, so
// that no rule of a schema is silently ignored.
class JsonSchema {
 public:
  // Checks the whole schema (definitions included); `name` prefixes error messages.
  JsonSchema(nlohmann::json schema, std::string name);
  // Reads and compiles a schema file; throws ConfigError for unreadable or malformed JSON and
  // SchemaError for an unusable schema.
  static JsonSchema load(const std::string& path);

  // Appends one issue per violation found in `doc`, attributed to `file`.
  void validate(const nlohmann::json& doc, const std::string& file,
                std::vector<ValidationIssue>* issues) const;
  // The issues of `doc` (file left empty).
  std::vector<ValidationIssue> validate(const nlohmann::json& doc) const;

  // The schema document.
  const nlohmann::json& root() const { return schema_; }
  // The name given at construction (the file path for load()).
  const std::string& name() const { return name_; }

 private:
  void compile(const nlohmann::json& s, const std::string& spath);
  const nlohmann::json& resolve(const std::string& ref, const std::string& spath) const;
  void check(const nlohmann::json& doc, const nlohmann::json& s, const std::string& path, int depth,
             const std::string& file, std::vector<ValidationIssue>* out) const;

  nlohmann::json schema_;
  std::string name_;
  std::unordered_map<std::string, std::regex> patterns_;
};

// The document kinds and their "schema" field values.
enum class DocumentKind { kMission, kSimConfig, kWorld, kManifest };
// "hameritt/mission", "hameritt/sim_config", "hameritt/world", "hameritt/manifest".
const char* schemaName(DocumentKind kind);
// The schema file of a kind inside a schema directory, e.g. DIR/mission.schema.json.
std::string schemaFile(const std::string& schema_dir, DocumentKind kind);

// Validates a parsed document: its kind comes from its "schema" field (a missing or unknown
// one is an issue, rule "schema_kind"); then the kind's schema from `schema_dir` and the
// semantic checks run. An unusable schema file is an issue with rule "schema" naming that
// file. Returns every issue found; empty when the document is valid.
std::vector<ValidationIssue> validateDocument(const nlohmann::json& doc, const std::string& file,
                                              const std::string& schema_dir);

// Parses a JSON text strictly (duplicate object keys are errors). On failure returns false and
// sets `issue` (rule "json", message with line and column where known; rule "limit" beyond
// the size or nesting limit of bounded_json.h).
bool parseJsonText(const std::string& text, const std::string& file, nlohmann::json* out,
                   ValidationIssue* issue);

// Reads, parses and validates a file: an unreadable file is one issue with rule "io",
// malformed JSON one issue with rule "json", a file beyond the limits one with rule "limit";
// otherwise validateDocument().
std::vector<ValidationIssue> validateFile(const std::string& path, const std::string& schema_dir);

// "FILE: PATH: RULE: MESSAGE" (PATH "/" ... or "(root)" for the document itself).
std::string formatIssue(const ValidationIssue& issue);

// Appends a reference token to a JSON Pointer, escaping '~' and '/'.
std::string jsonPointerAppend(const std::string& pointer, const std::string& token);
std::string jsonPointerAppend(const std::string& pointer, std::size_t index);

}  // namespace hameritt::scenario
