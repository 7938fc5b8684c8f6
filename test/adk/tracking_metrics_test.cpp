#include "hameritt/adk/tracking_metrics.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "hameritt/scenario/error.h"

namespace hameritt::adk {
namespace {

TargetTruth truth(const std::string& id, PixelBox b, double visible, double occlusion) {
  return TargetTruth{id, b, visible, occlusion};
}

TEST(MinCostAssignment, FindsTheOptimumOfSquareAndRectangularMatrices) {
  // Greedy takes (0,0) = 1 and then (1,1) = 100; the optimum is 2 + 3.
  const std::vector<std::vector<double>> c = {{1, 2}, {3, 100}};
  EXPECT_EQ(minCostAssignment(c), (std::vector<int>{1, 0}));
  // More rows than columns: the row left out gets -1.
  const std::vector<std::vector<double>> tall = {{5}, {1}, {3}};
  EXPECT_EQ(minCostAssignment(tall), (std::vector<int>{-1, 0, -1}));
  const std::vector<std::vector<double>> wide = {{4, 1, 3}, {2, 0, 5}};
  EXPECT_EQ(minCostAssignment(wide), (std::vector<int>{1, 0}));  // 1 + 2 < 4 + 0
  EXPECT_TRUE(minCostAssignment({}).empty());
  EXPECT_THROW(minCostAssignment({{1, NAN}}), InputError);
  // Against brute force over every permutation of random 5x5 matrices.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<std::vector<double>> m(5, std::vector<double>(5));
    for (auto& r : m) {
      for (auto& x : r) x = u(rng);
    }
    std::vector<int> perm = {0, 1, 2, 3, 4};
    double best = 1e300;
    do {
      double s = 0;
      for (int i = 0; i < 5; ++i) s += m[i][perm[i]];
      best = std::min(best, s);
    } while (std::next_permutation(perm.begin(), perm.end()));
    const auto a = minCostAssignment(m);
    double s = 0;
    for (int i = 0; i < 5; ++i) s += m[i][a[i]];
    EXPECT_NEAR(s, best, 1e-12);
  }
}

TEST(BoxScores, IouAndCentreError) {
  const PixelBox a{0, 0, 40, 40}, b{10, 0, 40, 40};
  EXPECT_DOUBLE_EQ(boxIou(a, b), 1200.0 / 2000.0);
  EXPECT_DOUBLE_EQ(boxIou(a, a), 1.0);
  EXPECT_DOUBLE_EQ(boxIou(a, PixelBox{50, 50, 5, 5}), 0.0);
  EXPECT_DOUBLE_EQ(boxIou(PixelBox{0, 0, 0, 0}, PixelBox{0, 0, 0, 0}), 0.0);
  EXPECT_DOUBLE_EQ(centreError(a, b), 10.0);
  EXPECT_DOUBLE_EQ(centreError(a, PixelBox{3, 4, 40, 40}), 5.0);
}

TEST(OcclusionLevels, Bins) {
  EXPECT_EQ(occlusionLevel(0.0), OcclusionLevel::kNone);
  EXPECT_EQ(occlusionLevel(0.01), OcclusionLevel::kPartial);
  EXPECT_EQ(occlusionLevel(0.5), OcclusionLevel::kPartial);
  EXPECT_EQ(occlusionLevel(0.51), OcclusionLevel::kHeavy);
  EXPECT_EQ(occlusionLevel(0.99), OcclusionLevel::kHeavy);
  EXPECT_EQ(occlusionLevel(1.0), OcclusionLevel::kFull);
  EXPECT_STREQ(occlusionLevelName(OcclusionLevel::kHeavy), "heavy");
}

// Six frames worked by hand (see the comments): tracked test, occlusion levels, UAV123
// precision and success, breaks and reacquisition.
std::vector<TrackingFrame> handSequence() {
  const PixelBox full{0, 0, 40, 40};
  std::vector<TrackingFrame> f(6);
  for (int i = 0; i < 6; ++i) f[i].t = i;
  // 0: fully visible, box exact: tracked, error 0, IoU 1.
  f[0].targets = {truth("car", full, 1.0, 0.0)};
  f[0].tracks = {{"car", full}};
  // 1: 60 % occluded (heavy): not tracked, a break starts; the box is 30 px off, IoU 1/7.
  f[1].targets = {truth("car", full, 0.4, 0.6)};
  f[1].tracks = {{"car", PixelBox{30, 0, 40, 40}}};
  // 2: fully occluded, no report: not scored by UAV123.
  f[2].targets = {truth("car", full, 0.0, 1.0)};
  // 3: 20 % occluded, box 10 px off (IoU 0.6): tracked again after 2 s.
  f[3].targets = {truth("car", full, 0.8, 0.2)};
  f[3].tracks = {{"car", PixelBox{10, 0, 40, 40}}};
  // 4: out of view: a second break starts.
  // 5: visible but 15 x 15 = 225 px < 400: not tracked; the break stays open for 1 s.
  f[5].targets = {truth("car", PixelBox{0, 0, 15, 15}, 1.0, 0.0)};
  f[5].tracks = {{"car", PixelBox{0, 0, 15, 15}}};
  return f;
}

TEST(ScoreTracking, HandWorkedSingleTarget) {
  const auto score = scoreTracking(handSequence(), {"car"});
  ASSERT_EQ(score.targets.size(), 1u);
  const auto& s = score.targets[0];
  EXPECT_EQ(s.frames, 6u);
  EXPECT_EQ(s.in_view_frames, 5u);
  EXPECT_EQ(s.tracked_frames, 2u);
  EXPECT_DOUBLE_EQ(s.tracked_fraction, 2.0 / 6.0);
  const auto& none = s.by_occlusion[0];
  EXPECT_EQ(none.frames, 2u);
  EXPECT_DOUBLE_EQ(none.tracked_fraction, 0.5);
  EXPECT_DOUBLE_EQ(none.held_fraction, 1.0);
  EXPECT_EQ(s.by_occlusion[1].frames, 1u);
  EXPECT_DOUBLE_EQ(s.by_occlusion[1].tracked_fraction, 1.0);
  EXPECT_DOUBLE_EQ(s.by_occlusion[1].held_fraction, 1.0);
  EXPECT_EQ(s.by_occlusion[2].frames, 1u);
  EXPECT_DOUBLE_EQ(s.by_occlusion[2].held_fraction, 0.0);
  EXPECT_EQ(s.by_occlusion[3].frames, 1u);
  EXPECT_DOUBLE_EQ(s.by_occlusion[3].tracked_fraction, 0.0);
  // Scored frames 0, 1, 3, 5: errors 0, 30, 10, 0 px.
  EXPECT_EQ(s.scored_frames, 4u);
  EXPECT_DOUBLE_EQ(s.precision, 0.75);
  // IoUs 1, 1/7, 0.6, 1 over thresholds k/20: above 0..0.10: 4 each (3 thresholds); 0.15..0.55:
  // 3 each (9); 0.60..0.95: 2 each (8); 1.0: none.
  EXPECT_NEAR(s.success, (3 * 4 + 9 * 3 + 8 * 2) / 4.0 / 21.0, 1e-12);
  EXPECT_EQ(s.breaks, 2u);
  EXPECT_EQ(s.reacquired, 1u);
  EXPECT_DOUBLE_EQ(s.reacquire_median_s, 2.0);
  EXPECT_DOUBLE_EQ(s.reacquire_max_s, 2.0);
  EXPECT_DOUBLE_EQ(s.open_break_s, 1.0);
  EXPECT_EQ(s.id_switches, 0u);
  // Negative control: stricter thresholds change the tracked test (frame 5 passes at 200 px,
  // frame 1 at 0.3 visible), and the scores move with them.
  TrackingSettings loose;
  loose.min_box_area = 200.0;
  loose.min_visible_fraction = 0.3;
  const auto l = scoreTracking(handSequence(), {"car"}, loose).targets[0];
  EXPECT_EQ(l.tracked_frames, 4u);
  EXPECT_EQ(l.breaks, 2u);
  EXPECT_DOUBLE_EQ(l.reacquire_median_s, 1.0);  // 2 -> 3 and 4 -> 5
  EXPECT_DOUBLE_EQ(l.reacquire_max_s, 1.0);
  EXPECT_DOUBLE_EQ(l.open_break_s, 0.0);
}

// MOT frames with given similarity matrices.
MotFrame mot(std::vector<std::string> g, std::vector<std::string> t,
             std::vector<std::vector<double>> s) {
  return MotFrame{std::move(g), std::move(t), std::move(s)};
}

TEST(TrackEvalMetrics, HandWorkedIdSwitch) {
  // One target over four frames, tracked by "a" for two frames and by "b" after.
  std::vector<MotFrame> f = {mot({"g"}, {"a"}, {{1.0}}), mot({"g"}, {"a"}, {{1.0}}),
                             mot({"g"}, {"b"}, {{1.0}}), mot({"g"}, {"b"}, {{1.0}})};
  const auto c = clearMot(f);
  EXPECT_EQ(c.tp, 4u);
  EXPECT_EQ(c.fp, 0u);
  EXPECT_EQ(c.fn, 0u);
  EXPECT_EQ(c.id_switches, 1u);
  EXPECT_DOUBLE_EQ(c.mota, 0.75);  // (4 - 0 - 1) / 4
  EXPECT_DOUBLE_EQ(c.motp, 1.0);
  EXPECT_EQ(c.mostly_tracked, 1u);
  EXPECT_EQ(c.fragmentations, 0u);
  const auto id = identityScore(f);
  EXPECT_EQ(id.idtp, 2u);  // g is a for two frames; b's two frames are false positives
  EXPECT_EQ(id.idfn, 2u);
  EXPECT_EQ(id.idfp, 2u);
  EXPECT_DOUBLE_EQ(id.idf1, 0.5);
  const auto h = hotaScore(f);
  // Every detection matches at every alpha (DetA 1); each of the 4 matches has Jaccard
  // association 2 / (4 + 2 - 2) = 0.5.
  EXPECT_DOUBLE_EQ(h.mean_det_a, 1.0);
  EXPECT_DOUBLE_EQ(h.mean_ass_a, 0.5);
  EXPECT_NEAR(h.mean_hota, std::sqrt(0.5), 1e-12);
  // IoU 0.62 everywhere and one tracker: a match for alphas 0.05..0.60 (12 of 19), HOTA 1 there.
  std::vector<MotFrame> g(3, mot({"g"}, {"a"}, {{0.62}}));
  const auto hg = hotaScore(g);
  EXPECT_NEAR(hg.mean_hota, 12.0 / 19.0, 1e-12);
  EXPECT_NEAR(hg.loc_a[0], 0.62, 1e-12);
  EXPECT_DOUBLE_EQ(hg.loc_a[18], 1.0);  // no match at alpha 0.95: TrackEval's 1e-10 / 1e-10
  // A frame with no detections of the tracker breaks CLEAR's match memory only through the FN.
  std::vector<MotFrame> gap = {mot({"g"}, {"a"}, {{0.9}}), mot({"g"}, {}, {{}}),
                               mot({"g"}, {"a"}, {{0.9}})};
  const auto cg = clearMot(gap);
  EXPECT_EQ(cg.fn, 1u);
  EXPECT_EQ(cg.fragmentations, 0u);  // TrackEval keeps the last match across an empty frame
  EXPECT_DOUBLE_EQ(cg.mota, 2.0 / 3.0);
  // Empty tracker output: HOTA 0, every detection a miss.
  EXPECT_DOUBLE_EQ(hotaScore({mot({"g"}, {}, {{}})}).mean_hota, 0.0);
  // Negative control: the same boxes without the switch score perfectly.
  std::vector<MotFrame> same(4, mot({"g"}, {"a"}, {{1.0}}));
  EXPECT_DOUBLE_EQ(clearMot(same).mota, 1.0);
  EXPECT_DOUBLE_EQ(identityScore(same).idf1, 1.0);
  EXPECT_DOUBLE_EQ(hotaScore(same).mean_hota, 1.0);
}

TEST(TrackEvalMetrics, ClearPrefersLastFramesMatch) {
  // Both trackers overlap g by more than 0.5 in frame 1; CLEAR keeps frame 0's "a" (no
  // switch) even though "b" has the higher IoU.
  std::vector<MotFrame> f = {mot({"g"}, {"a", "b"}, {{0.9, 0.1}}),
                             mot({"g"}, {"a", "b"}, {{0.6, 0.95}})};
  const auto c = clearMot(f);
  EXPECT_EQ(c.id_switches, 0u);
  EXPECT_NEAR(c.motp, (0.9 + 0.6) / 2, 1e-12);
}

TEST(TrackEvalMetrics, RejectsMalformedFrames) {
  EXPECT_THROW(clearMot({mot({"g"}, {"a"}, {})}), InputError);
  EXPECT_THROW(clearMot({mot({"g"}, {"a"}, {{1.5}})}), InputError);
  EXPECT_THROW(hotaScore({mot({"g", "g"}, {"a"}, {{1}, {1}})}), InputError);
  EXPECT_THROW(identityScore({mot({"g"}, {"a"}, {{NAN}})}), InputError);
}

TEST(ScoreTracking, RejectsMalformedInput) {
  auto f = handSequence();
  f[2].t = 1.0;
  EXPECT_THROW(scoreTracking(f, {"car"}), InputError);
  f = handSequence();
  f[0].tracks[0].box.w = NAN;
  try {
    scoreTracking(f, {"car"});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("frame 0: track car box"), std::string::npos) << e.what();
  }
  f = handSequence();
  f[0].tracks[0].box.h = -1;
  EXPECT_THROW(scoreTracking(f, {"car"}), InputError);
  f = handSequence();
  f[0].targets[0].visible_fraction = 1.2;
  EXPECT_THROW(scoreTracking(f, {"car"}), InputError);
  f = handSequence();
  f[0].tracks.push_back(f[0].tracks[0]);
  EXPECT_THROW(scoreTracking(f, {"car"}), InputError);
  TrackingSettings bad;
  bad.precision_threshold = 0;
  EXPECT_THROW(scoreTracking(handSequence(), {"car"}, bad), scenario::ConfigError);
}

// Random sequences: 1-4 targets moving close together, trackers that follow them with noise,
// drop out, swap ids and add false tracks.
std::vector<TrackingFrame> randomSequence(std::mt19937& rng, std::vector<std::string>* ids) {
  std::uniform_real_distribution<double> u(0, 1);
  const int n_targets = 1 + static_cast<int>(u(rng) * 4);
  const int n_frames = 20 + static_cast<int>(u(rng) * 40);
  ids->clear();
  std::vector<PixelBox> pos;
  std::vector<double> vx, vy;
  for (int k = 0; k < n_targets; ++k) {
    ids->push_back("t" + std::to_string(k));
    pos.push_back(PixelBox{u(rng) * 100, u(rng) * 100, 10 + u(rng) * 40, 10 + u(rng) * 40});
    vx.push_back(u(rng) * 6 - 3);
    vy.push_back(u(rng) * 6 - 3);
  }
  std::normal_distribution<double> noise(0, 4);
  std::vector<TrackingFrame> frames;
  double t = 0;
  int next_id = 100;
  std::vector<std::string> track_of(n_targets);
  for (int k = 0; k < n_targets; ++k)
    track_of[k] = u(rng) < 0.7 ? (*ids)[k] : "x" + std::to_string(k);
  for (int i = 0; i < n_frames; ++i) {
    TrackingFrame f;
    t += 0.05 + u(rng) * 0.2;
    f.t = t;
    for (int k = 0; k < n_targets; ++k) {
      pos[k].x += vx[k];
      pos[k].y += vy[k];
      if (u(rng) < 0.1) continue;  // out of view
      const double occ = u(rng) < 0.3 ? 0.0 : (u(rng) < 0.15 ? 1.0 : u(rng));
      const double vis = std::max(0.0, (1 - occ) * (u(rng) < 0.8 ? 1.0 : u(rng)));
      f.targets.push_back(truth((*ids)[k], pos[k], vis, occ));
      if (u(rng) < 0.15) continue;                                       // missed
      if (u(rng) < 0.05) track_of[k] = "n" + std::to_string(next_id++);  // new id
      if (u(rng) < 0.04 && n_targets > 1) {                              // swap with another target
        const int o = (k + 1) % n_targets;
        std::swap(track_of[k], track_of[o]);
      }
      PixelBox b{pos[k].x + noise(rng), pos[k].y + noise(rng), std::max(0.0, pos[k].w + noise(rng)),
                 std::max(0.0, pos[k].h + noise(rng))};
      bool dup = false;
      for (const auto& r : f.tracks) dup = dup || r.id == track_of[k];
      if (!dup) f.tracks.push_back({track_of[k], b});
    }
    if (u(rng) < 0.2) {  // a false track on a look-alike
      f.tracks.push_back(
          {"f" + std::to_string(next_id++ % 3), PixelBox{u(rng) * 120, u(rng) * 120, 20, 20}});
      for (std::size_t a = 0; a + 1 < f.tracks.size(); ++a) {
        if (f.tracks[a].id == f.tracks.back().id) {
          f.tracks.pop_back();
          break;
        }
      }
    }
    frames.push_back(std::move(f));
  }
  return frames;
}

nlohmann::json boxJson(const PixelBox& b) { return {b.x, b.y, b.w, b.h}; }

nlohmann::json sequenceJson(const std::vector<TrackingFrame>& frames,
                            const std::vector<std::string>& ids, const TrackingSettings& s) {
  nlohmann::json seq;
  seq["target_ids"] = ids;
  seq["settings"] = {{"min_visible_fraction", s.min_visible_fraction},
                     {"min_box_area", s.min_box_area},
                     {"precision_threshold", s.precision_threshold},
                     {"clear_threshold", s.clear_threshold},
                     {"mot_min_visible_fraction", s.mot_min_visible_fraction}};
  seq["frames"] = nlohmann::json::array();
  for (const auto& f : frames) {
    nlohmann::json jf;
    jf["t"] = f.t;
    jf["targets"] = nlohmann::json::array();
    for (const auto& g : f.targets) {
      jf["targets"].push_back({{"id", g.id},
                               {"box", boxJson(g.box)},
                               {"visible_fraction", g.visible_fraction},
                               {"occlusion", g.occlusion}});
    }
    jf["tracks"] = nlohmann::json::array();
    for (const auto& r : f.tracks) jf["tracks"].push_back({{"id", r.id}, {"box", boxJson(r.box)}});
    seq["frames"].push_back(jf);
  }
  return seq;
}

// Number of scores of `c` that differ from the reference `r` by more than 1e-9; each
// comparison is recorded in `compared`.
int differences(const TrackingScore& c, const nlohmann::json& r, int* compared) {
  int bad = 0;
  auto cmp = [&](double mine, const nlohmann::json& ref) {
    ++*compared;
    if (!(std::fabs(mine - ref.get<double>()) <= 1e-9)) ++bad;
  };
  const auto& cl = r["clear"];
  cmp(c.clear.mota, cl["MOTA"]);
  cmp(c.clear.motp, cl["MOTP"]);
  cmp(c.clear.tp, cl["CLR_TP"]);
  cmp(c.clear.fn, cl["CLR_FN"]);
  cmp(c.clear.fp, cl["CLR_FP"]);
  cmp(c.clear.id_switches, cl["IDSW"]);
  cmp(c.clear.mostly_tracked, cl["MT"]);
  cmp(c.clear.partly_tracked, cl["PT"]);
  cmp(c.clear.mostly_lost, cl["ML"]);
  cmp(c.clear.fragmentations, cl["Frag"]);
  const auto& id = r["identity"];
  cmp(c.identity.idf1, id["IDF1"]);
  cmp(c.identity.idr, id["IDR"]);
  cmp(c.identity.idp, id["IDP"]);
  cmp(c.identity.idtp, id["IDTP"]);
  const auto& h = r["hota"];
  cmp(c.hota.mean_hota, h["HOTA"]);
  cmp(c.hota.mean_det_a, h["DetA"]);
  cmp(c.hota.mean_ass_a, h["AssA"]);
  cmp(c.hota.mean_det_re, h["DetRe"]);
  cmp(c.hota.mean_det_pr, h["DetPr"]);
  cmp(c.hota.mean_ass_re, h["AssRe"]);
  cmp(c.hota.mean_ass_pr, h["AssPr"]);
  cmp(c.hota.mean_loc_a, h["LocA"]);
  for (const auto& t : c.targets) {
    const auto& rt = r["targets"][t.id];
    cmp(t.tracked_fraction, rt["tracked_fraction"]);
    cmp(t.precision, rt["precision"]);
    cmp(t.success, rt["success"]);
    cmp(t.breaks, rt["breaks"]);
    cmp(t.reacquired, rt["reacquired"]);
    cmp(t.reacquire_median_s, rt["reacquire_median_s"]);
    cmp(t.reacquire_max_s, rt["reacquire_max_s"]);
    cmp(t.open_break_s, rt["open_break_s"]);
    const auto sw = r["idsw_per_gt"].find(t.id);
    cmp(t.id_switches, sw == r["idsw_per_gt"].end() ? nlohmann::json(0) : *sw);
  }
  return bad;
}

// The C++ scores against the Python reference (TrackEval's formulas with numpy and scipy) on
// 60 random sequences, to 1e-9.
TEST(ScoreTracking, MatchesIndependentReferenceOnRandomSequences) {
  std::mt19937 rng(2024);
  std::vector<std::vector<TrackingFrame>> seqs;
  std::vector<std::vector<std::string>> ids;
  std::vector<TrackingSettings> settings;
  nlohmann::json in;
  in["sequences"] = nlohmann::json::array();
  for (int k = 0; k < 60; ++k) {
    std::vector<std::string> tid;
    seqs.push_back(randomSequence(rng, &tid));
    ids.push_back(tid);
    TrackingSettings s;
    if (k % 3 == 1) {  // other thresholds on a third of the sequences
      s.clear_threshold = 0.3;
      s.mot_min_visible_fraction = 0.25;
      s.precision_threshold = 8.0;
      s.min_box_area = 900.0;
    }
    settings.push_back(s);
    in["sequences"].push_back(sequenceJson(seqs.back(), tid, s));
  }
  const auto dir = std::filesystem::temp_directory_path() /
                   ("hameritt_tracking_ref_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "in.json") << in.dump();
  const std::string cmd = "/usr/bin/python3 test/adk/tracking_reference.py " +
                          (dir / "in.json").string() + " " + (dir / "out.json").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  nlohmann::json out;
  std::ifstream(dir / "out.json") >> out;
  std::filesystem::remove_all(dir);
  ASSERT_EQ(out["results"].size(), seqs.size());
  int compared = 0, bad = 0, mot_sequences = 0, switches = 0;
  for (std::size_t k = 0; k < seqs.size(); ++k) {
    const auto c = scoreTracking(seqs[k], ids[k], settings[k]);
    const int d = differences(c, out["results"][k], &compared);
    EXPECT_EQ(d, 0) << "sequence " << k;
    bad += d;
    mot_sequences += ids[k].size() > 1;
    switches += static_cast<int>(c.clear.id_switches);
  }
  EXPECT_EQ(bad, 0);
  std::printf("%d scores compared on %zu sequences (%d with several targets, %d id switches)\n",
              compared, seqs.size(), mot_sequences, switches);
  // The sequences exercise what they claim to: several targets, identity switches.
  EXPECT_GE(mot_sequences, 30);
  EXPECT_GE(switches, 100);
  EXPECT_GE(compared, 60 * 31);
  // Negative control: the comparison catches an implementation that is off. Scoring each
  // sequence with the reported boxes moved 3 px differs from the reference almost everywhere.
  int sequences_off = 0, dummy = 0;
  for (std::size_t k = 0; k < seqs.size(); ++k) {
    auto moved = seqs[k];
    for (auto& f : moved) {
      for (auto& r : f.tracks) r.box.x += 3.0;
    }
    sequences_off +=
        differences(scoreTracking(moved, ids[k], settings[k]), out["results"][k], &dummy) > 0;
  }
  std::printf("negative control: %d of %zu sequences differ with boxes moved 3 px\n", sequences_off,
              seqs.size());
  EXPECT_GE(sequences_off, 55);
}

TEST(TrackingRecorder, AReportBeforeItsFrameWaitsForIt) {
  // The client answers a frame before the ADK has it (two subscriptions, no order between them).
  const auto seq = handSequence();
  TrackingRecorder early({"car"}, {});
  for (const auto& f : seq) {
    early.addReport(f.t, f.tracks);
    EXPECT_EQ(early.pendingReports(), 1u);
    early.addFrame(f.t, f.targets);
    EXPECT_EQ(early.pendingReports(), 0u);
  }
  EXPECT_EQ(early.errors().total(), 0u);
  const auto batch = scoreTracking(seq, {"car"});
  EXPECT_DOUBLE_EQ(early.score().targets[0].precision, batch.targets[0].precision);
  EXPECT_DOUBLE_EQ(early.score().clear.mota, batch.clear.mota);
  // Control: a report for a frame that never comes is unmatched once a later frame passes it,
  // and a flood of them waits no longer than kMaxPending reports.
  TrackingRecorder missed({"car"}, {});
  missed.addFrame(1.0, {});
  missed.addReport(1.5, {});
  missed.addFrame(2.0, {});
  EXPECT_EQ(missed.errors().unmatched_stamp, 1u);
  EXPECT_EQ(missed.pendingReports(), 0u);
  for (std::size_t k = 0; k < TrackingRecorder::kMaxPending + 10; ++k) {
    missed.addReport(3.0 + static_cast<double>(k), {});
  }
  EXPECT_EQ(missed.pendingReports(), TrackingRecorder::kMaxPending);
  EXPECT_EQ(missed.errors().unmatched_stamp, 11u);
}

TEST(TrackingRecorder, ScoresLikeTheBatchAndCountsMalformedReports) {
  const auto seq = handSequence();
  TrackingRecorder clean({"car"}, {});
  TrackingRecorder noisy({"car"}, {});
  std::size_t bad_sent = 0;
  for (const auto& f : seq) {
    clean.addFrame(f.t, f.targets);
    noisy.addFrame(f.t, f.targets);
    if (!f.tracks.empty()) clean.addReport(f.t, f.tracks);
    // The noisy client sends the same tracks plus one malformed track of each kind...
    auto tracks = f.tracks;
    tracks.push_back({"car_unknown", PixelBox{0, 0, 10, 10}});
    tracks.push_back({"car", PixelBox{0, 0, NAN, 10}});
    tracks.push_back({"car", PixelBox{0, 0, 10, -1}});
    if (!f.tracks.empty()) tracks.push_back(f.tracks[0]);  // a repeated id
    bad_sent += 3 + !f.tracks.empty();
    noisy.addReport(f.t, tracks);
    // ...a report stamped between frames, and one re-sent after it (out of order).
    noisy.addReport(f.t + 0.5, f.tracks);
    noisy.addReport(f.t + 0.25, f.tracks);
  }
  EXPECT_EQ(clean.errors().total(), 0u);
  const auto& e = noisy.errors();
  EXPECT_EQ(e.unknown_id, 6u);
  EXPECT_EQ(e.bad_box, 12u);
  EXPECT_EQ(e.duplicate_id, 4u);  // the four frames with a box
  // Stamped between frames: unmatched once the next frame passes it; the last one still waits.
  EXPECT_EQ(e.unmatched_stamp, 5u);
  EXPECT_EQ(noisy.pendingReports(), 1u);
  EXPECT_EQ(e.out_of_order, 6u);
  EXPECT_EQ(e.unknown_id + e.bad_box + e.duplicate_id, bad_sent);
  EXPECT_EQ(noisy.reports(), 18u);
  EXPECT_EQ(noisy.frames(), 6u);
  // Dropped tracks cost nothing else: both score as the batch function does.
  const auto batch = scoreTracking(seq, {"car"});
  for (const auto* r : {&clean, &noisy}) {
    const auto s = r->score();
    EXPECT_DOUBLE_EQ(s.targets[0].precision, batch.targets[0].precision);
    EXPECT_DOUBLE_EQ(s.targets[0].success, batch.targets[0].success);
    EXPECT_DOUBLE_EQ(s.clear.mota, batch.clear.mota);
    EXPECT_DOUBLE_EQ(s.hota.mean_hota, batch.hota.mean_hota);
  }
  // Negative control: a client whose reports all miss their frames scores no precision.
  TrackingRecorder late({"car"}, {});
  for (const auto& f : seq) {
    late.addFrame(f.t, f.targets);
    late.addReport(f.t + 0.5, f.tracks);
  }
  EXPECT_EQ(late.errors().unmatched_stamp + late.pendingReports(), 6u);
  EXPECT_DOUBLE_EQ(late.score().targets[0].precision, 0.0);
  // A clock restart (simulator reset) starts a new recording.
  late.addFrame(0.0, {});
  EXPECT_EQ(late.frames(), 1u);
  EXPECT_THROW(late.addFrame(NAN, {}), InputError);
}

}  // namespace
}  // namespace hameritt::adk
