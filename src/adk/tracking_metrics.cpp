#include "hameritt/adk/tracking_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "hameritt/scenario/error.h"

namespace hameritt::adk {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();  // numpy's finfo(float).eps
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string num(double v) { return scenario::formatNumber(v); }

void requireFraction(double v, const std::string& field) {
  if (!(v >= 0.0 && v <= 1.0)) {
    throw InputError(field + ": expected a number in [0, 1], got " + num(v));
  }
}

void requireBox(const PixelBox& b, const std::string& field) {
  if (!std::isfinite(b.x) || !std::isfinite(b.y) || !std::isfinite(b.w) || !std::isfinite(b.h) ||
      b.w < 0.0 || b.h < 0.0) {
    throw InputError(field + ": expected finite x, y and a non-negative finite w, h, got (" +
                     num(b.x) + ", " + num(b.y) + ", " + num(b.w) + ", " + num(b.h) + ")");
  }
}

// Dense indices of the ids that occur, in sorted order (TrackEval relabels ids the same way).
std::map<std::string, int> indexIds(const std::vector<MotFrame>& frames, bool gt) {
  std::set<std::string> ids;
  for (const auto& f : frames) {
    for (const auto& id : gt ? f.gt_ids : f.tracker_ids) ids.insert(id);
  }
  std::map<std::string, int> index;
  for (const auto& id : ids) index.emplace(id, static_cast<int>(index.size()));
  return index;
}

void checkMotFrames(const std::vector<MotFrame>& frames) {
  for (std::size_t t = 0; t < frames.size(); ++t) {
    const auto& f = frames[t];
    const std::string at = "frame " + std::to_string(t);
    for (const auto* ids : {&f.gt_ids, &f.tracker_ids}) {
      std::set<std::string> seen(ids->begin(), ids->end());
      if (seen.size() != ids->size()) throw InputError(at + ": an id occurs twice");
    }
    if (f.similarity.size() != f.gt_ids.size()) {
      throw InputError(at + ": similarity has " + std::to_string(f.similarity.size()) +
                       " rows, expected one per ground-truth id (" +
                       std::to_string(f.gt_ids.size()) + ")");
    }
    for (const auto& row : f.similarity) {
      if (row.size() != f.tracker_ids.size()) {
        throw InputError(at + ": similarity row has " + std::to_string(row.size()) +
                         " columns, expected one per tracker id (" +
                         std::to_string(f.tracker_ids.size()) + ")");
      }
      for (double s : row) requireFraction(s, at + ": similarity");
    }
  }
}

// Rows of `cost` matched to columns by minCostAssignment, as (row, col) pairs in row order.
std::vector<std::pair<int, int>> assign(const std::vector<std::vector<double>>& cost) {
  const auto a = minCostAssignment(cost);
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t r = 0; r < a.size(); ++r) {
    if (a[r] >= 0) pairs.emplace_back(static_cast<int>(r), a[r]);
  }
  return pairs;
}

ClearMotScore clearMotImpl(const std::vector<MotFrame>& frames, double threshold,
                           std::map<std::string, std::size_t>* gt_switches) {
  checkMotFrames(frames);
  const auto gt_index = indexIds(frames, true);
  const auto tr_index = indexIds(frames, false);
  const std::size_t n_gt = gt_index.size();
  ClearMotScore res;
  double motp_sum = 0.0;
  std::vector<int> prev_tracker(n_gt, -1), prev_timestep_tracker(n_gt, -1);
  std::vector<std::size_t> gt_count(n_gt, 0), matched_count(n_gt, 0), frag_count(n_gt, 0),
      switches(n_gt, 0);
  for (const auto& f : frames) {
    std::vector<int> g, tr;
    for (const auto& id : f.gt_ids) g.push_back(gt_index.at(id));
    for (const auto& id : f.tracker_ids) tr.push_back(tr_index.at(id));
    if (g.empty()) {
      res.fp += tr.size();
      continue;
    }
    if (tr.empty()) {
      res.fn += g.size();
      for (int i : g) ++gt_count[i];
      continue;
    }
    // Keep last frame's matches first (1000 outweighs any IoU sum), then maximise the IoU.
    std::vector<std::vector<double>> cost(g.size(), std::vector<double>(tr.size()));
    std::vector<std::vector<double>> score(g.size(), std::vector<double>(tr.size()));
    for (std::size_t i = 0; i < g.size(); ++i) {
      for (std::size_t j = 0; j < tr.size(); ++j) {
        const double sim = f.similarity[i][j];
        double s = (prev_timestep_tracker[g[i]] == tr[j] ? 1000.0 : 0.0) + sim;
        if (sim < threshold - kEps) s = 0.0;
        score[i][j] = s;
        cost[i][j] = -s;
      }
    }
    std::vector<std::pair<int, int>> matches;
    for (const auto& [i, j] : assign(cost)) {
      if (score[i][j] > 0.0 + kEps) matches.emplace_back(i, j);
    }
    for (const auto& [i, j] : matches) {
      const int prev = prev_tracker[g[i]];
      if (prev >= 0 && prev != tr[j]) {
        ++res.id_switches;
        ++switches[g[i]];
      }
    }
    for (int i : g) ++gt_count[i];
    std::vector<bool> not_previously(n_gt);
    for (std::size_t k = 0; k < n_gt; ++k) not_previously[k] = prev_timestep_tracker[k] < 0;
    for (const auto& [i, j] : matches) {
      ++matched_count[g[i]];
      prev_tracker[g[i]] = tr[j];
    }
    std::fill(prev_timestep_tracker.begin(), prev_timestep_tracker.end(), -1);
    for (const auto& [i, j] : matches) prev_timestep_tracker[g[i]] = tr[j];
    for (std::size_t k = 0; k < n_gt; ++k) {
      if (not_previously[k] && prev_timestep_tracker[k] >= 0) ++frag_count[k];
    }
    res.tp += matches.size();
    res.fn += g.size() - matches.size();
    res.fp += tr.size() - matches.size();
    for (const auto& [i, j] : matches) motp_sum += f.similarity[i][j];
  }
  for (std::size_t k = 0; k < n_gt; ++k) {
    if (gt_count[k] == 0) continue;
    const double ratio = static_cast<double>(matched_count[k]) / gt_count[k];
    if (ratio > 0.8) {
      ++res.mostly_tracked;
    } else if (ratio >= 0.2) {
      ++res.partly_tracked;
    }
    if (frag_count[k] > 0) res.fragmentations += frag_count[k] - 1;
  }
  res.mostly_lost = n_gt - res.mostly_tracked - res.partly_tracked;
  res.mota = (static_cast<double>(res.tp) - static_cast<double>(res.fp) -
              static_cast<double>(res.id_switches)) /
             std::max(1.0, static_cast<double>(res.tp + res.fn));
  res.motp = motp_sum / std::max(1.0, static_cast<double>(res.tp));
  if (gt_switches) {
    for (const auto& [id, k] : gt_index) (*gt_switches)[id] = switches[k];
  }
  return res;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

double boxIou(const PixelBox& a, const PixelBox& b) {
  const double iw = std::min(a.x + a.w, b.x + b.w) - std::max(a.x, b.x);
  const double ih = std::min(a.y + a.h, b.y + b.h) - std::max(a.y, b.y);
  const double inter = std::max(iw, 0.0) * std::max(ih, 0.0);
  const double uni = a.area() + b.area() - inter;
  return uni > 0.0 ? inter / uni : 0.0;
}

double centreError(const PixelBox& a, const PixelBox& b) {
  return std::hypot(a.x + 0.5 * a.w - (b.x + 0.5 * b.w), a.y + 0.5 * a.h - (b.y + 0.5 * b.h));
}

void TrackingSettings::validate() const {
  auto fraction = [](double v, const char* field) {
    if (!(v >= 0.0 && v <= 1.0)) {
      throw scenario::ConfigError(std::string("tracking.") + field +
                                  ": expected a number in [0, 1], got " + num(v));
    }
  };
  auto positive = [](double v, const char* field) {
    if (!(v > 0.0 && std::isfinite(v))) {
      throw scenario::ConfigError(std::string("tracking.") + field +
                                  ": expected a finite number > 0, got " + num(v));
    }
  };
  fraction(min_visible_fraction, "min_visible_fraction");
  fraction(mot_min_visible_fraction, "mot_min_visible_fraction");
  if (!(min_box_area >= 0.0 && std::isfinite(min_box_area))) {
    throw scenario::ConfigError("tracking.min_box_area: expected a finite number >= 0, got " +
                                num(min_box_area));
  }
  positive(precision_threshold, "precision_threshold");
  positive(clear_threshold, "clear_threshold");
  fraction(clear_threshold, "clear_threshold");
}

OcclusionLevel occlusionLevel(double occlusion) {
  if (occlusion <= 0.0) return OcclusionLevel::kNone;
  if (occlusion <= 0.5) return OcclusionLevel::kPartial;
  if (occlusion < 1.0) return OcclusionLevel::kHeavy;
  return OcclusionLevel::kFull;
}

const char* occlusionLevelName(OcclusionLevel level) {
  switch (level) {
    case OcclusionLevel::kNone:
      return "none";
    case OcclusionLevel::kPartial:
      return "partial";
    case OcclusionLevel::kHeavy:
      return "heavy";
    case OcclusionLevel::kFull:
      return "full";
  }
  return "none";
}

std::vector<int> minCostAssignment(const std::vector<std::vector<double>>& cost) {
  const std::size_t rows = cost.size();
  if (rows == 0) return {};
  const std::size_t cols = cost[0].size();
  for (const auto& r : cost) {
    if (r.size() != cols) throw InputError("minCostAssignment: rows of different lengths");
    for (double c : r) {
      if (!std::isfinite(c)) throw InputError("minCostAssignment: a cost is not finite");
    }
  }
  if (cols == 0) return std::vector<int>(rows, -1);
  // The shortest augmenting path method wants rows <= cols: transpose otherwise.
  const bool transposed = rows > cols;
  const std::size_t n = transposed ? cols : rows, m = transposed ? rows : cols;
  auto a = [&](std::size_t i, std::size_t j) {
    return transposed ? cost[j - 1][i - 1] : cost[i - 1][j - 1];
  };
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0);
  std::vector<std::size_t> p(m + 1, 0), way(m + 1, 0);
  for (std::size_t i = 1; i <= n; ++i) {
    p[0] = i;
    std::size_t j0 = 0;
    std::vector<double> minv(m + 1, kInf);
    std::vector<bool> used(m + 1, false);
    do {
      used[j0] = true;
      const std::size_t i0 = p[j0];
      double delta = kInf;
      std::size_t j1 = 0;
      for (std::size_t j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const double cur = a(i0, j) - u[i0] - v[j];
        if (cur < minv[j]) {
          minv[j] = cur;
          way[j] = j0;
        }
        if (minv[j] < delta) {
          delta = minv[j];
          j1 = j;
        }
      }
      for (std::size_t j = 0; j <= m; ++j) {
        if (used[j]) {
          u[p[j]] += delta;
          v[j] -= delta;
        } else {
          minv[j] -= delta;
        }
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {
      const std::size_t j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  std::vector<int> result(rows, -1);
  for (std::size_t j = 1; j <= m; ++j) {
    if (p[j] == 0) continue;
    if (transposed) {
      result[j - 1] = static_cast<int>(p[j] - 1);
    } else {
      result[p[j] - 1] = static_cast<int>(j - 1);
    }
  }
  return result;
}

ClearMotScore clearMot(const std::vector<MotFrame>& frames, double threshold) {
  return clearMotImpl(frames, threshold, nullptr);
}

IdentityScore identityScore(const std::vector<MotFrame>& frames, double threshold) {
  checkMotFrames(frames);
  const auto gt_index = indexIds(frames, true);
  const auto tr_index = indexIds(frames, false);
  const std::size_t ng = gt_index.size(), nt = tr_index.size();
  std::vector<std::vector<double>> potential(ng, std::vector<double>(nt, 0.0));
  std::vector<double> gt_count(ng, 0.0), tr_count(nt, 0.0);
  for (const auto& f : frames) {
    for (std::size_t i = 0; i < f.gt_ids.size(); ++i) {
      for (std::size_t j = 0; j < f.tracker_ids.size(); ++j) {
        if (f.similarity[i][j] >= threshold) {
          potential[gt_index.at(f.gt_ids[i])][tr_index.at(f.tracker_ids[j])] += 1.0;
        }
      }
    }
    for (const auto& id : f.gt_ids) gt_count[gt_index.at(id)] += 1.0;
    for (const auto& id : f.tracker_ids) tr_count[tr_index.at(id)] += 1.0;
  }
  // TrackEval's square problem: gt rows and dummy rows, tracker columns and dummy columns.
  const std::size_t n = ng + nt;
  std::vector<std::vector<double>> fp(n, std::vector<double>(n, 0.0)), fn = fp;
  for (std::size_t r = ng; r < n; ++r) {
    for (std::size_t c = 0; c < nt; ++c) fp[r][c] = 1e10;
  }
  for (std::size_t r = 0; r < ng; ++r) {
    for (std::size_t c = nt; c < n; ++c) fn[r][c] = 1e10;
  }
  for (std::size_t g = 0; g < ng; ++g) {
    for (std::size_t c = 0; c < nt; ++c) fn[g][c] = gt_count[g];
    fn[g][nt + g] = gt_count[g];
  }
  for (std::size_t t = 0; t < nt; ++t) {
    for (std::size_t r = 0; r < ng; ++r) fp[r][t] = tr_count[t];
    fp[t + ng][t] = tr_count[t];
  }
  for (std::size_t g = 0; g < ng; ++g) {
    for (std::size_t t = 0; t < nt; ++t) {
      fn[g][t] -= potential[g][t];
      fp[g][t] -= potential[g][t];
    }
  }
  std::vector<std::vector<double>> cost(n, std::vector<double>(n));
  for (std::size_t r = 0; r < n; ++r) {
    for (std::size_t c = 0; c < n; ++c) cost[r][c] = fn[r][c] + fp[r][c];
  }
  double idfn = 0.0, idfp = 0.0;
  for (const auto& [r, c] : assign(cost)) {
    idfn += fn[r][c];
    idfp += fp[r][c];
  }
  double total_gt = 0.0;
  for (double c : gt_count) total_gt += c;
  IdentityScore res;
  res.idfn = static_cast<std::size_t>(idfn);
  res.idfp = static_cast<std::size_t>(idfp);
  res.idtp = static_cast<std::size_t>(total_gt - idfn);
  const double tp = static_cast<double>(res.idtp);
  res.idr = tp / std::max(1.0, tp + res.idfn);
  res.idp = tp / std::max(1.0, tp + res.idfp);
  res.idf1 = tp / std::max(1.0, tp + 0.5 * res.idfp + 0.5 * res.idfn);
  return res;
}

HotaScore hotaScore(const std::vector<MotFrame>& frames) {
  checkMotFrames(frames);
  HotaScore res;
  constexpr std::size_t kA = HotaScore::kAlphas;
  for (std::size_t a = 0; a < kA; ++a) res.alpha[a] = 0.05 + a * 0.05;  // numpy's arange
  std::array<double, kA> tp{}, fn{}, fp{}, loc{};
  std::size_t gt_dets = 0, tr_dets = 0;
  for (const auto& f : frames) {
    gt_dets += f.gt_ids.size();
    tr_dets += f.tracker_ids.size();
  }
  auto finish = [&]() {
    for (std::size_t a = 0; a < kA; ++a) {
      res.det_re[a] = tp[a] / std::max(1.0, tp[a] + fn[a]);
      res.det_pr[a] = tp[a] / std::max(1.0, tp[a] + fp[a]);
      res.det_a[a] = tp[a] / std::max(1.0, tp[a] + fn[a] + fp[a]);
      res.hota[a] = std::sqrt(res.det_a[a] * res.ass_a[a]);
    }
    auto mean = [](const std::array<double, kA>& x) {
      double s = 0.0;
      for (double v : x) s += v;
      return s / HotaScore::kAlphas;
    };
    res.mean_hota = mean(res.hota);
    res.mean_det_a = mean(res.det_a);
    res.mean_ass_a = mean(res.ass_a);
    res.mean_det_re = mean(res.det_re);
    res.mean_det_pr = mean(res.det_pr);
    res.mean_ass_re = mean(res.ass_re);
    res.mean_ass_pr = mean(res.ass_pr);
    res.mean_loc_a = mean(res.loc_a);
    return res;
  };
  if (tr_dets == 0 || gt_dets == 0) {
    for (std::size_t a = 0; a < kA; ++a) {
      fn[a] = static_cast<double>(tr_dets == 0 ? gt_dets : 0);
      fp[a] = static_cast<double>(tr_dets == 0 ? 0 : tr_dets);
      res.loc_a[a] = 1.0;
    }
    return finish();
  }
  const auto gt_index = indexIds(frames, true);
  const auto tr_index = indexIds(frames, false);
  const std::size_t ng = gt_index.size(), nt = tr_index.size();
  using Matrix = std::vector<std::vector<double>>;
  Matrix potential(ng, std::vector<double>(nt, 0.0));
  std::vector<double> gt_count(ng, 0.0), tr_count(nt, 0.0);
  std::vector<std::vector<int>> gi(frames.size()), ti(frames.size());
  for (std::size_t t = 0; t < frames.size(); ++t) {
    const auto& f = frames[t];
    for (const auto& id : f.gt_ids) gi[t].push_back(gt_index.at(id));
    for (const auto& id : f.tracker_ids) ti[t].push_back(tr_index.at(id));
    const std::size_t r = gi[t].size(), c = ti[t].size();
    std::vector<double> row_sum(r, 0.0), col_sum(c, 0.0);
    for (std::size_t i = 0; i < r; ++i) {
      for (std::size_t j = 0; j < c; ++j) {
        row_sum[i] += f.similarity[i][j];
        col_sum[j] += f.similarity[i][j];
      }
    }
    for (std::size_t i = 0; i < r; ++i) {
      for (std::size_t j = 0; j < c; ++j) {
        const double denom = col_sum[j] + row_sum[i] - f.similarity[i][j];
        if (denom > 0.0 + kEps) potential[gi[t][i]][ti[t][j]] += f.similarity[i][j] / denom;
      }
    }
    for (int g : gi[t]) gt_count[g] += 1.0;
    for (int k : ti[t]) tr_count[k] += 1.0;
  }
  Matrix global(ng, std::vector<double>(nt));
  for (std::size_t g = 0; g < ng; ++g) {
    for (std::size_t k = 0; k < nt; ++k) {
      global[g][k] = potential[g][k] / (gt_count[g] + tr_count[k] - potential[g][k]);
    }
  }
  std::vector<Matrix> matches(kA, Matrix(ng, std::vector<double>(nt, 0.0)));
  for (std::size_t t = 0; t < frames.size(); ++t) {
    const auto& f = frames[t];
    if (gi[t].empty()) {
      for (std::size_t a = 0; a < kA; ++a) fp[a] += ti[t].size();
      continue;
    }
    if (ti[t].empty()) {
      for (std::size_t a = 0; a < kA; ++a) fn[a] += gi[t].size();
      continue;
    }
    Matrix cost(gi[t].size(), std::vector<double>(ti[t].size()));
    for (std::size_t i = 0; i < gi[t].size(); ++i) {
      for (std::size_t j = 0; j < ti[t].size(); ++j) {
        cost[i][j] = -global[gi[t][i]][ti[t][j]] * f.similarity[i][j];
      }
    }
    const auto pairs = assign(cost);
    for (std::size_t a = 0; a < kA; ++a) {
      std::size_t n_match = 0;
      for (const auto& [i, j] : pairs) {
        const double sim = f.similarity[i][j];
        if (!(sim >= res.alpha[a] - kEps)) continue;
        ++n_match;
        loc[a] += sim;
        matches[a][gi[t][i]][ti[t][j]] += 1.0;
      }
      tp[a] += n_match;
      fn[a] += gi[t].size() - n_match;
      fp[a] += ti[t].size() - n_match;
    }
  }
  for (std::size_t a = 0; a < kA; ++a) {
    double ass_a = 0.0, ass_re = 0.0, ass_pr = 0.0;
    for (std::size_t g = 0; g < ng; ++g) {
      for (std::size_t k = 0; k < nt; ++k) {
        const double m = matches[a][g][k];
        ass_a += m * (m / std::max(1.0, gt_count[g] + tr_count[k] - m));
        ass_re += m * (m / std::max(1.0, gt_count[g]));
        ass_pr += m * (m / std::max(1.0, tr_count[k]));
      }
    }
    res.ass_a[a] = ass_a / std::max(1.0, tp[a]);
    res.ass_re[a] = ass_re / std::max(1.0, tp[a]);
    res.ass_pr[a] = ass_pr / std::max(1.0, tp[a]);
    res.loc_a[a] = std::max(1e-10, loc[a]) / std::max(1e-10, tp[a]);
  }
  return finish();
}

std::vector<MotFrame> motFrames(const std::vector<TrackingFrame>& frames,
                                const TrackingSettings& settings) {
  std::vector<MotFrame> out;
  out.reserve(frames.size());
  for (const auto& f : frames) {
    MotFrame m;
    std::vector<const PixelBox*> gt_boxes;
    for (const auto& g : f.targets) {
      if (g.visible_fraction < settings.mot_min_visible_fraction) continue;
      m.gt_ids.push_back(g.id);
      gt_boxes.push_back(&g.box);
    }
    for (const auto& r : f.tracks) m.tracker_ids.push_back(r.id);
    for (const auto* b : gt_boxes) {
      std::vector<double> row;
      for (const auto& r : f.tracks) row.push_back(boxIou(*b, r.box));
      m.similarity.push_back(std::move(row));
    }
    out.push_back(std::move(m));
  }
  return out;
}

TrackingScore scoreTracking(const std::vector<TrackingFrame>& frames,
                            const std::vector<std::string>& target_ids,
                            const TrackingSettings& settings) {
  settings.validate();
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const auto& f = frames[k];
    const std::string at = "frame " + std::to_string(k);
    if (!std::isfinite(f.t)) throw InputError(at + ": t is not finite");
    if (k > 0 && !(f.t > frames[k - 1].t)) {
      throw InputError(at + ": t = " + num(f.t) + " does not come after the previous frame's " +
                       num(frames[k - 1].t));
    }
    std::set<std::string> ids;
    for (const auto& g : f.targets) {
      if (!ids.insert(g.id).second) throw InputError(at + ": target " + g.id + " occurs twice");
      requireBox(g.box, at + ": target " + g.id + " box");
      requireFraction(g.visible_fraction, at + ": target " + g.id + " visible_fraction");
      requireFraction(g.occlusion, at + ": target " + g.id + " occlusion");
    }
    ids.clear();
    for (const auto& r : f.tracks) {
      if (!ids.insert(r.id).second) throw InputError(at + ": track " + r.id + " occurs twice");
      requireBox(r.box, at + ": track " + r.id + " box");
    }
  }
  TrackingScore score;
  const auto mot = motFrames(frames, settings);
  std::map<std::string, std::size_t> switches;
  score.clear = clearMotImpl(mot, settings.clear_threshold, &switches);
  score.identity = identityScore(mot, settings.clear_threshold);
  score.hota = hotaScore(mot);
  for (const auto& id : target_ids) {
    TargetTrackingScore s;
    s.id = id;
    s.frames = frames.size();
    std::array<std::size_t, kOcclusionLevels> tracked_at{}, held_at{};
    std::size_t within = 0;
    std::array<std::size_t, 21> above{};
    bool tracking = false, in_break = false;
    double lost_at = 0.0;
    std::vector<double> reacquire;
    for (const auto& f : frames) {
      const TargetTruth* truth = nullptr;
      for (const auto& g : f.targets) {
        if (g.id == id) truth = &g;
      }
      const ReportedTrack* track = nullptr;
      for (const auto& r : f.tracks) {
        if (r.id == id) track = &r;
      }
      const bool tracked = truth && truth->visible_fraction >= settings.min_visible_fraction &&
                           truth->box.area() >= settings.min_box_area;
      if (truth) {
        ++s.in_view_frames;
        const auto level = static_cast<std::size_t>(occlusionLevel(truth->occlusion));
        ++s.by_occlusion[level].frames;
        if (tracked) ++tracked_at[level];
        if (track && centreError(truth->box, track->box) <= settings.precision_threshold) {
          ++held_at[level];
        }
        if (truth->occlusion < 1.0) {
          ++s.scored_frames;
          const double err = track ? centreError(truth->box, track->box) : kInf;
          const double iou = track ? boxIou(truth->box, track->box) : 0.0;
          if (err <= settings.precision_threshold) ++within;
          for (std::size_t i = 0; i < above.size(); ++i) {
            if (iou > i / 20.0) ++above[i];
          }
        }
      }
      if (tracked) ++s.tracked_frames;
      if (tracking && !tracked) {
        ++s.breaks;
        in_break = true;
        lost_at = f.t;
      } else if (in_break && tracked) {
        reacquire.push_back(f.t - lost_at);
        in_break = false;
      }
      tracking = tracked;
    }
    if (in_break) s.open_break_s = frames.back().t - lost_at;
    s.reacquired = reacquire.size();
    s.reacquire_median_s = median(reacquire);
    s.reacquire_max_s =
        reacquire.empty() ? 0.0 : *std::max_element(reacquire.begin(), reacquire.end());
    s.tracked_fraction =
        frames.empty() ? 0.0 : static_cast<double>(s.tracked_frames) / frames.size();
    for (std::size_t l = 0; l < kOcclusionLevels; ++l) {
      auto& lv = s.by_occlusion[l];
      if (lv.frames == 0) continue;
      lv.tracked_fraction = static_cast<double>(tracked_at[l]) / lv.frames;
      lv.held_fraction = static_cast<double>(held_at[l]) / lv.frames;
    }
    if (s.scored_frames > 0) {
      s.precision = static_cast<double>(within) / s.scored_frames;
      double sum = 0.0;
      for (std::size_t c : above) sum += static_cast<double>(c) / s.scored_frames;
      s.success = sum / above.size();
    }
    const auto it = switches.find(id);
    s.id_switches = it == switches.end() ? 0 : it->second;
    score.targets.push_back(std::move(s));
  }
  return score;
}

}  // namespace hameritt::adk

namespace hameritt::adk {

TrackingRecorder::TrackingRecorder(std::vector<std::string> target_ids, TrackingSettings settings)
    : target_ids_(std::move(target_ids)), settings_(settings) {
  settings_.validate();
}

void TrackingRecorder::addFrame(double t, std::vector<TargetTruth> targets) {
  if (!std::isfinite(t)) throw InputError("tracking frame: t is not finite");
  if (!frames_.empty() && !(t > frames_.back().t)) {
    frames_.clear();
    pending_.clear();
    have_report_ = false;
  }
  TrackingFrame f;
  f.t = t;
  f.targets = std::move(targets);
  frames_.push_back(std::move(f));
  // The reports that came before this frame: matched now, or unmatched if it passed them.
  while (!pending_.empty() && pending_.front().first <= t + 1e-3) {
    if (std::fabs(pending_.front().first - t) <= 1e-3) {
      apply(&frames_.back(), pending_.front().second);
    } else {
      ++errors_.unmatched_stamp;
    }
    pending_.pop_front();
  }
}

void TrackingRecorder::addReport(double stamp, const std::vector<ReportedTrack>& tracks) {
  ++reports_;
  if (!std::isfinite(stamp) || (have_report_ && !(stamp > last_report_))) {
    ++errors_.out_of_order;
    return;
  }
  have_report_ = true;
  last_report_ = stamp;
  // Frames arrive in time order: search from the newest.
  TrackingFrame* frame = nullptr;
  for (auto it = frames_.rbegin(); it != frames_.rend(); ++it) {
    if (std::fabs(it->t - stamp) <= 1e-3) {
      frame = &*it;
      break;
    }
    if (it->t < stamp - 1e-3) break;
  }
  if (!frame && (frames_.empty() || stamp > frames_.back().t + 1e-3)) {
    pending_.emplace_back(stamp, tracks);  // ahead of its frame: it waits
    if (pending_.size() > kMaxPending) {
      pending_.pop_front();
      ++errors_.unmatched_stamp;
    }
    return;
  }
  if (!frame) {
    ++errors_.unmatched_stamp;
    return;
  }
  apply(frame, tracks);
}

void TrackingRecorder::apply(TrackingFrame* frame, const std::vector<ReportedTrack>& tracks) {
  frame->tracks.clear();
  std::set<std::string> seen;
  for (const auto& r : tracks) {
    if (std::find(target_ids_.begin(), target_ids_.end(), r.id) == target_ids_.end()) {
      ++errors_.unknown_id;
      continue;
    }
    const PixelBox& b = r.box;
    if (!std::isfinite(b.x) || !std::isfinite(b.y) || !std::isfinite(b.w) || !std::isfinite(b.h) ||
        b.w < 0.0 || b.h < 0.0) {
      ++errors_.bad_box;
      continue;
    }
    if (!seen.insert(r.id).second) {
      ++errors_.duplicate_id;
      continue;
    }
    frame->tracks.push_back(r);
  }
}

TrackingScore TrackingRecorder::score() const {
  return scoreTracking(frames_, target_ids_, settings_);
}

}  // namespace hameritt::adk
