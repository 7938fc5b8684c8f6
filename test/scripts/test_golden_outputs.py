#!/usr/bin/python3
"""Golden outputs: the SHA-256 of every file hameritt_generate writes for one scenario of each
class (area_search seed 2044 - the shipped scenarios/default -, route_search seed 14, pursuit
seed 11) and for a batch of all classes (--count 6 --seed 5) generated with --jobs 1 and again
with --jobs 2, against test/data/golden/generated.sha256. Any change to generated output fails
here until the golden file is updated on purpose:

  HAMERITT_UPDATE_GOLDEN=1 ctest -R script_test_golden_outputs   (from build/, after sourcing
  devel/setup.bash) rewrites test/data/golden/generated.sha256; review and commit the diff.

Negative control, run every time: the comparison is fed the same outputs with one byte
flipped in one file, one file missing and one extra file, and must report exactly those three.
Prints the counts; exits 1 on any mismatch.
"""

import hashlib
import os
import shutil
import subprocess
import sys
import tempfile

BIN = os.environ["HAMERITT_BIN_DIR"]
# A sanitizer tree names its generator hameritt_generate_sanitized (CMakeLists.txt).
GENERATE = os.environ.get("HAMERITT_GENERATE", f"{BIN}/hameritt_generate")
SRC = os.environ["HAMERITT_SOURCE_DIR"]
GOLDEN = os.path.join(SRC, "test", "data", "golden", "generated.sha256")
SINGLES = [("area_search", 2044), ("route_search", 14), ("pursuit", 11)]
BATCH = ["--class", "all", "--count", "6", "--seed", "5"]


def generate(out, args):
    subprocess.run([GENERATE, *args, "--out", out, "--quiet"], check=True)


def digests(root, prefix):
    """{prefix/relative path: sha256} of every file under root."""
    out = {}
    for d, _, files in os.walk(root):
        for f in files:
            p = os.path.join(d, f)
            with open(p, "rb") as fh:
                out[prefix + "/" + os.path.relpath(p, root)] = hashlib.sha256(fh.read()).hexdigest()
    return out


def compare(golden, got):
    """Sorted list of differences between two {name: sha256} maps."""
    diffs = [f"changed: {k}" for k in golden if k in got and got[k] != golden[k]]
    diffs += [f"missing: {k}" for k in golden if k not in got]
    diffs += [f"new: {k}" for k in got if k not in golden]
    return sorted(diffs)


def read_golden():
    golden = {}
    with open(GOLDEN) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                digest, name = line.split()
                golden[name] = digest
    return golden


def main():
    work = tempfile.mkdtemp(prefix="hameritt_golden_")
    try:
        got = {}
        for cls, seed in SINGLES:
            generate(f"{work}/{cls}", ["--class", cls, "--scenario-seed", str(seed)])
            got.update(digests(f"{work}/{cls}", f"{cls}-{seed}"))
        runs = {}
        for jobs in (1, 2):
            generate(f"{work}/batch{jobs}", BATCH + ["--jobs", str(jobs)])
            runs[jobs] = digests(f"{work}/batch{jobs}", "batch")
        got.update(runs[1])

        if os.environ.get("HAMERITT_UPDATE_GOLDEN") == "1":
            with open(GOLDEN + ".tmp", "w") as f:
                f.write("# SHA-256 of hameritt_generate outputs, checked by "
                        "test/scripts/test_golden_outputs.py;\n# regenerate with "
                        "HAMERITT_UPDATE_GOLDEN=1 (see the script).\n")
                for name in sorted(got):
                    f.write(f"{got[name]}  {name}\n")
            os.replace(GOLDEN + ".tmp", GOLDEN)
            print(f"golden outputs: wrote {len(got)} digests to {GOLDEN}")
            return 0

        golden = read_golden()
        failures = []
        for label, digest_map in (("singles and batch --jobs 1", got),
                                  ("batch --jobs 2", {**{k: v for k, v in got.items()
                                                         if not k.startswith("batch/")},
                                                      **runs[2]})):
            diffs = compare(golden, digest_map)
            print(f"{label}: {len(digest_map)} files, {len(diffs)} differ from the golden file")
            failures += [f"{label}: {d}" for d in diffs]

        # Negative control: one flipped byte, one missing file, one new file.
        cls, seed = SINGLES[-1]
        prefix = f"{cls}-{seed}"
        name = sorted(k for k in got if k.startswith(prefix + "/"))[0]
        path = os.path.join(work, cls, name.split("/", 1)[1])
        with open(path, "r+b") as f:
            b = f.read(1)
            f.seek(0)
            f.write(bytes([b[0] ^ 1]))
        broken = digests(f"{work}/{cls}", prefix)
        broken.pop(sorted(broken)[-1])
        broken[prefix + "/extra.json"] = "0" * 64
        control = compare({k: v for k, v in got.items() if k.startswith(prefix + "/")}, broken)
        kinds = sorted(d.split(":")[0] for d in control)
        print(f"negative control (one byte flipped, one file removed, one added): {control}")
        if kinds != ["changed", "missing", "new"]:
            failures.append(f"negative control: expected one changed, one missing and one new "
                            f"file, got {control}")
        n_golden = len(golden)
        if n_golden != len(got):
            failures.append(f"golden file lists {n_golden} files, this run wrote {len(got)}")
        for f in failures:
            print("FAIL:", f)
        if failures:
            print("If the change to generated output is intended: HAMERITT_UPDATE_GOLDEN=1 "
                  "(see test/scripts/test_golden_outputs.py), then review and commit the diff.")
        # Checks: each file of both comparisons, the negative control, the golden file's size.
        total = 2 * len(got) + 2
        print(f"{len(got)} files pinned; {total - len(failures)} passed, {len(failures)} failed")
        return 1 if failures else 0
    finally:
        shutil.rmtree(work)


if __name__ == "__main__":
    sys.exit(main())
