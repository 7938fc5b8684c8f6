// The streaming JSON writer: valid JSON, and numbers that read back to the same double.
#include "hameritt/scenario/json_writer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "hameritt/scenario/entity.h"

using hameritt::scenario::JsonWriter;
using hameritt::scenario::roundMilli;

TEST(JsonWriterTest, NumbersRoundTripExactly) {
  std::mt19937_64 gen(99);
  std::vector<double> values = {0.0, -0.0, 1.0, -1.0, 0.001, -0.001, 12.5, 1e-7, 123456789.123,
                                0.1 + 0.2, 1e300, -2.5e-300, 4.0000000000000001, 999.999};
  for (int i = 0; i < 20000; ++i) {
    const double raw = std::ldexp(static_cast<double>(gen() >> 11) * 0x1.0p-53 - 0.5, static_cast<int>(gen() % 40) - 10);
    values.push_back(raw);
    values.push_back(roundMilli(raw));
  }
  JsonWriter w(false);
  w.beginArray();
  for (double v : values) w.value(v);
  w.endArray();
  const auto j = nlohmann::json::parse(w.str());
  ASSERT_EQ(j.size(), values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    EXPECT_EQ(j[i].get<double>(), values[i] == 0.0 ? 0.0 : values[i]) << i;
  }
}

TEST(JsonWriterTest, MillimetreValuesPrintShort) {
  JsonWriter w(false);
  w.beginArray();
  for (double v : {roundMilli(12.3456), roundMilli(-0.0004), 3.0, roundMilli(-7.25), 0.5})
    w.value(v);
  w.endArray();
  EXPECT_EQ(w.str(), "[12.346,0,3,-7.25,0.5]\n");
}

TEST(JsonWriterTest, StructureAndEscaping) {
  JsonWriter w;
  w.beginObject();
  w.key("text").value("quote \" backslash \\ newline \n tab \t bell \x07");
  w.key("point").numbers({1.5, -2.0});
  w.key("empty").beginArray().endArray();
  w.key("nested").beginObject().key("flag").value(true).key("n").value(std::int64_t{-3}).endObject();
  w.key("none").null();
  w.endObject();
  const auto j = nlohmann::json::parse(w.str());
  EXPECT_EQ(j["text"], "quote \" backslash \\ newline \n tab \t bell \x07");
  EXPECT_EQ(j["point"][1], -2.0);
  EXPECT_TRUE(j["empty"].empty());
  EXPECT_EQ(j["nested"]["n"], -3);
  EXPECT_TRUE(j["none"].is_null());
  EXPECT_THROW(JsonWriter().value(std::nan("")), std::invalid_argument);
}

// numbers() formats a whole array at once: the same characters as value() per element.
TEST(JsonWriterTest, NumberArraysMatchValueByValue) {
  std::mt19937_64 gen(14);
  int checked = 0;
  for (int i = 0; i < 5000; ++i) {
    const double raw = std::ldexp(static_cast<double>(gen() >> 11) * 0x1.0p-53 - 0.5,
                                  static_cast<int>(gen() % 50) - 10);
    const double milli = roundMilli(raw);
    JsonWriter a(false);
    a.numbers({raw, milli, -milli, 0.0, -0.0, 0.0005, 1e12 + 0.5});
    JsonWriter b(false);
    b.beginArray();
    for (double v : {raw, milli, -milli, 0.0, -0.0, 0.0005, 1e12 + 0.5}) b.value(v);
    b.endArray();
    ASSERT_EQ(a.str(), b.str()) << raw;
    ++checked;
  }
  EXPECT_EQ(checked, 5000);
  // Pretty output keeps the array on one line with ", " between numbers; a long list that
  // overflows the formatting buffer comes out whole.
  JsonWriter p;
  p.beginObject();
  p.key("p").numbers({1.5, -2.0, 0.25});
  p.key("long").numbers({0.1 + 0.2, 1e-7 / 3,  2.0 / 3,   -1.0 / 7, 0.1 + 0.2, 1e-7 / 3,  2.0 / 3,
                         -1.0 / 7,  0.1 + 0.2, 1e-7 / 3,  2.0 / 3,  -1.0 / 7,  0.1 + 0.2, 1e-7 / 3,
                         2.0 / 3,   -1.0 / 7,  0.1 + 0.2, 1e-7 / 3, 2.0 / 3,   -1.0 / 7,  12.345});
  p.key("none").numbers({});
  p.endObject();
  EXPECT_NE(p.str().find("\"p\": [1.5, -2, 0.25]"), std::string::npos) << p.str();
  EXPECT_NE(p.str().find("\"none\": []"), std::string::npos) << p.str();
  const auto j = nlohmann::json::parse(p.str());
  ASSERT_EQ(j["long"].size(), 21u);
  EXPECT_EQ(j["long"][0].get<double>(), 0.1 + 0.2);
  EXPECT_EQ(j["long"][19].get<double>(), -1.0 / 7);
  EXPECT_EQ(j["long"][20].get<double>(), 12.345);
  EXPECT_THROW(JsonWriter().numbers({1.0, std::nan("")}), std::invalid_argument);
}

// Strings without a character to escape are copied as they are, UTF-8 included.
TEST(JsonWriterTest, PlainStringsCopiedAsTheyAre) {
  JsonWriter w(false);
  w.beginObject().key("name").value("caf\xc3\xa9 street_12").key("q").value("a\"b").endObject();
  EXPECT_EQ(w.str(), "{\"name\":\"caf\xc3\xa9 street_12\",\"q\":\"a\\\"b\"}\n");
}

// Millimetre values (k / 1000) print as printf's "%.3f" without trailing zeros (and without the
// point when nothing follows it), on both sides of the eight-digit fast path (|k| < 10^8).
TEST(JsonWriterTest, MillimetreValuesMatchFixedPointText) {
  const auto expected = [](double d) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.3f", d);
    std::string s(buf);
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
    return s == "-0" ? std::string("0") : s;
  };
  std::vector<long long> ks;
  for (long long k = -20000; k <= 20000; ++k) ks.push_back(k);
  for (long long k = 99990000; k <= 100010000; ++k) ks.push_back(k);
  std::mt19937_64 gen(2026);
  for (int i = 0; i < 100000; ++i) {
    const long long mag = static_cast<long long>(gen() % 1000000000000000ULL);
    ks.push_back(static_cast<long long>(mag % (1LL << (gen() % 50))) * (gen() % 2 ? 1 : -1));
  }
  int checked = 0;
  for (long long k : ks) {
    const double d = static_cast<double>(k) / 1000.0;
    JsonWriter w(false);
    w.value(d);
    std::string text = w.str();
    text.pop_back();  // the final newline
    ASSERT_EQ(text, expected(d)) << k;
    JsonWriter a(false);
    a.numbers({d, -d});
    ASSERT_EQ(a.str(), "[" + expected(d) + "," + expected(-d) + "]\n") << k;
    ++checked;
  }
  EXPECT_EQ(checked, static_cast<int>(ks.size()));
}

// A writer reused after clear() (as writeScenarioDir() reuses one per thread) writes the same
// bytes as a fresh one, also when a document outgrows its buffer; finish() is str() in place.
TEST(JsonWriterTest, ReusedWriterWritesTheSameDocuments) {
  const auto document = [](JsonWriter& w, int n) {
    w.beginObject().key("name").value("doc").key("points").beginArray();
    for (int i = 0; i < n; ++i) w.numbers({i * 0.001, -i * 1.5, 1e-7 * i});
    w.endArray().key("last").value(std::int64_t{n}).endObject();
  };
  JsonWriter reused(true, 64);
  for (int n : {3, 2000, 0, 40, 5000, 1}) {
    JsonWriter fresh;
    document(fresh, n);
    reused.clear(n % 2 == 0 ? 64 * static_cast<std::size_t>(n) : 0);
    document(reused, n);
    const std::string expected = fresh.str();
    ASSERT_EQ(reused.str(), expected) << n;
    ASSERT_EQ(std::string(reused.finish()), expected) << n;
    ASSERT_EQ(nlohmann::json::parse(expected)["points"].size(), static_cast<std::size_t>(n));
  }
  JsonWriter taken(false, 64);
  document(taken, 100);
  const std::string text = taken.take();
  EXPECT_EQ(text.back(), '\n');
  document(taken, 100);  // empty after take(): the same document again
  EXPECT_EQ(taken.str(), text);
}
