#pragma once
// The city mission's own cars against the ambient traffic: the ambient cars are simulated once
// per traffic episode, shared by every scenario that draws it, and never see a scenario's own
// cars. A scenario therefore withholds every ambient car that would come near one of its own
// cars (SimConfig::traffic's withheld ids): the footprints are compared every
// kClearanceStep seconds over the scenario's duration.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "hameritt/scenario/scenario.h"

namespace hameritt::scenario {

// The sampling step of the comparison (s) and the margin by which a scenario keeps the ambient
// cars it keeps away from its own (m, on every side of each footprint).
constexpr double kClearanceStep = 0.1;
constexpr double kTrafficClearance = 0.5;

// The broad phase compares footprints over blocks of this many seconds (20 samples).
constexpr double kClearanceBlock = 2.0;

// A box (x and y bounds) that holds a footprint over a stretch of time.
struct ClearanceBox {
  double min_x = 0.0, min_y = 0.0, max_x = 0.0, max_y = 0.0;
};

// The boxes that hold a footprint, grown by `margin` on every side, over consecutive blocks of
// its trajectory's own time: boxes[e] holds it over [e, e + 1] * kClearanceBlock, and the last
// one from its start on (the trajectory has ended there). A shared traffic episode computes its
// cars' once (SharedTrafficEpisode::clearance), so that each scenario that draws the episode
// compares its own cars with them without walking every ambient trajectory again.
struct ClearanceBlocks {
  double margin = kTrafficClearance;
  std::vector<ClearanceBox> boxes;
};

// A grid over many footprints' blocks (a shared episode's cars): for each block e and each
// `cell` x `cell` m square, the footprints whose box at e touches it (a footprint's last box
// stands for every later block). A scenario then looks up, per block of its own cars, only the
// ambient cars near them instead of comparing every ambient car's boxes.
struct ClearanceIndex {
  double margin = kTrafficClearance;
  double cell = 64.0;
  double x0 = 0.0, y0 = 0.0;  // the grid's corner
  int nx = 0, ny = 0;
  std::size_t blocks = 0;
  // The footprints of block e and cell (ix, iy): cars[start[k]] .. cars[start[k + 1] - 1] with
  // k = slot(e, ix, iy), ascending.
  std::vector<std::uint32_t> start;
  std::vector<std::uint32_t> cars;
  // The footprints' blocks the index was built from.
  const std::vector<ClearanceBlocks>* source = nullptr;

  // A cell's blocks lie side by side: a query walks a few cells over consecutive blocks.
  std::size_t slot(std::size_t e, int ix, int iy) const {
    return (static_cast<std::size_t>(iy) * static_cast<std::size_t>(nx) +
            static_cast<std::size_t>(ix)) * blocks + e;
  }

  // The cells (clamped to the grid) that box b touches.
  void cellRange(const ClearanceBox& b, int* x0, int* y0, int* x1, int* y1) const;
};

// The grid of `blocks` (every one with at least one box and the same margin; the vector must
// outlive the index).
ClearanceIndex clearanceIndex(const std::vector<ClearanceBlocks>& blocks, double cell = 64.0);

// A car's footprint moving along a trajectory: a length x width rectangle centred on the pose,
// along its yaw. The scenario's t is the trajectory's t - time_shift (an episode car's
// trajectory runs on episode time, the scenario starting at its offset). A trajectory with a
// single point, or none, stands at `pose`.
struct MovingFootprint {
  const Trajectory* trajectory = nullptr;
  TrajectoryPoint pose;
  double time_shift = 0.0;
  double length = 4.5;
  double width = 1.8;
  // Optional: this footprint's clearanceBlocks() (on the trajectory's own time, time_shift not
  // applied); used when its margin is the comparison's.
  const ClearanceBlocks* blocks = nullptr;
};

// The blocks of `f`'s trajectory (its time_shift ignored) over [0, its last point's t].
ClearanceBlocks clearanceBlocks(const MovingFootprint& f, double margin = kTrafficClearance);

// The footprint of a scenario entity: its box's length and width along its trajectory, or at
// its box when it has none.
MovingFootprint footprintOf(const ScenarioEntity& se);

// Whether a scenario entity is one of the mission's own cars: a car of any role but "traffic".
bool isMissionCar(const ScenarioEntity& se);

// Whether two rectangles (centres, yaws, half length and half width) overlap: the
// separating-axis test on their four edge normals (Gottschalk, Lin and Manocha 1996, "OBBTree").
bool rectanglesOverlap(double ax, double ay, double ayaw, double ahl, double ahw, double bx,
                       double by, double byaw, double bhl, double bhw);

// The first t = k * kClearanceStep in [0, duration] at which the footprints of a and b, each
// grown by `margin` on every side, overlap; nullopt when they never do.
std::optional<double> firstOverlap(const MovingFootprint& a, const MovingFootprint& b,
                                   double duration, double margin);

// The indices (ascending) of the `traffic` cars whose footprint comes within `margin` of a
// `mission` car's at some sample of [0, duration].
std::vector<std::size_t> trafficToWithhold(const std::vector<MovingFootprint>& mission,
                                           const std::vector<MovingFootprint>& traffic,
                                           double duration, double margin = kTrafficClearance);
// The same cars, looked up in `index` (built from traffic[i].blocks, in order, every traffic
// footprint with the same time_shift): the same result as above, in a time that grows with the
// mission cars' blocks and the cars near them rather than with the number of traffic cars. Falls
// back to the comparison above when the index does not fit (another margin, other sizes).
std::vector<std::size_t> trafficToWithhold(const std::vector<MovingFootprint>& mission,
                                           const std::vector<MovingFootprint>& traffic,
                                           const ClearanceIndex& index, double duration,
                                           double margin = kTrafficClearance);

}  // namespace hameritt::scenario
