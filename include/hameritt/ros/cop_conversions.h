#pragma once
// The COP between its core (cop::Track, cop::Observation, cop::TargetSpec) and ROS messages:
// claims (hameritt/Detection) and perfect-perception reports (hameritt/PerceptionReport) in,
// hameritt/CopTrack out, and a CopTrack as the TAK bridge's cop::TrackReport.

#include <vector>

#include "hameritt/CopTrack.h"
#include "hameritt/Detection.h"
#include "hameritt/Mission.h"
#include "hameritt/PerceptionReport.h"
#include "hameritt/cop/operational_picture.h"
#include "hameritt/cop/tak_events.h"

namespace hameritt::ros_wrappers {

// A perception client's claim; sigma: its 1-sigma position error (m).
cop::Observation fromMsg(const hameritt::Detection& msg, double sigma);

// Every entity of a perfect-perception report (confidence 1, entity ids kept).
std::vector<cop::Observation> fromMsg(const hameritt::PerceptionReport& msg, double sigma);

// The mission objective's targets (class and the described attributes).
std::vector<cop::TargetSpec> targetsOf(const hameritt::Mission& msg);

// The mission's areas of interest and keep-out zones.
std::vector<cop::ZoneReport> zonesOf(const hameritt::Mission& msg);

hameritt::CopTrack toMsg(const cop::Track& track);

// The bridge's view of a track: ce = sqrt of the larger horizontal covariance eigenvalue.
cop::TrackReport toTrackReport(const hameritt::CopTrack& msg);

}  // namespace hameritt::ros_wrappers
