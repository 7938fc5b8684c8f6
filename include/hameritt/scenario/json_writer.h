#pragma once
// A small streaming JSON writer: compact or two-space indented output, numbers in the
// shortest form that reads back to the same double (std::to_chars), so that output is
// byte-identical for identical values on every run. Used for the generator's hot path, where
// building a DOM first would cost more than the geometry.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hameritt::scenario {

class JsonWriter {
 public:
  // reserve: bytes to allocate up front (a good guess saves regrowing the buffer).
  explicit JsonWriter(bool pretty = true, std::size_t reserve = 1 << 14)
      : pretty_(pretty), cap_(std::max<std::size_t>(reserve, 64)), buf_(new char[cap_]) {}

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
  std::string str() const {
    std::string s;
    s.reserve(len_ + 1);
    s.append(buf_.get(), len_);
    s += '\n';
    return s;
  }
  // The same document as str(); the writer is empty afterwards (see clear()).
  std::string take() {
    std::string s = str();
    clear();
    return s;
  }
  // The document with its final newline, in the writer's own buffer (no copy): valid until
  // the writer is changed or destroyed. Call once, after the outermost end*().
  std::string_view finish() {
    put('\n');
    return {buf_.get(), len_};
  }
  // Empties the writer for a new document; its buffer is kept (and grown to at least reserve
  // bytes), so a writer reused for document after document allocates nothing.
  void clear(std::size_t reserve = 0) {
    len_ = 0;
    has_items_.clear();
    after_key_ = false;
    if (reserve > cap_) grow(reserve);
  }

 private:
  void separate();
  void newline();
  void escape(std::string_view s);
  // Room for n more characters at the end of the document; returns where they go (the caller
  // writes them and adds what it used to len_).
  char* room(std::size_t n) {
    if (cap_ - len_ < n) grow(n);
    return buf_.get() + len_;
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
  // The document is the first len_ characters of buf_ (cap_ bytes, not initialized; doubled
  // when full), so that appending is a bounds check and a copy.
  std::size_t cap_;
  std::unique_ptr<char[]> buf_;
  std::size_t len_ = 0;
  // Per open container: whether it already has an element; and whether it is inline.
  std::vector<unsigned char> has_items_;
  bool after_key_ = false;
  int inline_depth_ = 0;
};

}  // namespace hameritt::scenario
