#pragma once
// At most one claim per candidate location: a client tells the ADK "I see the target here" once,
// not at every frame. ROS-free.

#include <deque>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "hameritt/geometry/types.h"

namespace hameritt::clients {

// Remembers where claims were made. A new claim within `radius` metres (in the plane) of an
// earlier one is a repeat until `hold` seconds have passed since that earlier claim (hold <= 0:
// forever).
class ClaimLedger {
 public:
  ClaimLedger(double radius = 4.0, double hold = 30.0);

  // True (and recorded) when a claim at p, time t, is new; false for a repeat.
  bool claim(const geometry::Vec3& p, double t);
  // True when a claim at p, time t, would be a repeat (nothing recorded).
  bool isRepeat(const geometry::Vec3& p, double t) const;
  // Distinct locations claimed so far.
  std::size_t locations() const;

 private:
  struct Claim {
    geometry::Vec3 p;
    double t;
  };
  double radius_, hold_;
  std::vector<Claim> claims_;
  std::vector<geometry::Vec3> places_;
};

// Where vehicles of each description stand: a sighting of a description is standing when a
// sighting of the same description lay within `radius` metres of it (in the plane) at least
// `hold` seconds earlier. A track or pursuit target drives, so a look-alike that stands (a parked
// confuser, which the public map does not list) is not claimed as one while it stands; a target
// waiting at a red light is claimed once it drives on. Sightings older than `keep` seconds are
// forgotten.
class StandingSightings {
 public:
  StandingSightings(double radius = 1.0, double hold = 3.0, double keep = 60.0);

  // Records a sighting of description `key` at p, time t (not before the previous sighting's
  // time); true when it stands.
  bool observe(const std::string& key, const geometry::Vec3& p, double t);

 private:
  struct Sighting {
    geometry::Vec3 p;
    double t;
  };
  double radius_, hold_, keep_;
  std::map<std::string, std::vector<Sighting>> seen_;
};

// Where the targets of a convoy were sighted lately: the generator's track phase of several
// targets drives them together (the second "behind" the first), so a vehicle of one target's
// description is one of them only where a vehicle of another target's description was sighted
// within `radius` metres in the last `window` seconds; a look-alike driving alone is not.
class ConvoySightings {
 public:
  ConvoySightings(double radius = 80.0, double window = 20.0);

  // Records a sighting of description `key` at p, time t (not before the previous one's time).
  void observe(const std::string& key, const geometry::Vec3& p, double t);
  // Whether a sighting of a description other than `key` lies within the radius of p among
  // those of the window before t (the sightings already recorded).
  bool besideAnother(const std::string& key, const geometry::Vec3& p, double t) const;
  void clear() { seen_.clear(); }

 private:
  struct Sighting {
    std::string key;
    geometry::Vec2 p;
    double t;
  };
  double radius_, window_;
  std::deque<Sighting> seen_;
};

// Leads a pursuit set aside. A pursuit whose find is not confirmed (no target state from the ADK,
// no target claimed on a track phase), lost, with the UAV within `reach` metres (in the plane) of
// its prediction for more than `after` seconds, followed a false lead: a look-alike seen once,
// standing out of sight, or a car glimpsed from afar that drove off. Where it was last seen is set
// aside: a sighting within `radius` metres of it starts no pursuit and no claim again.
class FalseLeads {
 public:
  FalseLeads(double reach = 20.0, double after = 10.0, double radius = 8.0);

  // One pursuit tick at time t (not before the previous one's): true when the pursuit is to be
  // given up now. Any tick that is not lost, confirmed or out of reach restarts the count.
  // `confirm_by`: where a true find is confirmed at once (in maneuver_only mode the ADK sends a
  // found target's state within a tracker's period of the claim), the time by which it would
  // have been: past it, an unconfirmed pursuit is given up at once, lost or not (a look-alike
  // that the context could not tell apart, claimed, held in view and hovered over to the end).
  bool giveUp(double t, bool lost, bool confirmed, const geometry::Vec2& uav,
              const geometry::Vec2& prediction,
              double confirm_by = std::numeric_limits<double>::infinity());
  // A new pursuit: the count starts again.
  void restart() { reached_at_ = -1.0; }
  // Sets aside the lead last seen at p (and restarts the count).
  void setAside(const geometry::Vec2& p);
  // Whether p lies within the radius of a lead set aside.
  bool near(const geometry::Vec2& p) const;
  std::size_t size() const { return leads_.size(); }
  void clear();

 private:
  double reach_, after_, radius_;
  double reached_at_ = -1.0;  // since when the UAV, lost, is within reach of the prediction
  std::vector<geometry::Vec2> leads_;
};

}  // namespace hameritt::clients
