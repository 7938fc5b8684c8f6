#!/usr/bin/python3
"""Outside-judge check of the scenario JSON schemas with python3-jsonschema (Draft 7).

Runs $HAMERITT_BIN_DIR/hameritt_generate for a batch of every class, then checks that
  * every schema in $HAMERITT_SOURCE_DIR/config/schema is itself a valid draft-07 schema,
  * every mission.json, sim_config.json, world.json and manifest.json of the batch validates,
  * hand-broken documents are rejected at the expected place,
  * $HAMERITT_BIN_DIR/hameritt_validate accepts the batch and rejects a bow-tie AOI polygon
    (a rule beyond the schema) with a "FILE: PATH: RULE: MESSAGE" line.
Prints one line per failure and a "N passed, N failed" summary; exits 1 on any failure.
"""

import copy
import glob
import json
import os
import shutil
import subprocess
import sys
import tempfile

try:
    from jsonschema import Draft7Validator
except ImportError:  # Debian: apt-get install python3-jsonschema
    print("test_jsonschema: python3-jsonschema is not installed", file=sys.stderr)
    sys.exit(1)

KINDS = ("mission", "sim_config", "world", "manifest")

passed = 0
failed = 0


def ok(name):
    global passed
    passed += 1


def fail(name, why):
    global failed
    failed += 1
    print("FAIL %s: %s" % (name, why))


def env_dir(var):
    value = os.environ.get(var)
    if not value or not os.path.isdir(value):
        print("test_jsonschema: $%s must name a directory (got %r)" % (var, value), file=sys.stderr)
        sys.exit(1)
    return value


def load_validators(schema_dir):
    validators = {}
    for kind in KINDS:
        name = "%s.schema.json" % kind
        path = os.path.join(schema_dir, name)
        try:
            with open(path) as f:
                schema = json.load(f)
            Draft7Validator.check_schema(schema)
        except Exception as e:  # missing file, malformed JSON or an invalid schema
            fail("schema " + name, e)
            continue
        if schema.get("properties", {}).get("schema", {}).get("const") != "hameritt/" + kind:
            fail("schema " + name, 'properties.schema.const is not "hameritt/%s"' % kind)
            continue
        ok("schema " + name)
        validators["hameritt/" + kind] = Draft7Validator(schema)
    return validators


def errors_of(validators, doc):
    """Error messages of doc against the schema its "schema" field names."""
    v = validators.get(doc.get("schema")) if isinstance(doc, dict) else None
    if v is None:
        kind = doc.get("schema") if isinstance(doc, dict) else doc
        return ["no schema for document kind %r" % (kind,)]
    return ["/%s: %s" % ("/".join(str(p) for p in e.absolute_path), e.message)
            for e in v.iter_errors(doc)]


def expect_rejected(validators, name, doc, where):
    """doc must fail, with an error located at JSON path `where` (a list of keys/indices)."""
    v = validators.get(doc["schema"])
    if v is None:
        fail(name, "no validator for %s" % doc["schema"])
        return
    errs = list(v.iter_errors(doc))
    if not errs:
        fail(name, "broken document was accepted")
    elif not any(list(e.absolute_path) == where for e in errs):
        fail(name, "rejected, but not at /%s: %s" % ("/".join(map(str, where)),
                                                      [e.message for e in errs]))
    else:
        ok(name)


def expect_beyond_schema(name, validators, validate, schema_dir, doc, path, want):
    """doc (written to `path`) passes jsonschema, and hameritt_validate rejects the file with
    exit 2 and stderr starting with `want`: a rule beyond what a schema can express."""
    run = subprocess.run([validate, "--schema-dir", schema_dir, path], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, universal_newlines=True, timeout=60)
    if errors_of(validators, doc):
        fail(name, "jsonschema rejected it: %s" % errors_of(validators, doc))
    elif run.returncode != 2 or not run.stderr.startswith(want):
        fail(name, "hameritt_validate exit %d, stderr %r" % (run.returncode, run.stderr))
    else:
        ok(name)


def expect_all_valid(name, validate, schema_dir, files):
    """hameritt_validate accepts every file: exit 0 and one "FILE: ok" line each."""
    run = subprocess.run([validate, "--schema-dir", schema_dir] + files, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, universal_newlines=True, timeout=300)
    ok_lines = [l for l in run.stdout.splitlines() if l.endswith(": ok")]
    if run.returncode != 0 or len(ok_lines) != len(files):
        fail(name, "exit %d, %d of %d ok: %s" % (
            run.returncode, len(ok_lines), len(files), run.stderr.strip()[:500]))
    else:
        ok(name)


def check_avoid(validators, generate, validate, schema_dir, out, search_mission):
    """Avoid scenarios (a class outside "all"): their files validate with jsonschema and
    hameritt_validate; broken ones are rejected where they break, and an aircraft that jumps
    (continuity, beyond a schema) passes jsonschema but not hameritt_validate."""
    aout = os.path.join(out, "avoid")
    run = subprocess.run([generate, "--class", "avoid", "--count", "4", "--seed", "7", "--out",
                          aout, "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         universal_newlines=True, timeout=300)
    if run.returncode != 0:
        fail("hameritt_generate avoid", "exit %d: %s" % (run.returncode, run.stderr.strip()))
        return
    files = sorted(glob.glob(os.path.join(aout, "avoid-*", "*.json")))
    docs = {}
    for path in files:
        with open(path) as f:
            doc = json.load(f)
        errs = errors_of(validators, doc)
        if errs:
            fail(os.path.relpath(path, out), "; ".join(errs[:5]))
        else:
            ok(os.path.relpath(path, out))
        docs.setdefault(doc.get("schema"), doc)
    if len(files) != 8:
        fail("avoid batch", "expected 8 documents, found %d" % len(files))
        return
    ok("avoid batch")
    expect_all_valid("hameritt_validate avoid", validate, schema_dir, files)
    m, s = docs["hameritt/mission"], docs["hameritt/sim_config"]
    if search_mission is not None:
        b = copy.deepcopy(m)
        b["objective"]["targets"] = copy.deepcopy(search_mission["objective"]["targets"])
        expect_rejected(validators, "reach objective with targets", b, ["objective"])
    b = copy.deepcopy(m)
    moving = [i for i, k in enumerate(b["keep_out_zones"]) if "motion" in k]
    if len(moving) != 1:
        fail("avoid moving zone", "expected one zone with motion, found %d" % len(moving))
    else:
        b["keep_out_zones"][moving[0]]["motion"][0] = [0.0, 1.0]
        expect_rejected(validators, "two-number motion sample", b,
                        ["keep_out_zones", moving[0], "motion", 0])
    b = copy.deepcopy(s)
    b["aircraft"][0]["trajectory"] = b["aircraft"][0]["trajectory"][:1]
    expect_rejected(validators, "one-sample aircraft trajectory", b, ["aircraft", 0, "trajectory"])
    b = copy.deepcopy(s)
    b["aircraft"][0]["model"] = "airship"
    expect_rejected(validators, "unknown aircraft model", b, ["aircraft", 0, "model"])
    b = copy.deepcopy(s)
    b["aircraft"][0]["trajectory"][1][1] += 5000.0
    broken = os.path.join(out, "jump_sim_config.json")
    with open(broken, "w") as f:
        json.dump(b, f)
    expect_beyond_schema("aircraft jump", validators, validate, schema_dir, b, broken,
                         broken + ": /aircraft/0/trajectory/1: trajectory_speed: ")
    # Against the world (beyond the files): a stated shortest path shorter than the straight
    # line passes jsonschema; hameritt_validate checks the sim_config with its mission.
    src = os.path.dirname(files[0])
    bad_dir = os.path.join(out, "short_path")
    shutil.copytree(src, bad_dir)
    with open(os.path.join(bad_dir, "mission.json")) as f:
        b = json.load(f)
    b["phases"][0]["shortest_path_m"] = 1.0
    with open(os.path.join(bad_dir, "mission.json"), "w") as f:
        json.dump(b, f)
    bad_sim = os.path.join(bad_dir, "sim_config.json")
    expect_beyond_schema("avoid short path", validators, validate, schema_dir, b, bad_sim,
                         bad_sim + ": (root): avoid_scenario: mission.json: phases: avoid "
                         "shortest_path_m 1 ")


def main():
    bin_dir = env_dir("HAMERITT_BIN_DIR")
    source_dir = env_dir("HAMERITT_SOURCE_DIR")
    schema_dir = os.path.join(source_dir, "config", "schema")
    generate = os.path.join(bin_dir, "hameritt_generate")

    validators = load_validators(schema_dir)
    if len(validators) != len(KINDS):
        print("%d passed, %d failed" % (passed, failed))
        return 1

    out = tempfile.mkdtemp(prefix="hameritt_jsonschema_")
    try:
        cmd = [generate, "--class", "all", "--count", "60", "--seed", "7", "--out", out, "--quiet"]
        run = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             universal_newlines=True, timeout=540)
        if run.returncode != 0:
            fail("hameritt_generate", "exit %d: %s" % (run.returncode, run.stderr.strip()))
            print("%d passed, %d failed" % (passed, failed))
            return 1
        ok("hameritt_generate")

        files = sorted(glob.glob(os.path.join(out, "*", "mission.json")) +
                       glob.glob(os.path.join(out, "*", "sim_config.json")))
        files += [os.path.join(out, "world.json"), os.path.join(out, "manifest.json")]
        counts = {}
        docs = {}
        for path in files:
            rel = os.path.relpath(path, out)
            try:
                with open(path) as f:
                    doc = json.load(f)
            except Exception as e:
                fail(rel, "cannot read JSON: %s" % e)
                continue
            errs = errors_of(validators, doc)
            if errs:
                more = " (+%d more)" % (len(errs) - 5) if len(errs) > 5 else ""
                fail(rel, "; ".join(errs[:5]) + more)
            else:
                ok(rel)
            counts[doc.get("schema")] = counts.get(doc.get("schema"), 0) + 1
            docs.setdefault(doc.get("schema"), doc)
        for kind, want in (("hameritt/mission", 60), ("hameritt/sim_config", 60),
                           ("hameritt/world", 1), ("hameritt/manifest", 1)):
            if counts.get(kind, 0) != want:
                fail("batch", "expected %d %s documents, found %d"
                     % (want, kind, counts.get(kind, 0)))
            else:
                ok("batch " + kind)

        # Hand-broken documents, each derived from a valid one.
        mission = docs.get("hameritt/mission")
        sim = docs.get("hameritt/sim_config")
        if mission is None or sim is None:
            fail("broken documents", "no valid mission/sim_config to derive them from")
        else:
            m = copy.deepcopy(mission)
            m["frame"]["origin"]["datum"] = "WGS84"
            expect_rejected(validators, "unknown key", m, ["frame", "origin"])

            m = copy.deepcopy(mission)
            m["scene_relations"] = [{
                "related": {"id": "group_1", "class": "group", "attributes": {"kind": "block"}},
                "operator": "EVENTUALLY_PART_OF", "target": m["objective"]["targets"][0]["id"],
                "evidence": {"time": 3.0}, "text": "x"}]
            expect_rejected(validators, "EVENTUALLY_PART_OF operator", m,
                            ["scene_relations", 0, "operator"])

            m = copy.deepcopy(mission)
            m["keep_out_zones"] = [{"id": "koz_1", "purpose": "restricted",
                                    "polygon": [[0, 0], [10, 0]], "altitude": {},
                                    "time_window": {}}]
            expect_rejected(validators, "two-point polygon", m, ["keep_out_zones", 0, "polygon"])

            # Mission phases: a chain of every phase type validates; a broken phase is
            # rejected at its item.
            m = copy.deepcopy(mission)
            tid = m["objective"]["targets"][0]["id"]
            m["phases"] = [
                {"id": "find", "type": "search", "targets": [tid]},
                {"id": "keep_behind", "type": "follow", "targets": [tid], "duration": 120.0,
                 "envelope": {"distance": 15.0, "distance_tolerance": 5.0, "height": 20.0,
                              "height_tolerance": 5.0},
                 "criteria": {"min_inside_fraction": 0.8, "max_outside_s": 10.0,
                              "approach_s": 34.0}},
                {"id": "watch", "type": "track", "targets": [tid], "duration": 60.0,
                 "criteria": {"min_visible_fraction": 0.5, "min_box_area": 400.0,
                              "min_tracked_fraction": 0.7, "max_reacquire_s": 10.0}},
                {"id": "home", "type": "avoid", "targets": [], "goal": [10.0, -20.0, 30.0],
                 "goal_radius": 5.0, "shortest_path_m": 412.0,
                 "criteria": {"min_horizontal_separation": 5.0, "min_vertical_separation": 3.0}}]
            errs = errors_of(validators, m)
            if errs:
                fail("mission with phases", errs)
            else:
                ok("mission with phases")
            b = copy.deepcopy(m)
            b["phases"][1]["targets"] = [tid, tid]
            expect_rejected(validators, "follow phase with two targets", b, ["phases", 1])
            b = copy.deepcopy(m)
            b["phases"][2]["criteria"]["min_tracked_fraction"] = 1.5
            expect_rejected(validators, "track fraction above 1", b, ["phases", 2])
            b = copy.deepcopy(m)
            del b["phases"][3]["goal"]
            expect_rejected(validators, "avoid phase without a goal", b, ["phases", 3])
            b = copy.deepcopy(m)
            b["phases"][0]["duration"] = 30.0
            expect_rejected(validators, "search phase with a duration", b, ["phases", 0])

            s = copy.deepcopy(sim)
            s["entities"][0]["trajectory"] = [[0, 1, 2, 0]]
            expect_rejected(validators, "4-number trajectory sample", s,
                            ["entities", 0, "trajectory", 0])

            s = copy.deepcopy(sim)
            s["seed"] = -1
            expect_rejected(validators, "negative seed", s, ["seed"])

            s = copy.deepcopy(sim)
            del s["world"]["params"]["lot_depth"]
            expect_rejected(validators, "world params missing a key", s, ["world", "params"])

        # The C++ validator agrees on the batch and also catches what a schema cannot express.
        validate = os.path.join(bin_dir, "hameritt_validate")
        expect_all_valid("hameritt_validate batch", validate, schema_dir, files)
        area = [p for p in files if os.path.basename(os.path.dirname(p)).startswith("area_search")
                and p.endswith("mission.json")]
        if not area:
            fail("bow-tie AOI", "the batch has no area_search mission")
        else:
            with open(area[0]) as f:
                m = json.load(f)
            poly = m["areas_of_interest"][0]["polygon"]
            poly[1], poly[2] = poly[2], poly[1]  # edges 0-1 and 2-3 now cross
            broken = os.path.join(out, "bowtie_mission.json")
            with open(broken, "w") as f:
                json.dump(m, f)
            # Schemas cannot express geometry: jsonschema accepts it, hameritt_validate does not.
            expect_beyond_schema("bow-tie AOI", validators, validate, schema_dir, m, broken,
                                 broken + ": /areas_of_interest/0/polygon: polygon_simple: ")
        check_avoid(validators, generate, validate, schema_dir, out, mission)
    finally:
        shutil.rmtree(out, ignore_errors=True)

    print("%d passed, %d failed" % (passed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
