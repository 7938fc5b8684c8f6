#pragma once
// The Common Operational Picture: fuses detection reports (perception clients' claims and the
// ADK's perfect-perception reports) into tracks. Each track runs a constant-velocity Kalman
// filter on the ground plane (x, y, vx, vy; Bar-Shalom, Li and Kirubarajan, "Estimation with
// Applications to Tracking and Navigation", 2001, ch. 6: discretized continuous white-noise
// acceleration) and a random-walk filter on the height. Reports are associated to tracks by
// global-nearest-neighbour over the Mahalanobis distance of the innovation, gated by a chi-square
// threshold and by class compatibility. Tracks are confirmed by hits and deleted when stale;
// two tracks that have become statistically the same are merged.
// Everything is deterministic: the same reports in the same order give the same tracks and ids.

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace hameritt::cop {

// A report of one entity at one time.
struct Observation {
  double stamp = 0.0;                                  // seconds (sim time)
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // map (ENU) frame, bottom-face centre
  std::string entity_class;  // car, pedestrian, ... ("" = unknown: compatible with any)
  std::map<std::string, std::string> attributes;
  double confidence = 1.0;  // [0, 1]
  std::string source;       // client name, or "perfect_perception"
  std::string entity_id;    // ground truth (perfect perception only), "" otherwise
  double sigma = 3.0;       // 1-sigma horizontal position error of the report, metres
};

// What the mission asks to find: a class and attributes (vehicle_class, make, model, color).
struct TargetSpec {
  std::string id;
  std::string entity_class;
  std::map<std::string, std::string> attributes;  // only the described (non-empty) ones
};

// One fused track.
struct Track {
  std::string id;  // T0001, T0002, ... in order of creation
  std::string entity_class;
  // Merged attributes: per key, the accumulated confidence of each value seen.
  std::map<std::string, std::map<std::string, double>> attribute_votes;
  Eigen::Vector4d state = Eigen::Vector4d::Zero();  // x, y, vx, vy
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Identity();
  double z = 0.0;
  double z_variance = 1.0;
  double first_seen = 0.0;
  double last_seen = 0.0;
  std::uint32_t hits = 0;
  std::uint64_t last_report = 0;  // number of the last update() that fed it (1, 2, ...)
  bool confirmed = false;
  double miss_probability = 1.0;  // product of (1 - confidence) over the reports
  std::string entity_id;          // last ground-truth entity id associated ("" if none)
  std::map<std::string, std::uint32_t> sources;  // reports per source
  std::string target_id;       // mission target this track is believed to be ("" = none)
  double target_belief = 0.0;  // belief in that target (or the best one), [0, 1]

  // The attribute value with the most accumulated confidence per key (ties: smallest value).
  std::map<std::string, std::string> attributes() const;
  // Position covariance (x, y, z) from the filters.
  Eigen::Matrix3d positionCovariance() const;
};

// Tuning of the fusion; see validate().
struct CopConfig {
  double process_accel_sigma = 0.5;  // m/s^2, white acceleration of the CV model
  double height_walk_sigma = 0.1;    // m/sqrt(s), random walk of the height
  double gate_chi2 = 13.82;          // Mahalanobis^2 gate, chi-square 2 dof at 99.9 %
  // Two tracks whose positions differ by less than this Mahalanobis^2 (summed covariances) are
  // one entity seen twice (a report that fell outside the gate): the newer merges into the older,
  // unless one report fed both (two entities side by side). 0 turns merging off.
  double merge_chi2 = 2.0;
  double initial_speed_sigma = 5.0;  // m/s, velocity prior of a new track
  std::uint32_t confirm_hits = 3;
  double tentative_timeout = 5.0;    // s without reports before a tentative track is deleted
  double confirmed_timeout = 120.0;  // s without reports before a confirmed track is deleted
  double belief_threshold = 0.5;     // a track at or above this is "believed to be" the target

  // Throws std::invalid_argument naming the field and the bad value.
  void validate() const;
};

// Counters for logs and benchmarks.
struct CopStats {
  std::uint64_t observations = 0;
  std::uint64_t associated = 0;
  std::uint64_t created = 0;
  std::uint64_t deleted = 0;
  std::uint64_t merged = 0;
};

// The picture: tracks keyed by id, the mission's targets and the association logic.
class OperationalPicture {
 public:
  explicit OperationalPicture(const CopConfig& config = {});

  // The targets beliefs are computed against (replaces the previous ones; beliefs refresh).
  void setTargets(std::vector<TargetSpec> targets);

  // Fuses one report's observations (all from the same frame: one-to-one association).
  void update(const std::vector<Observation>& observations);

  // Deletes tracks stale at `now`; returns the ids deleted.
  std::vector<std::string> prune(double now);

  // Belief that `track` is `target`, [0, 1]: attribute agreement (class must match; the product
  // over the described attributes of 1 if the track's value matches, 0.02 if it differs, 1/2 if
  // unknown: look-alikes differ in one attribute) times the probability that at least one report
  // was right, 1 - prod(1 - confidence).
  static double belief(const Track& track, const TargetSpec& target);

  // Tracks ordered by id.
  const std::map<std::string, Track>& tracks() const { return tracks_; }
  const std::vector<TargetSpec>& targets() const { return targets_; }
  const CopStats& stats() const { return stats_; }
  const CopConfig& config() const { return config_; }

 private:
  void predict(Track& t, double stamp) const;
  void correct(Track& t, const Observation& o);
  Track create(const Observation& o);
  void refreshBeliefs();
  void mergeDuplicates();

  CopConfig config_;
  std::map<std::string, Track> tracks_;
  std::vector<TargetSpec> targets_;
  std::uint64_t next_id_ = 1;
  std::uint64_t reports_ = 0;
  CopStats stats_;
};

}  // namespace hameritt::cop
