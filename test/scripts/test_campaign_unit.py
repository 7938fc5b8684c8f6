#!/usr/bin/python3
"""hameritt_campaign's functions (python unittest): config checks, the plan, ports, atomic
unit completion, stale work, the sbatch script, the summary and the manifest comparison; and,
with the built hameritt_generate, a generation-only campaign run in 3 shards and in 1 whose
merged scenarios are byte-identical and whose manifests are equal."""

import filecmp
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import unittest
from contextlib import redirect_stderr, redirect_stdout

SRC = os.environ.get("HAMERITT_SOURCE_DIR",
                     os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(SRC, "src", "tools"))
import hameritt_campaign as hc  # noqa: E402

BASE = """
name: unit
seed: 11
classes: all
count: 10
shards: 3
missions:
  count: 2
  modes: [maneuver_only, end_to_end]
  time_limit: 5
"""


def rd(path):
    with open(path) as f:
        return f.read()


def wr(path, text):
    with open(path, "w") as f:
        f.write(text)


def cfg_of(text=BASE):
    return hc.parse_config(text, "c.yaml")


class ConfigTest(unittest.TestCase):
    def test_defaults_and_normalization(self):
        c = cfg_of()
        self.assertEqual(c["classes"], ["area_search", "route_search", "pursuit"])
        self.assertEqual(c["generate"]["unit_size"], 4)  # ceil(10 / 3)
        self.assertEqual(c["missions"]["scenarios"], [0, 1])
        self.assertEqual(c["missions"]["cameras"], "all")
        self.assertTrue(c["missions"]["record"])
        self.assertEqual(c["slurm"]["time"], "01:00:00")

    def test_follow_class_is_accepted_but_not_part_of_all(self):
        c = cfg_of("seed: 1\ncount: 2\nclasses: [follow, pursuit]\n")
        self.assertEqual(c["classes"], ["follow", "pursuit"])
        self.assertEqual([hc.class_of(c, i) for i in range(3)], ["follow", "pursuit", "follow"])
        self.assertNotIn("follow", cfg_of("seed: 1\ncount: 2\nclasses: all\n")["classes"])

    def test_track_class_is_accepted_but_not_part_of_all(self):
        c = cfg_of("seed: 1\ncount: 2\nclasses: [track]\n")
        self.assertEqual(c["classes"], ["track"])
        self.assertNotIn("track", cfg_of("seed: 1\ncount: 2\nclasses: all\n")["classes"])

    def test_errors_name_the_file_and_the_field(self):
        cases = [
            ("seed: -1", "field 'seed'"),
            ("seed: 1\ncount: 3\nbogus: 1", "field 'bogus'"),
            ("seed: 1\ncount: 3\nclasses: [area_search, boats]", "field 'classes'"),
            ("seed: 1\ncount: 3\nmissions: {scenarios: [0, 3]}", "field 'missions.scenarios'"),
            ("seed: 1\ncount: 3\nmissions: {count: 4}", "field 'missions.count'"),
            ("seed: 1\ncount: 3\nmissions: {modes: [fly]}", "field 'missions.modes'"),
            ("seed: 1\ncount: 3\nmissions: {time_limit: .nan}", "field 'missions.time_limit'"),
            ("seed: 1\ncount: 3\nmissions: {record: 'yes'}", "field 'missions.record'"),
            ("seed: 1\ncount: 3\ngenerate: {unit_size: 0}", "field 'generate.unit_size'"),
            ("seed: 1\ncount: 3\nslurm: {time: 'soon'}", "field 'slurm.time'"),
            ("seed: 1\ncount: 3\nslurm: {extra: ['-x']}", "field 'slurm.extra'"),
            ("seed: 1\ncount: 0", "field 'count'"),
            ("count: 3", "field 'seed'"),
            ("name: 'a b'\nseed: 1\ncount: 3", "field 'name'"),
            ("[1, 2]", "(top level)"),
            ("seed: [", "not valid YAML"),
            ("seed: 1\ncount: 3\nworld: metropolis", "field 'world'"),
        ]
        for text, want in cases:
            with self.assertRaises(hc.CampaignError, msg=text) as e:
                hc.parse_config(text, "c.yaml")
            self.assertIn("c.yaml", str(e.exception))
            self.assertIn(want, str(e.exception), text)


class PlanTest(unittest.TestCase):
    def test_plan_is_deterministic_and_covers_every_index_once(self):
        c = cfg_of()
        p = hc.make_plan(c)
        self.assertEqual(json.dumps(p, sort_keys=True), json.dumps(hc.make_plan(cfg_of()),
                                                                   sort_keys=True))
        covered = []
        for u in p["units"]:
            self.assertTrue(0 <= u["shard"] < 3)
            if u["kind"] == "generate":
                covered += list(range(u["first"], u["first"] + u["count"]))
        self.assertEqual(covered, list(range(10)))
        missions = [u for u in p["units"] if u["kind"] == "mission"]
        self.assertEqual([u["id"] for u in missions],
                         ["mission-000000-maneuver_only", "mission-000000-end_to_end",
                          "mission-000001-maneuver_only", "mission-000001-end_to_end"])
        self.assertEqual([u["class"] for u in missions],
                         ["area_search", "area_search", "route_search", "route_search"])
        # The missions spread over the shards.
        self.assertEqual(sorted(u["shard"] for u in missions[:3]), [0, 1, 2])
        ids = [u["id"] for u in p["units"]]
        self.assertEqual(len(ids), len(set(ids)))

    def test_mission_units_do_not_depend_on_the_shard_count(self):
        one = hc.make_plan(cfg_of(BASE.replace("shards: 3", "shards: 1")))
        three = hc.make_plan(cfg_of())
        strip = lambda p: [dict((k, v) for k, v in u.items() if k != "shard")
                           for u in p["units"] if u["kind"] == "mission"]
        self.assertEqual(strip(one), strip(three))
        self.assertEqual({u["shard"] for u in one["units"]}, {0})


class PortTest(unittest.TestCase):
    def test_port_from_the_task_id_and_the_fallbacks(self):
        self.assertEqual(hc.pick_port(3, 2, lambda p: True), 20000 + 48 + 2)
        taken = {20050, 20051}
        self.assertEqual(hc.pick_port(3, 2, lambda p: p not in taken), 20052)
        p = hc.pick_port(3, 2, lambda p: p >= 44000)
        self.assertGreaterEqual(p, 44000)
        kernel = hc.pick_port(3, 2, lambda p: False)
        self.assertTrue(1024 < kernel < 65536)
        import socket
        s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        self.assertFalse(hc.port_is_free(s.getsockname()[1]))
        s.close()


class UnitFilesTest(unittest.TestCase):
    def setUp(self):
        self.d = tempfile.mkdtemp(prefix="campaign_unit_")
        os.makedirs(os.path.join(self.d, "units", ".work"))

    def tearDown(self):
        shutil.rmtree(self.d)

    def test_a_unit_appears_by_one_rename_and_only_once(self):
        final, work = hc.unit_paths(self.d, "gen-000000", "h@1")
        os.makedirs(work)
        wr(os.path.join(work, "x"), "first")
        self.assertTrue(hc.finish_unit(work, final, {"a": 1}))
        self.assertFalse(os.path.exists(work))
        self.assertEqual(json.loads(rd(os.path.join(final, "unit.json"))), {"a": 1})
        # A second run of the same unit finishing later keeps the first copy.
        _, work2 = hc.unit_paths(self.d, "gen-000000", "h@2")
        os.makedirs(work2)
        wr(os.path.join(work2, "x"), "second")
        self.assertFalse(hc.finish_unit(work2, final, {"a": 2}))
        self.assertFalse(os.path.exists(work2))
        self.assertEqual(rd(os.path.join(final, "x")), "first")

    def test_stale_work_of_dead_processes_is_removed(self):
        import socket
        host = socket.gethostname()
        dead = subprocess.Popen(["true"])
        dead.wait()
        work = os.path.join(self.d, "units", ".work")
        for name in ["u1@%s@%d" % (host, dead.pid), "u1@%s@%d" % (host, os.getppid()),
                     "u2@%s@%d" % (host, dead.pid), "u1@otherhost@%d" % dead.pid]:
            os.makedirs(os.path.join(work, name))
        removed = hc.clean_stale_work(self.d, {"u1"})
        self.assertEqual(removed, ["u1@%s@%d" % (host, dead.pid)])
        self.assertEqual(len(os.listdir(work)), 3)

    def test_sbatch_script(self):
        c = cfg_of(BASE + "slurm: {partition: gpu, time: '00:30:00', mem: 2G, "
                          "max_parallel: 2, extra: ['--qos=low']}\n")
        s = hc.sbatch_script(self.d, c, [0, 2])
        for want in ["#SBATCH --array=0,2%2", "#SBATCH --requeue", "#SBATCH --time=00:30:00",
                     "#SBATCH --mem=2G", "#SBATCH --partition=gpu", "#SBATCH --qos=low",
                     "#SBATCH --cpus-per-task=2",
                     "#SBATCH --output=%s/slurm/%%A_%%a.out" % self.d,
                     "run-shard %s --shard \"$SLURM_ARRAY_TASK_ID\"" % self.d]:
            self.assertIn(want, s)
        self.assertTrue(s.startswith("#!/bin/bash\n"))
        self.assertEqual(hc.array_spec([3, 0, 1, 2, 7, 9, 10]), "0-3,7,9-10")
        self.assertEqual(hc.array_spec([5]), "5")


class ProcessGroupTest(unittest.TestCase):
    def test_a_timeout_stops_the_whole_group(self):
        d = tempfile.mkdtemp(prefix="campaign_pg_")
        try:
            pidfile = os.path.join(d, "child")
            # A parent that ignores SIGINT and a child: both must be gone after the timeout.
            cmd = ["/bin/bash", "-c", "trap '' INT; sleep 60 & echo $! > %s; wait" % pidfile]
            with open(os.path.join(d, "log"), "wb") as out:
                rc = hc.run_process_group(cmd, out, dict(os.environ), 1.0, grace=1.0)
            self.assertIsNone(rc)
            child = int(rd(pidfile))
            for _ in range(50):  # its reaping by init may take a moment
                if not hc.pid_alive(child):
                    break
                time.sleep(0.1)
            self.assertFalse(hc.pid_alive(child), "the group's child outlived the timeout")
            with open(os.path.join(d, "log"), "wb") as out:
                self.assertEqual(hc.run_process_group(["/bin/sh", "-c", "exit 3"], out,
                                                      dict(os.environ), 10.0), 3)
        finally:
            shutil.rmtree(d)


def mission(cls, mode, outcome, ttd, koz, **kw):
    e = {"class": cls, "mode": mode, "outcome": outcome, "time_to_first_correct_detection": ttd,
         "koz_violation_count": koz, "bag_size": 10, "shard": 0, "host": "h", "job": "",
         "wall_time": 1.0, "finished": "t", "energy": 1.0, "path_length": 2.0, "coverage": 0.1,
         "end_time": 6.0}
    e.update(kw)
    return e


class SummaryAndCompareTest(unittest.TestCase):
    def test_summary_per_class_and_mode(self):
        ms = [mission("pursuit", "end_to_end", "success", 10.0, 0),
              mission("pursuit", "end_to_end", "timeout", None, 2),
              mission("pursuit", "end_to_end", "success", 20.0, 1),
              mission("area_search", "maneuver_only", "crash", None, 0)]
        s = hc.summarize(cfg_of(), ms)
        self.assertEqual(s["missions"], 4)
        self.assertEqual(s["outcomes"], {"success": 2, "timeout": 1, "crash": 1})
        self.assertEqual(s["success_rate"], 0.5)
        self.assertEqual(s["mean_time_to_detect"], 15.0)
        self.assertEqual(s["koz_violations"], 3)
        self.assertEqual(s["bag_bytes"], 40)
        g = {(x["class"], x["mode"]): x for x in s["by_class_and_mode"]}
        self.assertEqual(g[("pursuit", "end_to_end")]["success_rate"], round(2 / 3.0, 6))
        self.assertEqual(g[("pursuit", "end_to_end")]["missions_with_koz_violations"], 2)
        self.assertEqual(g[("area_search", "maneuver_only")]["mean_time_to_detect"], None)
        self.assertEqual(hc.summarize(cfg_of(), [])["success_rate"], None)

    def test_compare_leaves_out_run_specific_fields_only(self):
        a = {"run": {"shards": 4}, "missions": [mission("pursuit", "end_to_end", "success", 1.0, 0)],
             "summary": {"bag_bytes": 1, "missions": 1}}
        b = json.loads(json.dumps(a))
        b["run"]["shards"] = 1
        b["missions"][0].update(shard=3, host="n2", job="7_3", wall_time=9.0, finished="u",
                                bag_size=99, energy=1.5, end_time=6.4)
        b["summary"]["bag_bytes"] = 99
        self.assertEqual(hc.compare_manifests(a, b), [])
        b["missions"][0]["outcome"] = "timeout"
        b["missions"][0]["energy"] = None
        b["summary"]["missions"] = 2
        d = hc.compare_manifests(a, b)
        self.assertEqual(len(d), 2, d)
        self.assertIn(".missions[0].outcome", d[0])
        del b["missions"][0]["bag_size"]
        self.assertIn(".missions[0].bag_size: only in first", hc.compare_manifests(a, b))
        b["missions"].append(b["missions"][0])
        self.assertIn(".missions: 1 vs 2 items", hc.compare_manifests(a, b))


@unittest.skipUnless(os.environ.get("HAMERITT_BIN_DIR"), "needs the built hameritt_generate")
class GenerationCampaignTest(unittest.TestCase):
    """A generation-only campaign (24 scenarios) in 3 shards and in 1: the merged scenario files
    are byte-identical, the manifests equal; merge refuses while a unit is missing."""

    def setUp(self):
        self.d = tempfile.mkdtemp(prefix="campaign_gen_")

    def tearDown(self):
        shutil.rmtree(self.d)

    def run_main(self, *argv):
        out, err = io.StringIO(), io.StringIO()
        with redirect_stdout(out), redirect_stderr(err):
            rc = hc.main(list(argv))
        return rc, out.getvalue() + err.getvalue()

    def test_city_world(self):
        # "world: city" reaches hameritt_generate; the default adds nothing to the plan.
        self.assertNotIn("world", cfg_of())
        cfg = os.path.join(self.d, "city.yaml")
        wr(cfg, "name: c\nseed: 5\nclasses: [area_search]\ncount: 2\nworld: city\n")
        cdir = os.path.join(self.d, "city")
        self.assertEqual(self.run_main("plan", cfg, "--out", cdir)[0], 0)
        self.assertEqual(hc.run_shard(cdir, 0), 0)
        self.assertEqual(self.run_main("merge", cdir)[0], 0)
        with open(os.path.join(cdir, "merged", "world.json")) as f:
            self.assertEqual(json.load(f)["params"]["type"], "city")

    def test_sharded_equals_unsharded(self):
        text = "name: g\nseed: 5\nclasses: [pursuit, area_search]\ncount: 24\nshards: %d\n"
        dirs = {}
        for shards in (3, 1):
            cfg = os.path.join(self.d, "c%d.yaml" % shards)
            wr(cfg, text % shards)
            cdir = os.path.join(self.d, "s%d" % shards)
            self.assertEqual(self.run_main("plan", cfg, "--out", cdir)[0], 0)
            # Planning twice into one directory is fine; another config is refused.
            self.assertEqual(self.run_main("plan", cfg, "--out", cdir)[0], 0)
            dirs[shards] = cdir
        other = os.path.join(self.d, "other.yaml")
        wr(other, text.replace("seed: 5", "seed: 6") % 3)
        rc, msg = self.run_main("plan", other, "--out", dirs[3])
        self.assertEqual(rc, 2)
        self.assertIn("a different plan", msg)
        # Shard 1 of 3 only: status and merge report what is missing.
        self.assertEqual(hc.run_shard(dirs[3], 1), 0)
        st = hc.campaign_status(dirs[3])
        self.assertEqual((st["total"], st["complete"], st["shards_missing"]), (3, 1, [0, 2]))
        rc, msg = self.run_main("merge", dirs[3])
        self.assertEqual(rc, 3)
        self.assertIn("2 units missing", msg)
        # The rest, shard by shard; shard 1 again redoes nothing.
        for s in (0, 2, 1):
            self.assertEqual(hc.run_shard(dirs[3], s), 0)
        self.assertEqual(hc.run_shard(dirs[1], 0), 0)
        for cdir in dirs.values():
            self.assertEqual(self.run_main("status", cdir)[0], 0)
            self.assertEqual(self.run_main("merge", cdir)[0], 0)
        a, b = (os.path.join(dirs[k], "merged") for k in (3, 1))
        names = sorted(os.listdir(os.path.join(a, "scenarios")))
        self.assertEqual(len(names), 24)
        self.assertEqual(names, sorted(os.listdir(os.path.join(b, "scenarios"))))
        for n in names:
            for f in ("mission.json", "sim_config.json"):
                self.assertTrue(filecmp.cmp(os.path.join(a, "scenarios", n, f),
                                            os.path.join(b, "scenarios", n, f), shallow=False))
        self.assertTrue(filecmp.cmp(os.path.join(a, "world.json"), os.path.join(b, "world.json"),
                                    shallow=False))
        ma = json.loads(rd(os.path.join(a, "manifest.json")))
        mb = json.loads(rd(os.path.join(b, "manifest.json")))
        self.assertEqual(hc.compare_manifests(ma, mb), [])
        self.assertEqual(ma["run"]["shards"], 3)
        self.assertEqual([s["index"] for s in ma["scenarios"]], list(range(24)))
        # The scenarios are those of one whole hameritt_generate batch, byte for byte.
        whole = os.path.join(self.d, "whole")
        subprocess.run([os.path.join(os.environ["HAMERITT_BIN_DIR"], "hameritt_generate"),
                        "--class", "pursuit,area_search", "--count", "24", "--seed", "5",
                        "--out", whole, "--quiet"], check=True)
        for n in names:
            self.assertTrue(filecmp.cmp(os.path.join(a, "scenarios", n, "sim_config.json"),
                                        os.path.join(whole, n, "sim_config.json"), shallow=False))
        # Each scenario's recorded hash is its file's.
        s0 = ma["scenarios"][0]
        self.assertEqual(s0["sha256"]["mission.json"],
                         hc.sha256_file(os.path.join(a, s0["path"], "mission.json")))

    def test_spec_campaign(self):
        # spec: a scenario-language spec instead of classes; the scenarios are byte for byte
        # those of hameritt_generate --spec, and hameritt_validate --spec accepts each one.
        spec = os.path.join(SRC, "scenarios", "specs", "red_sedan_garage.hspec")
        binp = os.environ["HAMERITT_BIN_DIR"]
        cfg = os.path.join(self.d, "spec.yaml")
        wr(cfg, "name: s\nseed: 5\ncount: 6\nshards: 2\nspec: %s\n"
           % os.path.relpath(spec, self.d))
        cdir = os.path.join(self.d, "spec")
        self.assertEqual(self.run_main("plan", cfg, "--out", cdir)[0], 0)
        for k in (0, 1):
            self.assertEqual(hc.run_shard(cdir, k), 0)
        self.assertEqual(self.run_main("merge", cdir)[0], 0)
        man = json.loads(rd(os.path.join(cdir, "merged", "manifest.json")))
        self.assertEqual(man["campaign"]["classes"], ["area_search"])
        self.assertEqual(man["campaign"]["spec"]["file"], spec)
        names = sorted(os.listdir(os.path.join(cdir, "merged", "scenarios")))
        self.assertEqual(len(names), 6)
        whole = os.path.join(self.d, "whole")
        subprocess.run([os.path.join(binp, "hameritt_generate"), "--spec", spec, "--count", "6",
                        "--seed", "5", "--out", whole, "--quiet"], check=True)
        for n in names:
            for f in ("mission.json", "sim_config.json"):
                self.assertTrue(filecmp.cmp(os.path.join(cdir, "merged", "scenarios", n, f),
                                            os.path.join(whole, n, f), shallow=False))
            self.assertIn("spec", json.loads(rd(os.path.join(whole, n, "sim_config.json"))))
        r = subprocess.run([os.path.join(binp, "hameritt_validate"), "--spec", spec,
                            os.path.join(cdir, "merged", "scenarios")], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, universal_newlines=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("6 scenarios, 6 meet the spec, 0 fail", r.stdout)
        # Negative control: the same scenes fail another spec.
        other = os.path.join(SRC, "scenarios", "specs", "impala_lookalikes.hspec")
        r = subprocess.run([os.path.join(binp, "hameritt_validate"), "--spec", other,
                            os.path.join(cdir, "merged", "scenarios")], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, universal_newlines=True)
        self.assertEqual(r.returncode, 2)
        self.assertIn("6 scenarios, 0 meet the spec, 6 fail", r.stdout)
        # Bad spec campaigns are refused at plan time, naming the field or the requirement.
        unsat = os.path.join(self.d, "unsat.hspec")
        wr(unsat, "scenario area_search\ntarget car parked\nrequire street ON_TOP_OF target\n"
           "require driveway ON_TOP_OF target\n")
        for text, want in (
                ("seed: 1\ncount: 2\nclasses: all\nspec: %s\n" % spec, "field 'classes'"),
                ("seed: 1\ncount: 2\nspec: %s\nsampler: sobol\n" % spec, "field 'sampler'"),
                ("seed: 1\ncount: 2\nsampler: halton\n", "field 'sampler': expected only with"),
                ("seed: 1\ncount: 2\nspec: nope.hspec\n", "field 'spec'"),
                ("seed: 1\ncount: 2\nspec: %s\nspec_params: {snwo: 1}\n"
                 % os.path.join(SRC, "scenarios", "specs", "snowy_dusk_search.hspec"),
                 "unknown parameter 'snwo'"),
                ("seed: 1\ncount: 2\nspec: %s\n" % unsat, "unsatisfiable in this world")):
            wr(cfg, text)
            out = os.path.join(self.d, "bad_plan")
            rc, msg = self.run_main("plan", cfg, "--out", out)
            self.assertEqual(rc, 2, text)
            self.assertIn(want, msg, text)
            self.assertFalse(os.path.exists(os.path.join(out, "plan.json")), text)

    def test_cli_errors(self):
        bad = os.path.join(self.d, "bad.yaml")
        wr(bad, "seed: 1\ncount: 2\nmissions: {modes: [hover]}\n")
        rc, msg = self.run_main("plan", bad, "--out", os.path.join(self.d, "x"))
        self.assertEqual(rc, 2)
        self.assertIn("bad.yaml: field 'missions.modes'", msg)
        rc, msg = self.run_main("status", os.path.join(self.d, "nothing"))
        self.assertEqual(rc, 2)
        self.assertIn("plan.json: cannot read", msg)
        rc, msg = self.run_main("run", os.path.join(self.d, "nothing"))
        self.assertEqual(rc, 2)
        self.assertIn("--local is required", msg)

    def test_generate_first_flag(self):
        gen = os.path.join(os.environ["HAMERITT_BIN_DIR"], "hameritt_generate")
        out = os.path.join(self.d, "g")
        for extra, want in ((["--count", "1", "--seed", "1", "--first", "-1"], "--first"),
                            (["--count", "1", "--seed", "1", "--first", "x"], "--first"),
                            (["--scenario-seed", "3", "--first", "2"], "--scenario-seed")):
            r = subprocess.run([gen, "--class", "all", "--out", out] + extra,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               universal_newlines=True)
            self.assertEqual(r.returncode, 2, extra)
            self.assertIn(want, r.stderr.splitlines()[0], extra)
        self.assertFalse(os.path.exists(os.path.join(out, "manifest.json")))


if __name__ == "__main__":
    unittest.main(verbosity=2)
