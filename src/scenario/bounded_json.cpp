#include "hameritt/scenario/bounded_json.h"

#include <filesystem>
#include <fstream>
#include <system_error>

#include "hameritt/scenario/error.h"

namespace hameritt::scenario {

namespace {

std::string mib(std::uintmax_t bytes) {
  return bytes % (std::uintmax_t{1} << 20) == 0 ? " (" + std::to_string(bytes >> 20) + " MiB)"
                                                : std::string();
}

[[noreturn]] void tooLarge(const std::string& file, const std::string& size,
                           std::uintmax_t max_bytes) {
  throw ConfigError(file + ": " + size + ", more than the limit of " + std::to_string(max_bytes) +
                    " bytes" + mib(max_bytes) + " for a JSON document");
}

}  // namespace

void checkJsonDepth(std::string_view text, const std::string& file, std::size_t max_depth) {
  std::size_t depth = 0;
  bool in_string = false;
  bool escaped = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) {
        throw ConfigError(file + ": JSON nested deeper than the limit of " +
                          std::to_string(max_depth) + " levels (at byte " + std::to_string(i) +
                          ")");
      }
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
}

void checkJsonText(std::string_view text, const std::string& file, std::uintmax_t max_bytes,
                   std::size_t max_depth) {
  if (text.size() > max_bytes) tooLarge(file, std::to_string(text.size()) + " bytes", max_bytes);
  checkJsonDepth(text, file, max_depth);
}

std::string readBoundedFile(const std::string& path, std::uintmax_t max_bytes) {
  // An ifstream opens a directory and reports its size as the largest offset: say what it is.
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw ConfigError(path + ": is a directory, expected a JSON file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot open file");
  // A regular file's size is known before reading; a pipe or a device is read in blocks and
  // refused at the first byte beyond the limit.
  in.seekg(0, std::ios::end);
  const std::streamoff end = in.tellg();
  if (end > 0 && static_cast<std::uintmax_t>(end) > max_bytes) {
    tooLarge(path, std::to_string(end) + " bytes", max_bytes);
  }
  in.clear();
  in.seekg(0, std::ios::beg);
  in.clear();
  std::string text;
  char block[65536];
  while (in) {
    in.read(block, sizeof(block));
    text.append(block, static_cast<std::size_t>(in.gcount()));
    if (text.size() > max_bytes)
      tooLarge(path, "more than " + std::to_string(max_bytes) + " bytes", max_bytes);
  }
  if (in.bad()) throw ConfigError(path + ": cannot read file");
  return text;
}

std::string readBoundedJsonFile(const std::string& path, std::uintmax_t max_bytes,
                                std::size_t max_depth) {
  std::string text = readBoundedFile(path, max_bytes);
  checkJsonDepth(text, path, max_depth);
  return text;
}

}  // namespace hameritt::scenario
