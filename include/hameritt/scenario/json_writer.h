#pragma once
// A small streaming JSON writer: compact or two-space indented output, numbers in the
// shortest form that reads back to the same double (std::to_chars), so that output is
// byte-identical for identical values on every run. Used for the generator's hot path, where
// building a DOM first would cost more than the geometry.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hameritt::scenario {

class JsonWriter {
 public:
  // reserve: bytes to allocate up front (a good guess saves regrowing the buffer).
  explicit JsonWriter(bool pretty = true, std::size_t reserve = 1 << 14) : pretty_(pretty) {
    out_.resize(std::max<std::size_t>(reserve, 64));
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
  std::string str() const { return out_.substr(0, len_) + "\n"; }
  // The same document as str(), moved out without a copy; the writer is empty afterwards.
  std::string take() {
    out_.resize(len_);
    out_ += '\n';
    len_ = 0;
    return std::move(out_);
  }

 private:
  void separate();
  void newline();
  void escape(std::string_view s);
  // Room for n more characters at the end of the document; returns where they go (the caller
  // writes them and adds what it used to len_).
  char* room(std::size_t n) {
    if (out_.size() - len_ < n) grow(n);
    return out_.data() + len_;
  }
  void grow(std::size_t n);
  void put(const char* s, std::size_t n) {
    std::memcpy(room(n), s, n);
    len_ += n;
  }
  void put(char c) {
    *room(1) = c;
    ++len_;
  }

  bool pretty_;
  // The document is out_'s first len_ characters: out_ is sized ahead (doubling when full), so
  // that appending is a bounds check and a copy into its buffer.
  std::string out_;
  std::size_t len_ = 0;
  // Per open container: whether it already has an element; and whether it is inline.
  std::vector<unsigned char> has_items_;
  bool after_key_ = false;
  int inline_depth_ = 0;
};

}  // namespace hameritt::scenario
