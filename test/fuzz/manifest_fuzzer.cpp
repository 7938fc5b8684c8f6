// Document validator on manifest.json (and any other kind the "schema" field names):
// parseJsonText() + validateDocument() report issues, never throw; a document with issues
// has each issue's file, rule and message filled in.
#include "fuzz_util.h"
#include "hameritt/scenario/validation.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hameritt;
  static const std::string schema_dir = fuzz::schemaDir();
  nlohmann::json doc;
  scenario::ValidationIssue issue;
  if (!scenario::parseJsonText(fuzz::text(data, size), "fuzz.json", &doc, &issue)) {
    fuzz::require((issue.rule == "json" || issue.rule == "limit") && !issue.message.empty(), "a JSON issue has a message");
    return 0;
  }
  for (const auto& i : scenario::validateDocument(doc, "fuzz.json", schema_dir)) {
    fuzz::require(i.file == "fuzz.json" && !i.rule.empty() && !i.message.empty(),
                  "an issue names the file, the rule and what was expected");
    (void)scenario::formatIssue(i);
  }
  return 0;
}
