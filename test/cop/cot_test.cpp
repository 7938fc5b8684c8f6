// CoT 2.0 event XML: escaping, times, required attributes, shapes; parsed back with tinyxml2.
#include "hameritt/cop/cot.h"

#include <gtest/gtest.h>
#include <tinyxml2.h>

#include "hameritt/cop/tak_events.h"

namespace hameritt::cop {
namespace {

TEST(Cot, EscapesXmlSpecialAndControlCharacters) {
  EXPECT_EQ(xmlEscape("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&apos;");
  EXPECT_EQ(xmlEscape(std::string("x\x01y\x1fz", 5)), "xyz");
  EXPECT_EQ(xmlEscape("line\nnext"), "line&#10;next");
  EXPECT_EQ(xmlEscape("Müller"), "Müller");  // UTF-8 passes through
}

TEST(Cot, IsoTimesAreUtcWithMilliseconds) {
  EXPECT_EQ(isoTime(0.0), "1970-01-01T00:00:00.000Z");
  EXPECT_EQ(isoTime(1795556529.123), "2026-11-24T21:42:09.123Z");
  EXPECT_EQ(isoTime(1795556529.9996), "2026-11-24T21:42:10.000Z");  // rounds into the next second
  EXPECT_EQ(isoTime(951782400.5), "2000-02-29T00:00:00.500Z");      // leap day
}

TEST(Cot, EventParsesWithTheRequiredSchemaFields) {
  CotEvent e;
  e.uid = "hameritt.track.T0001";
  e.type = "a-u-G";
  e.how = "m-f";
  e.time = e.start = 1795556529.25;
  e.stale = e.time + 30;
  e.point = {42.4851, -71.1873, 40.5, 2.5, 1.0};
  e.callsign = "T0001 <car> & \"friends\"";
  e.track = std::make_pair(90.0, 3.5);
  e.remarks = "white Toyota RAV4 (suv) <believed target>";
  e.extra = {{"track", "T0001"}, {"belief", "0.930"}};
  const std::string xml = toXml(e);
  tinyxml2::XMLDocument doc;
  ASSERT_EQ(doc.Parse(xml.c_str()), tinyxml2::XML_SUCCESS) << xml;
  const tinyxml2::XMLElement* ev = doc.FirstChildElement("event");
  ASSERT_NE(ev, nullptr);
  EXPECT_STREQ(ev->Attribute("version"), "2.0");
  EXPECT_STREQ(ev->Attribute("uid"), "hameritt.track.T0001");
  EXPECT_STREQ(ev->Attribute("type"), "a-u-G");
  EXPECT_STREQ(ev->Attribute("how"), "m-f");
  EXPECT_STREQ(ev->Attribute("time"), "2026-11-24T21:42:09.250Z");
  EXPECT_STREQ(ev->Attribute("start"), "2026-11-24T21:42:09.250Z");
  EXPECT_STREQ(ev->Attribute("stale"), "2026-11-24T21:42:39.250Z");
  const tinyxml2::XMLElement* pt = ev->FirstChildElement("point");
  ASSERT_NE(pt, nullptr);
  EXPECT_NEAR(pt->DoubleAttribute("lat"), 42.4851, 1e-9);
  EXPECT_NEAR(pt->DoubleAttribute("lon"), -71.1873, 1e-9);
  EXPECT_NEAR(pt->DoubleAttribute("hae"), 40.5, 1e-9);
  EXPECT_NEAR(pt->DoubleAttribute("ce"), 2.5, 1e-9);
  EXPECT_NEAR(pt->DoubleAttribute("le"), 1.0, 1e-9);
  const tinyxml2::XMLElement* d = ev->FirstChildElement("detail");
  ASSERT_NE(d, nullptr);
  EXPECT_STREQ(d->FirstChildElement("contact")->Attribute("callsign"), "T0001 <car> & \"friends\"");
  EXPECT_NEAR(d->FirstChildElement("track")->DoubleAttribute("course"), 90.0, 1e-9);
  EXPECT_NEAR(d->FirstChildElement("track")->DoubleAttribute("speed"), 3.5, 1e-9);
  EXPECT_STREQ(d->FirstChildElement("remarks")->GetText(),
               "white Toyota RAV4 (suv) <believed target>");
  EXPECT_STREQ(d->FirstChildElement("hameritt")->Attribute("belief"), "0.930");
  EXPECT_EQ(d->FirstChildElement("link"), nullptr);
}

TEST(Cot, ZonesAreClosedFreeformShapesWithLinkPoints) {
  const EnuFrame frame({42.4851, -71.1873, 40.0});
  ZoneReport z;
  z.id = "koz_1";
  z.keep_out = true;
  z.purpose = "vantage_denial";
  z.polygon = {{0, 0}, {100, 0}, {100, 50}, {0, 50}};
  z.alt_max = 96;
  TakEventConfig config;
  const CotEvent e = zoneEvent(frame, z, 1000.0, config);
  EXPECT_EQ(e.uid, "hameritt.koz.koz_1");
  EXPECT_EQ(e.type, "u-d-f");
  EXPECT_DOUBLE_EQ(e.stale, 1000.0 + config.zone_stale_s);
  tinyxml2::XMLDocument doc;
  ASSERT_EQ(doc.Parse(toXml(e).c_str()), tinyxml2::XML_SUCCESS);
  const tinyxml2::XMLElement* d = doc.FirstChildElement("event")->FirstChildElement("detail");
  std::vector<Eigen::Vector3d> links;
  for (auto* l = d->FirstChildElement("link"); l; l = l->NextSiblingElement("link")) {
    double lat = 0, lon = 0;
    ASSERT_EQ(std::sscanf(l->Attribute("point"), "%lf,%lf", &lat, &lon), 2);
    links.push_back(frame.toEnu({lat, lon, 40.0}));
  }
  ASSERT_EQ(links.size(), 5u);  // closed: the first vertex again
  EXPECT_LT((links.front() - links.back()).norm(), 1e-6);
  for (size_t i = 0; i < 4; ++i)
    EXPECT_LT((links[i].head<2>() - z.polygon[i]).norm(), 0.01) << i;  // 1e-8 deg ~ 1 mm
  EXPECT_NE(d->FirstChildElement("strokeColor"), nullptr);
  EXPECT_EQ(d->FirstChildElement("strokeColor")->IntAttribute("value"), -65536);
  EXPECT_NE(std::string(d->FirstChildElement("remarks")->GetText()).find("96"), std::string::npos);
}

TEST(Cot, UavAndTrackEventsCarryPositionCourseAndBelief) {
  const EnuFrame frame({42.4851, -71.1873, 40.0});
  TakEventConfig config;
  const CotEvent uav =
      uavEvent(frame, Eigen::Vector3d(10, 20, 60), Eigen::Vector3d(0, -5, 0), 50.0, config);
  EXPECT_EQ(uav.type, "a-f-A-M-F-Q");
  EXPECT_EQ(uav.uid, "hameritt.uav");
  EXPECT_NEAR(uav.track->first, 180.0, 1e-9);  // moving south
  EXPECT_NEAR(uav.track->second, 5.0, 1e-9);
  const Eigen::Vector3d back = frame.toEnu({uav.point.lat, uav.point.lon, uav.point.hae});
  EXPECT_LT((back - Eigen::Vector3d(10, 20, 60)).norm(), 1e-6);
  EXPECT_DOUBLE_EQ(uav.stale - uav.time, config.stale_s);

  TrackReport t;
  t.id = "T0003";
  t.entity_class = "car";
  t.attributes = {{"color", "white"}};
  t.velocity = Eigen::Vector2d(-1, 0);  // west
  t.target_id = "car_706";
  t.target_belief = 0.93;
  const CotEvent te = trackEvent(frame, t, 50.0, config);
  EXPECT_EQ(te.type, "a-u-G");
  EXPECT_EQ(te.uid, "hameritt.track.T0003");
  EXPECT_NEAR(te.track->first, 270.0, 1e-9);
  EXPECT_NE(te.remarks.find("believed target car_706"), std::string::npos);
  EXPECT_NEAR(courseDegrees({1, 1}), 45.0, 1e-9);
  EXPECT_NEAR(courseDegrees({0, 0}), 0.0, 1e-9);
}

}  // namespace
}  // namespace hameritt::cop
