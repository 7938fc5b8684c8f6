#pragma once
// Shared by the fuzz targets: the input as text, and a hard failure for a broken property.
// A target lets only the project's typed error escape its try block; any other exception, an
// abort, a sanitizer report or a timeout is a finding (libFuzzer saves the input).

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace hameritt::fuzz {

// The fuzzer's bytes as a std::string (embedded NULs kept).
inline std::string text(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

// Aborts (a libFuzzer crash, input saved) when a property of an accepted input does not hold.
inline void require(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz property violated: %s\n", what);
    std::abort();
  }
}

// The checkout's config/schema (the validator's schemas).
inline std::string schemaDir() { return std::string(HAMERITT_FUZZ_ROOT) + "/config/schema"; }

}  // namespace hameritt::fuzz
