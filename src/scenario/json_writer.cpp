#include "hameritt/scenario/json_writer.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>

namespace hameritt::scenario {

namespace {

// A comma, a newline and an indent of up to 64 spaces: separators are appended from it at once.
constexpr std::string_view kCommaIndent =
    ",\n                                                                ";

// True when s needs no escaping.
bool plainText(std::string_view s) {
  return std::all_of(s.begin(), s.end(), [](char c) {
    return static_cast<unsigned char>(c) >= 0x20 && c != '"' && c != '\\';
  });
}

}  // namespace

void JsonWriter::newline() {
  if (!pretty_ || inline_depth_ > 0) return;
  const std::size_t n = 1 + 2 * has_items_.size();
  if (n + 1 <= kCommaIndent.size()) {
    std::memcpy(room(kCommaIndent.size()), kCommaIndent.data() + 1, kCommaIndent.size() - 1);
    len_ += n;
  } else {
    char* p = room(n);
    p[0] = '\n';
    std::memset(p + 1, ' ', n - 1);
    len_ += n;
  }
}

void JsonWriter::grow(std::size_t n) {
  const std::size_t cap = std::max(2 * cap_, len_ + n);
  std::unique_ptr<char[]> buf(new char[cap]);
  std::memcpy(buf.get(), buf_.get(), len_);
  buf_ = std::move(buf);
  cap_ = cap;
}

void JsonWriter::separate() {
  if (after_key_) {
    after_key_ = false;
    return;
  }
  if (!has_items_.empty()) {
    const bool had = has_items_.back();
    has_items_.back() = true;
    const std::size_t n = 2 + 2 * has_items_.size();  // comma, newline, indent
    if (pretty_ && inline_depth_ == 0 && n <= kCommaIndent.size()) {
      // The comma (if any), the newline and the indent in one copy of fixed size (inlined;
      // the characters past the separator are overwritten next).
      char* const p = room(kCommaIndent.size());
      std::memcpy(p, kCommaIndent.data() + (had ? 0 : 1), kCommaIndent.size() - 1);
      len_ += had ? n : n - 1;
      return;
    }
    if (had) {
      put(',');
      if (inline_depth_ > 0 && pretty_) put(' ');
    }
    newline();
  }
}

JsonWriter& JsonWriter::beginObject() {
  separate();
  put('{');
  has_items_.push_back(false);
  return *this;
}

JsonWriter& JsonWriter::endObject() {
  const bool had = has_items_.back();
  has_items_.pop_back();
  if (had) newline();
  put('}');
  return *this;
}

JsonWriter& JsonWriter::beginArray() {
  separate();
  put('[');
  has_items_.push_back(false);
  return *this;
}

JsonWriter& JsonWriter::endArray() {
  const bool had = has_items_.back();
  has_items_.pop_back();
  if (had) newline();
  put(']');
  return *this;
}

JsonWriter& JsonWriter::key(std::string_view k) {
  separate();
  after_key_ = true;
  if (plainText(k)) {
    // The quoted key and the colon written at once.
    char* const p = room(k.size() + 4);
    std::size_t n = 0;
    p[n++] = '"';
    std::memcpy(p + n, k.data(), k.size());
    n += k.size();
    p[n++] = '"';
    p[n++] = ':';
    if (pretty_) p[n++] = ' ';
    len_ += n;
    return *this;
  }
  escape(k);
  pretty_ ? put(": ", 2) : put(':');
  return *this;
}

void JsonWriter::escape(std::string_view s) {
  put('"');
  // Plain text (the usual case: ids, keys, names) is copied at once.
  if (plainText(s)) {
    put(s.data(), s.size());
    put('"');
    return;
  }
  for (char c : s) {
    switch (c) {
      case '"':
        put("\\\"", 2);
        break;
      case '\\':
        put("\\\\", 2);
        break;
      case '\n':
        put("\\n", 2);
        break;
      case '\t':
        put("\\t", 2);
        break;
      case '\r':
        put("\\r", 2);
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof(buf), "\\u%04x", c);
          put(buf, 6);
        } else {
          put(c);
        }
    }
  }
  put('"');
}

JsonWriter& JsonWriter::value(std::string_view s) {
  separate();
  if (plainText(s)) {
    // A plain string with its quotes written at once.
    char* const p = room(s.size() + 2);
    p[0] = '"';
    std::memcpy(p + 1, s.data(), s.size());
    p[s.size() + 1] = '"';
    len_ += s.size() + 2;
    return *this;
  }
  escape(s);
  return *this;
}

namespace {

// "00" "01" ... "99".
constexpr char kDigitPairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

// Writes a's decimal digits just before end, two at a time; returns where they start. (Called
// with 32-bit values where they fit: their division by 100 is cheaper.)
template <typename U>
char* digitsBefore(U a, char* end) {
  char* q = end;
  while (a >= 100) {
    const unsigned r = static_cast<unsigned>(a % 100);
    a /= 100;
    q -= 2;
    std::memcpy(q, kDigitPairs + 2 * r, 2);
  }
  if (a >= 10) {
    q -= 2;
    std::memcpy(q, kDigitPairs + 2 * a, 2);
  } else {
    *--q = static_cast<char>('0' + a);
  }
  return q;
}

// The decimal digits of v < 10^8, most significant first, one per byte (values 0-9), all
// eight computed at once: v is split into two halves of four digits in 32-bit lanes, each half
// into two pairs in 16-bit lanes, each pair into two digits in bytes (division by 100 and by 10
// as multiply-and-shift, exact in these ranges).
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "eightDigits: byte 0 is written first");
inline std::uint64_t eightDigits(std::uint32_t v) {
  const std::uint64_t x = (v / 10000) | (static_cast<std::uint64_t>(v % 10000) << 32);
  const std::uint64_t hundreds = ((x * 10486) >> 20) & 0x0000007F0000007FULL;
  const std::uint64_t pairs = hundreds | ((x - 100 * hundreds) << 16);
  const std::uint64_t tens = ((pairs * 103) >> 10) & 0x000F000F000F000FULL;
  return tens | ((pairs - 10 * tens) << 8);
}

// Writes a finite number at p (room for 40 characters); returns the end.
// Inlined into numbers() and value(double): saves a call per number.
__attribute__((always_inline)) inline char* writeNumber(double d, char* p) {
  if (d == 0.0) d = 0.0;  // no "-0"
  char* const end = p + 40;
  // Most values are millimetre-rounded (k / 1000): print k's digits with the decimal point
  // moved, which is the shortest form that reads back to the same double and much faster
  // than the general algorithm. Anything else takes std::to_chars' shortest round-trip form.
  if (std::abs(d) < 1e12) {
    // std::llround(x) inline: |x| < 2^52, so x - trunc(x) is exact.
    const double x = d * 1000.0;
    long long k = static_cast<long long>(x);
    const double rest = x - static_cast<double>(k);
    if (rest >= 0.5) ++k;
    if (rest <= -0.5) --k;
    if (static_cast<double>(k) / 1000.0 == d) {
      unsigned long long a = k < 0 ? 0ULL - static_cast<unsigned long long>(k) : k;
      if (k < 0) *p++ = '-';
      if (a < 100000000ULL) {
        // Up to 99999.999 (nearly every value): the eight digits with leading zeros, then the
        // whole part from its first non-zero digit (at least the units) and the fraction
        // without its trailing zeros, as below. Copies write 8 and 4 bytes; bytes past the
        // number are overwritten later or lie past the returned end.
        const std::uint64_t digits = eightDigits(static_cast<std::uint32_t>(a));
        const int lead = digits == 0 ? 4 : std::min(4, __builtin_ctzll(digits) / 8);
        const std::uint64_t text = (digits + 0x3030303030303030ULL) >> (8 * lead);
        std::memcpy(p, &text, 8);
        p += 5 - lead;
        const std::uint64_t frac = digits >> 40;  // the three fraction digits, first in byte 0
        if (frac != 0) {
          const std::uint32_t tail = '.' | static_cast<std::uint32_t>((frac + 0x303030) << 8);
          std::memcpy(p, &tail, 4);
          p += 2 + (63 - __builtin_clzll(frac)) / 8;  // up to the last non-zero digit
        }
        return p;
      }
      // All digits of a (at least four), two at a time from a table, then the whole part,
      // the point and the fraction without its trailing zeros. Copies have fixed sizes
      // (inlined); bytes past the number are overwritten later or lie past the returned end.
      const unsigned frac = static_cast<unsigned>(a % 1000);
      char tmp[64];
      char* const tend = tmp + 40;
      char* q = a <= 0xffffffffULL ? digitsBefore(static_cast<std::uint32_t>(a), tend)
                                   : digitsBefore(a, tend);
      while (tend - q < 4) *--q = '0';
      const std::size_t whole_len = static_cast<std::size_t>(tend - q) - 3;  // at most 12
      std::memcpy(p, q, 16);
      p += whole_len;
      if (frac != 0) {
        *p = '.';
        std::memcpy(p + 1, tend - 3, 4);
        p += frac % 100 == 0 ? 2 : frac % 10 == 0 ? 3 : 4;
      }
      return p;
    }
  }
  return std::to_chars(p, end, d).ptr;
}

}  // namespace

JsonWriter& JsonWriter::value(double d) {
  if (!std::isfinite(d)) throw std::invalid_argument("JsonWriter: non-finite number");
  separate();
  char* const p = room(40);
  len_ += static_cast<std::size_t>(writeNumber(d, p) - p);
  return *this;
}

JsonWriter& JsonWriter::value(std::int64_t i) {
  separate();
  char* const p = room(24);
  len_ += static_cast<std::size_t>(std::to_chars(p, p + 24, i).ptr - p);
  return *this;
}

JsonWriter& JsonWriter::value(std::uint64_t u) {
  separate();
  char* const p = room(24);
  len_ += static_cast<std::size_t>(std::to_chars(p, p + 24, u).ptr - p);
  return *this;
}

JsonWriter& JsonWriter::value(bool b) {
  separate();
  b ? put("true", 4) : put("false", 5);
  return *this;
}

JsonWriter& JsonWriter::null() {
  separate();
  put("null", 4);
  return *this;
}

// The same characters as beginArray(), value() per number and the closing bracket, formatted
// straight into the document (room for 48 characters per number is made first).
JsonWriter& JsonWriter::numbers(std::initializer_list<double> v) {
  for (double d : v) {
    if (!std::isfinite(d)) throw std::invalid_argument("JsonWriter: non-finite number");
  }
  separate();
  char* const start = room(2 + 48 * v.size());
  char* p = start;
  *p++ = '[';
  for (const double* d = v.begin(); d != v.end(); ++d) {
    if (d != v.begin()) {
      *p++ = ',';
      if (pretty_) *p++ = ' ';
    }
    p = writeNumber(*d, p);
  }
  *p++ = ']';
  len_ += static_cast<std::size_t>(p - start);
  return *this;
}

}  // namespace hameritt::scenario
