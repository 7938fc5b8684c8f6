#pragma once
// Scores of a track mission from ground truth and the client's reported tracks, as the tracking
// benchmarks define them: the single-target scores of UAV123 (Mueller, Smith and Ghanem, "A
// Benchmark and Simulator for UAV Tracking", ECCV 2016: precision at 20 px, success as the area
// under the IoU curve), breaks and reacquisition, and for several targets CLEAR-MOT (Bernardin
// and Stiefelhagen 2008), IDF1 (Ristani et al. 2016) and HOTA (Luiten et al., IJCV 2021)
// exactly as the TrackEval code computes them. ROS-free; the ADK node feeds it one frame per
// camera image.

#include <array>
#include <cstddef>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "hameritt/adk/intervals.h"  // InputError

namespace hameritt::adk {

// An axis-aligned image box in pixels: top-left corner and size.
struct PixelBox {
  double x = 0.0;
  double y = 0.0;
  double w = 0.0;
  double h = 0.0;
  double area() const { return w * h; }
};

// Intersection over union of two boxes; 0 when the union is empty.
double boxIou(const PixelBox& a, const PixelBox& b);

// Distance between the boxes' centres, pixels.
double centreError(const PixelBox& a, const PixelBox& b);

// Ground truth of one target in one frame, when its projection falls in the image at all (a
// target absent from a frame is out of view): its box (the whole target, occluded parts
// included, clipped to the image), the fraction of its projected pixels that are visible
// (occlusion and truncation by the image border both lower it) and the fraction of its
// in-image box hidden by occluders.
struct TargetTruth {
  std::string id;
  PixelBox box;
  double visible_fraction = 1.0;  // [0, 1]
  double occlusion = 0.0;         // [0, 1]
};

// One box the client reports in a frame, under its own track id. For the single-target scores
// a track whose id is a mission target's id is the client's estimate of that target.
struct ReportedTrack {
  std::string id;
  PixelBox box;
};

// Ground truth and reports of one camera frame at sim time t.
struct TrackingFrame {
  double t = 0.0;
  std::vector<TargetTruth> targets;
  std::vector<ReportedTrack> tracks;
};

// Thresholds (the mission's track criteria); validate() throws scenario::ConfigError naming
// "tracking.<field>" and the bad value.
struct TrackingSettings {
  double min_visible_fraction = 0.5;  // a target is tracked when at least this much shows
  double min_box_area = 400.0;        // px^2, and its box is at least this large
  double precision_threshold = 20.0;  // px, UAV123's precision
  double clear_threshold = 0.5;       // IoU for a CLEAR-MOT and an IDF1 match (TrackEval)
  // A target is a ground-truth detection for MOTA, IDF1 and HOTA when at least this fraction
  // of it shows (0: whenever it is in the image).
  double mot_min_visible_fraction = 0.0;
  void validate() const;
};

// Occlusion levels of a frame, from the target's occlusion: none (0), partial (0 to 0.5],
// heavy (0.5 to 1), full (1).
enum class OcclusionLevel { kNone = 0, kPartial = 1, kHeavy = 2, kFull = 3 };
constexpr std::size_t kOcclusionLevels = 4;
OcclusionLevel occlusionLevel(double occlusion);
// "none", "partial", "heavy", "full".
const char* occlusionLevelName(OcclusionLevel level);

// One target's frames at one occlusion level.
struct OcclusionLevelScore {
  std::size_t frames = 0;
  double tracked_fraction = 0.0;  // of these frames (0 when there are none)
  // Of these frames, those where the client's box of the target lies within the precision
  // threshold of the true box centre: the tracker holds the target through the occlusion.
  double held_fraction = 0.0;
};

// The single-target scores of one target.
struct TargetTrackingScore {
  std::string id;
  std::size_t frames = 0;          // frames of the sequence
  std::size_t in_view_frames = 0;  // frames with the target in the image
  std::size_t tracked_frames = 0;  // frames passing the tracked test
  double tracked_fraction = 0.0;   // tracked_frames / frames
  std::array<OcclusionLevelScore, kOcclusionLevels> by_occlusion;
  // UAV123 over the frames where the target shows (in view, occlusion < 1); a frame without a
  // box from the client has an infinite centre error and IoU 0.
  std::size_t scored_frames = 0;
  double precision = 0.0;  // fraction with centre error <= precision_threshold
  double success = 0.0;    // mean over thresholds 0, 0.05, ..., 1 of the fraction with IoU > it
  // Breaks: a tracked frame followed by an untracked one. A break ends at the next tracked
  // frame; the time to reacquire runs from the first untracked frame's stamp to it.
  std::size_t breaks = 0;
  std::size_t reacquired = 0;
  double reacquire_median_s = 0.0;  // over reacquired breaks (0 when none)
  double reacquire_max_s = 0.0;
  // A break still open at the last frame, from its first untracked frame to the last frame.
  double open_break_s = 0.0;
  // CLEAR-MOT identity switches of this target.
  std::size_t id_switches = 0;
};

// CLEAR-MOT as TrackEval's clear.py computes it.
struct ClearMotScore {
  std::size_t tp = 0, fn = 0, fp = 0, id_switches = 0;
  std::size_t mostly_tracked = 0, partly_tracked = 0, mostly_lost = 0, fragmentations = 0;
  double mota = 0.0;
  double motp = 0.0;
};

// The identity scores as TrackEval's identity.py computes them.
struct IdentityScore {
  std::size_t idtp = 0, idfn = 0, idfp = 0;
  double idf1 = 0.0, idr = 0.0, idp = 0.0;
};

// HOTA as TrackEval's hota.py computes it: each score at alpha = 0.05, 0.10, ..., 0.95, and
// its mean over the 19 alphas.
struct HotaScore {
  static constexpr std::size_t kAlphas = 19;
  std::array<double, kAlphas> alpha{}, hota{}, det_a{}, ass_a{}, det_re{}, det_pr{}, ass_re{},
      ass_pr{}, loc_a{};
  double mean_hota = 0.0, mean_det_a = 0.0, mean_ass_a = 0.0, mean_det_re = 0.0, mean_det_pr = 0.0,
         mean_ass_re = 0.0, mean_ass_pr = 0.0, mean_loc_a = 0.0;
};

// Every score of a sequence.
struct TrackingScore {
  std::vector<TargetTrackingScore> targets;  // in the order of the target ids given
  ClearMotScore clear;
  IdentityScore identity;
  HotaScore hota;
};

// Ground-truth ids, tracker ids and their IoUs per frame: TrackEval's input to its metrics.
struct MotFrame {
  std::vector<std::string> gt_ids;
  std::vector<std::string> tracker_ids;
  std::vector<std::vector<double>> similarity;  // [gt][tracker]
};

// The MOT frames of a sequence: each target with visible_fraction >= mot_min_visible_fraction
// is a ground-truth detection, each reported track a tracker detection, similarity their IoU.
std::vector<MotFrame> motFrames(const std::vector<TrackingFrame>& frames,
                                const TrackingSettings& settings);

// TrackEval's metrics over MOT frames. Ids need not be contiguous; ids that never occur do not
// count. Throws InputError for a similarity matrix of the wrong shape or with a
// value outside [0, 1], or an id twice in one frame.
ClearMotScore clearMot(const std::vector<MotFrame>& frames, double threshold = 0.5);
IdentityScore identityScore(const std::vector<MotFrame>& frames, double threshold = 0.5);
HotaScore hotaScore(const std::vector<MotFrame>& frames);

// Every score of a sequence of frames for the given mission targets. Throws
// InputError naming the frame and field for stamps that do not increase, a
// non-finite or negative box, a fraction outside [0, 1], or an id twice in one frame.
TrackingScore scoreTracking(const std::vector<TrackingFrame>& frames,
                            const std::vector<std::string>& target_ids,
                            const TrackingSettings& settings = {});

// Minimum-cost assignment of a rectangular cost matrix (rows x cols, finite costs): for each
// row the column it gets, or -1 when there are more rows than columns and it gets none. Every
// min(rows, cols) assignment of least total cost is a valid answer (Kuhn 1955, Munkres 1957;
// the O(n^3) shortest augmenting path form).
std::vector<int> minCostAssignment(const std::vector<std::vector<double>>& cost);

}  // namespace hameritt::adk

namespace hameritt::adk {

// Kinds of malformed client track reports: counted, never fatal.
struct TrackReportErrors {
  std::size_t unknown_id = 0;       // an id that is not a mission target's
  std::size_t bad_box = 0;          // non-finite, or negative width or height
  std::size_t duplicate_id = 0;     // the same id twice in one report
  std::size_t out_of_order = 0;     // a stamp not after the previous report's
  std::size_t unmatched_stamp = 0;  // no camera frame with that stamp
  std::size_t total() const {
    return unknown_id + bad_box + duplicate_id + out_of_order + unmatched_stamp;
  }
};

// Collects a track mission's frames as they happen: the ADK node adds each camera frame's
// ground truth, and each report the client publishes (the image stamp it refers to and its
// boxes). A report is matched to the frame with the same stamp (within 1 ms); malformed
// reports and tracks are dropped and counted, so that a client's bad output costs it score but
// never stops the scoring. ROS-free.
class TrackingRecorder {
 public:
  TrackingRecorder(std::vector<std::string> target_ids, TrackingSettings settings);

  // A camera frame's ground truth at sim time t. A t not after the previous frame's restarts
  // the recording (a simulator reset). Non-finite t: InputError.
  void addFrame(double t, std::vector<TargetTruth> targets);
  // A client report for the frame stamped `stamp`: bad tracks are dropped one by one (an
  // unknown id, a bad box, a repeated id), a whole report with an out-of-order or unmatched
  // stamp is dropped. A second report for a frame replaces the first. A report stamped after the
  // newest frame waits for its frame (a client may answer a frame before the ADK has it: two
  // subscriptions, no order between them); it is unmatched once a later frame comes instead,
  // or when more than kMaxPending wait.
  void addReport(double stamp, const std::vector<ReportedTrack>& tracks);
  static constexpr std::size_t kMaxPending = 64;

  const TrackReportErrors& errors() const { return errors_; }
  // Reports still waiting for their frame (unmatched if the recording ends now).
  std::size_t pendingReports() const { return pending_.size(); }
  std::size_t frames() const { return frames_.size(); }
  std::size_t reports() const { return reports_; }
  // Every score over the frames so far.
  TrackingScore score() const;

 private:
  std::vector<std::string> target_ids_;
  TrackingSettings settings_;
  std::vector<TrackingFrame> frames_;
  std::deque<std::pair<double, std::vector<ReportedTrack>>> pending_;  // in stamp order
  TrackReportErrors errors_;
  std::size_t reports_ = 0;
  bool have_report_ = false;
  double last_report_ = 0.0;
  void apply(TrackingFrame* frame, const std::vector<ReportedTrack>& tracks);
};

}  // namespace hameritt::adk
