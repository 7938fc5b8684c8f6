#include "hameritt/adk/path_csv.h"

#include <gtest/gtest.h>

#include <fstream>

#include "../scenario/test_util.h"
#include "hameritt/scenario/error.h"

namespace hameritt::adk {
namespace {

std::string errorOf(const std::string& text) {
  try {
    parsePathCsv(text, "p.csv");
  } catch (const scenario::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(PathCsv, ParsesSamplesPaddingCrlfAndIgnoresExtraColumns) {
  const auto p = parsePathCsv("t,x,y,z,yaw\r\n0, 1.5 ,2,3,0.1\r\n\r\n0.25,-4,5e1,6,9\r\n", "p.csv");
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[0].t, 0.0);
  EXPECT_EQ(p[0].p, geometry::Vec3(1.5, 2, 3));
  EXPECT_EQ(p[1].t, 0.25);
  EXPECT_EQ(p[1].p, geometry::Vec3(-4, 50, 6));
}

TEST(PathCsv, RoundTripsExactly) {
  std::vector<PathSample> path = {{0.1, {1.0 / 3.0, -2e-7, 45.25}},
                                  {0.30000000000000004, {1, 2, 3}}};
  const auto back = parsePathCsv(pathCsv(path), "x");
  ASSERT_EQ(back.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back[i].t, path[i].t);
    EXPECT_EQ(back[i].p, path[i].p);
  }
}

TEST(PathCsv, ErrorsNameFileLineAndColumn) {
  EXPECT_EQ(errorOf("t,x,y\n0,1,2\n"),
            "p.csv:1: header: expected the columns t,x,y,z first, got 't,x,y'");
  EXPECT_EQ(errorOf("t,x,z,y\n0,1,2,3\n"),
            "p.csv:1: header column 3: expected 'y' (the header starts t,x,y,z), got 'z'");
  EXPECT_EQ(errorOf("0,1,2,3\n"),
            "p.csv:1: header column 1: expected 't' (the header starts t,x,y,z), got '0'");
  EXPECT_EQ(errorOf("t,x,y,z,\n0,1,2,3,4\n"),
            "p.csv:1: header column 5: expected a column name, got an empty field");
  EXPECT_EQ(errorOf("t,x,y,z\n0,1,2,3\n1,abc,2,3\n"),
            "p.csv:3: column 2 (x): expected a finite number, got 'abc'");
  EXPECT_EQ(errorOf("t,x,y,z\n0,1,2,nan\n"),
            "p.csv:2: column 4 (z): expected a finite number, got 'nan'");
  EXPECT_EQ(errorOf("t,x,y,z\n0,1,2,1e999\n"),
            "p.csv:2: column 4 (z): expected a finite number, got '1e999'");
  EXPECT_EQ(errorOf("t,x,y,z\n0,1,,3\n"),
            "p.csv:2: column 3 (y): expected a finite number, got ''");
  EXPECT_EQ(errorOf("t,x,y,z\n0,1,2\n"), "p.csv:2: expected 4 fields as in the header, got 3");
  EXPECT_EQ(errorOf("t,x,y,z,yaw\n0,1,2,3\n"),
            "p.csv:2: expected 5 fields as in the header, got 4");
  EXPECT_EQ(errorOf("t,x,y,z\n0,1,2,3\n\n2,1,2,3\n1.5,1,2,3\n"),
            "p.csv:5: column 1 (t): expected a time after the previous sample's 2 (strictly "
            "increasing), got 1.5");
  EXPECT_EQ(errorOf("t,x,y,z\n2,1,2,3\n2,1,2,3\n"),
            "p.csv:3: column 1 (t): expected a time after the previous sample's 2 (strictly "
            "increasing), got 2");
  EXPECT_EQ(errorOf(""), "p.csv: empty file: expected a header t,x,y,z");
  EXPECT_EQ(errorOf("t,x,y,z\n"), "p.csv: no samples: expected rows after the header");
}

TEST(PathCsv, ReadsFilesAndNamesAMissingOne) {
  const std::string dir = scenario::testing::freshTempDir("path_csv");
  {
    std::ofstream f(dir + "/a.csv");
    f << "t,x,y,z\n0,1,2,3\n";
  }
  EXPECT_EQ(readPathCsv(dir + "/a.csv").size(), 1u);
  try {
    readPathCsv(dir + "/missing.csv");
    FAIL();
  } catch (const scenario::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/missing.csv: cannot read"), std::string::npos);
  }
}

}  // namespace
}  // namespace hameritt::adk
