#pragma once
// A small streaming JSON writer: compact or two-space indented output, numbers in the
// shortest form that reads back to the same double (std::to_chars), so that output is
// byte-identical for identical values on every run. Used for the generator's hot path, where
// building a DOM first would cost more than the geometry.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hameritt::scenario {

class JsonWriter {
 public:
  // reserve: bytes to allocate up front (a good guess saves regrowing the buffer).
  explicit JsonWriter(bool pretty = true, std::size_t reserve = 1 << 14) : pretty_(pretty) {
    out_.reserve(reserve);
  }

  JsonWriter& beginObject();
  JsonWriter& endObject();
  JsonWriter& beginArray();
  JsonWriter& endArray();
  // Starts a member of the current object; the next value call writes its value.
  JsonWriter& key(std::string_view k);
  JsonWriter& value(std::string_view s);
  JsonWriter& value(const char* s) { return value(std::string_view(s)); }
  JsonWriter& value(const std::string& s) { return value(std::string_view(s)); }
  JsonWriter& value(double d);
  JsonWriter& value(std::int64_t i);
  JsonWriter& value(int i) { return value(static_cast<std::int64_t>(i)); }
  JsonWriter& value(std::uint64_t u);
  JsonWriter& value(bool b);
  JsonWriter& null();
  // An array of numbers on one line, e.g. a point [x, y].
  JsonWriter& numbers(std::initializer_list<double> v);

  // The document (call after the outermost end*()); ends with a newline.
  std::string str() const { return out_ + "\n"; }
  // The same document as str(), moved out without a copy; the writer is empty afterwards.
  std::string take() {
    out_ += '\n';
    return std::move(out_);
  }

 private:
  void separate();
  void newline();
  void escape(std::string_view s);

  bool pretty_;
  std::string out_;
  // Per open container: whether it already has an element; and whether it is inline.
  std::vector<bool> has_items_;
  bool after_key_ = false;
  int inline_depth_ = 0;
};

}  // namespace hameritt::scenario
