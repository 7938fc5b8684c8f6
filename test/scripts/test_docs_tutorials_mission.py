"""The documentation cannot drift from the code: every runnable shell block of the tutorials is run.

A runnable block is a fenced block whose opening line is exactly ```bash and whose previous
non-empty line is <!-- runnable -->. For each docs/tutorials/NN-*.md in order, this test runs the
page's runnable blocks in order in ONE bash process (so cd and variables carry from block to
block) under `set -euo pipefail`, in a scratch directory of its own that looks like a clone with
a build (`build` links to the build directory this test belongs to, so `source
build/devel/setup.bash` works as the first tutorial says), with the devel space sourced, a
private ROS master port (ROS_MASTER_URI) and UDP port for a TAK listener (TAK_PORT), and a
deadline. A page fails when a block exits non-zero or the deadline passes; the failure names the
page, the block number, the block and the output's tail. The number of blocks that ran to their
end must equal the number the page has, and every <!-- runnable --> marker must open a bash block.

Also checked: README.md keeps the two quick-start commands, a picture from docs/images/ and
links to BENCHMARKS.md and docs/RELIABILITY.md; each tool of docs/reference/tools.md answers
--help with a usage (exit 0) that names every --flag its section names; every relative link and
image of README.md and docs/**/*.md resolves to an existing file (anchors are not checked);
README.md has at most 250 lines and each page of docs/index.md, docs/tutorials, docs/howto,
docs/reference and docs/explanation at most 400 (docs/RELIABILITY.md, like BENCHMARKS.md, is the
measured record and has no limit).

Negative controls, run first: a synthetic page whose second of three blocks fails must be
reported failing at block 2 with block 3 not run; a block that outlives the deadline must be
reported and its processes stopped; marker errors must be reported; a broken link, a page over
the line limit and a README without the quick start, picture or links must be reported; a
documented flag a tool lacks, and a missing tool, must be reported.
"""
import glob
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time

SRC = os.environ.get("HAMERITT_SOURCE_DIR") or os.path.abspath(
    os.path.join(os.path.dirname(__file__), "..", ".."))
BIN = os.environ.get("HAMERITT_BIN_DIR", "")
# HAMERITT_BIN_DIR is <build>/devel/lib/hameritt.
DEVEL = os.path.dirname(os.path.dirname(BIN)) if BIN else os.path.join(SRC, "build", "devel")
BUILD = os.path.dirname(DEVEL)
MARKER = "<!-- runnable -->"
PAGE_DEADLINE_S = 240.0
README_MAX_LINES = 250
PAGE_MAX_LINES = 400


def parse_page(text):
    """(runnable blocks as (first line number, code), errors) of a Markdown page."""
    lines = text.split("\n")
    blocks, errors = [], []
    markers = [i for i, l in enumerate(lines) if l.strip() == MARKER]
    used = set()
    i = 0
    while i < len(lines):
        if lines[i].startswith("```"):
            opening = lines[i]
            j = i + 1
            while j < len(lines) and lines[j].rstrip() != "```":
                j += 1
            if j == len(lines):
                errors.append("line %d: a fenced block that never closes" % (i + 1))
                break
            k = i - 1
            while k >= 0 and not lines[k].strip():
                k -= 1
            if k >= 0 and lines[k].strip() == MARKER:
                used.add(k)
                if opening != "```bash":
                    errors.append("line %d: %s opens %r, not ```bash" % (k + 1, MARKER, opening))
                else:
                    blocks.append((i + 2, "\n".join(lines[i + 1:j])))
            i = j + 1
            continue
        i += 1
    for m in markers:
        if m not in used:
            errors.append("line %d: %s is not followed by a fenced block" % (m + 1, MARKER))
    return blocks, errors


def free_port(kind=socket.SOCK_STREAM, start=20000):
    """A port that binds now, from a pid-dependent start."""
    base = start + (os.getpid() * 7) % 20000
    for p in range(base, base + 2000):
        s = socket.socket(socket.AF_INET, kind)
        try:
            s.bind(("127.0.0.1", p))
            return p
        except OSError:
            continue
        finally:
            s.close()
    raise RuntimeError("no free port")


def make_scratch(root, name):
    """A scratch directory that looks like a clone with a build: `build` links to the build."""
    d = os.path.join(root, name)
    os.makedirs(d)
    os.symlink(BUILD, os.path.join(d, "build"))
    return d


def run_page(name, text, scratch, deadline=PAGE_DEADLINE_S, grace=10.0):
    """Runs a page's runnable blocks; returns (ok, blocks in the page, blocks completed, report)."""
    blocks, errors = parse_page(text)
    if errors:
        return False, len(blocks), 0, "%s: %s" % (name, "; ".join(errors))
    if not blocks:
        return False, 0, 0, "%s: no runnable block (every tutorial command must be run)" % name
    progress = os.path.join(scratch, ".docs_progress")
    parts = ["set -eo pipefail",
             'source "%s/setup.bash"' % DEVEL,
             "set -u",
             'cd "%s"' % scratch]
    for n, (_, code) in enumerate(blocks, 1):
        parts.append('echo "start %d" >> "%s"' % (n, progress))
        parts.append("# ---- block %d" % n)
        parts.append(code)
        parts.append('echo "end %d" >> "%s"' % (n, progress))
    script = os.path.join(scratch, ".docs_page.sh")
    with open(script, "w") as f:
        f.write("\n".join(parts) + "\n")
    log_path = os.path.join(scratch, ".docs_output.log")
    env = dict(os.environ)
    env.update({
        "PATH": "/usr/bin:/bin:/usr/sbin:/sbin:" + env.get("PATH", ""),
        "PYTHONNOUSERSITE": "1",
        "ROS_MASTER_URI": "http://localhost:%d" % free_port(),
        "TAK_PORT": str(free_port(socket.SOCK_DGRAM, 30000)),
        "ROS_LOG_DIR": os.path.join(scratch, ".ros_log"),
        "ROS_HOME": os.path.join(scratch, ".ros_home"),
    })
    t0 = time.time()
    timed_out = False
    with open(log_path, "w") as log:
        proc = subprocess.Popen(["/bin/bash", script], cwd=scratch, env=env, stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True)
        try:
            rc = proc.wait(timeout=deadline)
        except subprocess.TimeoutExpired:
            timed_out = True
            rc = None
        wall = time.time() - t0
        # Whatever the page left running (a background launch, a listener) goes with it.
        for sig, wait_s in ((signal.SIGINT, grace), (signal.SIGKILL, 5.0)):
            try:
                os.killpg(proc.pid, sig)
            except ProcessLookupError:
                break
            end = time.time() + wait_s
            while time.time() < end:
                proc.poll()  # reap the page's shell, so that a zombie does not count as alive
                try:
                    os.killpg(proc.pid, 0)
                except ProcessLookupError:
                    break
                time.sleep(0.2)
        if rc is None:
            proc.wait()
    started, ended = [], []
    if os.path.exists(progress):
        for line in open(progress):
            what, n = line.split()
            (started if what == "start" else ended).append(int(n))
    completed = len(ended)
    if rc == 0 and not timed_out and completed == len(blocks):
        return True, len(blocks), completed, "%s: %d of %d blocks run, %.0f s" % (
            name, completed, len(blocks), wall)
    failed = started[-1] if started else 0
    why = ("did not finish within %.0f s" % deadline) if timed_out else ("exited %s" % rc)
    output = open(log_path, errors="replace").read().splitlines()
    code = blocks[failed - 1][1] if failed else "(before the first block)"
    line = blocks[failed - 1][0] if failed else 0
    report = ("%s: block %d of %d (line %d) %s after %.0f s; %d blocks completed\n"
              "---- the block:\n%s\n---- the last 60 lines of its output:\n%s") % (
                  name, failed, len(blocks), line, why, wall, completed, code,
                  "\n".join(output[-60:]))
    return False, len(blocks), completed, report


CODE_FENCE = re.compile(r"^```.*?^```", re.S | re.M)
CODE_SPAN = re.compile(r"`[^`\n]*`")
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")


def check_links(root, files):
    """(links checked, broken links) of the Markdown files (paths under root)."""
    checked, broken = 0, []
    for rel in files:
        text = open(os.path.join(root, rel)).read()
        text = CODE_SPAN.sub("", CODE_FENCE.sub("", text))
        for target in LINK.findall(text):
            if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
                continue
            path = target.split("#", 1)[0]
            full = os.path.normpath(os.path.join(root, os.path.dirname(rel), path))
            checked += 1
            if os.path.exists(full):
                continue
            broken.append("%s -> %s" % (rel, target))
    return checked, broken


def check_lengths(root, files):
    """Pages over their line limit."""
    over = []
    for rel in files:
        n = len(open(os.path.join(root, rel)).read().splitlines())
        limit = README_MAX_LINES if rel == "README.md" else PAGE_MAX_LINES
        if rel in ("README.md", "docs/index.md") or re.match(
                r"docs/(tutorials|howto|reference|explanation)/", rel):
            if n > limit:
                over.append("%s: %d lines (at most %d)" % (rel, n, limit))
    return over


def check_tools(root, bin_dir):
    """(tools checked, problems): each `## hameritt_*` section of docs/reference/tools.md names a
    tool whose --help exits 0 with a usage, and every --flag the section names is in that help
    (for hameritt_campaign, the help of each subcommand)."""
    text = open(os.path.join(root, "docs", "reference", "tools.md")).read()
    sections = re.split(r"^## ", text, flags=re.M)[1:]
    checked, problems = 0, []
    for sec in sections:
        tool = sec.split("\n", 1)[0].strip()
        if not tool.startswith("hameritt_"):
            continue
        checked += 1
        exe = os.path.join(bin_dir, tool)
        runs = [[exe, "--help"]]
        if tool == "hameritt_campaign":
            runs += [[exe, c, "--help"] for c in
                     ("plan", "run", "run-shard", "submit", "status", "merge", "compare")]
        helps = []
        if not os.access(exe, os.X_OK):
            problems.append("%s: no such tool in %s" % (tool, bin_dir))
            continue
        for cmd in runs:
            r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               universal_newlines=True)
            if r.returncode != 0 or "usage" not in r.stdout.lower():
                problems.append("%s: exit %d, no usage: %s" % (" ".join(cmd[1:]), r.returncode,
                                                             r.stdout[:200]))
            helps.append(r.stdout)
        for flag in sorted(set(re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", sec))):
            if not any(re.search(re.escape(flag) + r"(?![\w-])", h) for h in helps):
                problems.append("%s: docs name %s, its --help does not" % (tool, flag))
    return checked, problems


def check_readme(root):
    """What the front door must keep: the two quick-start commands, a picture from docs/images/,
    and links to the measured record."""
    text = open(os.path.join(root, "README.md")).read()
    blocks = re.findall(r"^```bash\n(.*?)^```", text, re.S | re.M)
    problems = []
    for cmd in ("bash scripts/run_main.sh", "bash scripts/run_tests.sh"):
        if not any(re.search(r"^" + re.escape(cmd) + r"(\s|$)", b, re.M) for b in blocks):
            problems.append("README.md: no bash block with the quick-start command %r" % cmd)
    if not re.search(r"!\[[^\]]*\]\(docs/images/[^)]+\.png\)", text):
        problems.append("README.md: no picture from docs/images/")
    for target in ("BENCHMARKS.md", "docs/RELIABILITY.md"):
        if "](%s)" % target not in text:
            problems.append("README.md: no link to %s" % target)
    return problems


def doc_files(root):
    files = ["README.md"] if os.path.exists(os.path.join(root, "README.md")) else []
    files += sorted(os.path.relpath(p, root)
                    for p in glob.glob(os.path.join(root, "docs", "**", "*.md"), recursive=True))
    return files


def negative_controls(tmp):
    fails = []
    # A failing second block: reported at block 2, block 3 never runs.
    page = ("# Synthetic\n\n<!-- runnable -->\n```bash\necho one > one.txt\n```\n\n"
            "<!-- runnable -->\n```bash\ntest -e one.txt\nfalse\n```\n\n"
            "<!-- runnable -->\n```bash\necho three > three.txt\n```\n")
    d = make_scratch(tmp, "neg_fail")
    ok, n, done, report = run_page("synthetic.md", page, d)
    if ok or n != 3 or done != 1 or "block 2 of 3" not in report or os.path.exists(
            os.path.join(d, "three.txt")):
        fails.append("negative control: a failing block 2 was not reported as such (ok %s, "
                     "%d blocks, %d done): %s" % (ok, n, done, report[:300]))
    else:
        print("negative control: failing block reported: %s" % report.splitlines()[0])
    # A block that outlives the deadline, with a background child that must be stopped too.
    page = "<!-- runnable -->\n```bash\nsleep 3017 &\nsleep 3017\n```\n"
    d = make_scratch(tmp, "neg_slow")
    ok, n, done, report = run_page("slow.md", page, d, deadline=2, grace=1)
    alive = subprocess.run(["pgrep", "-f", "sleep 3017"], stdout=subprocess.PIPE).stdout.split()
    if ok or "did not finish within 2 s" not in report or alive:
        fails.append("negative control: a hung block was not reported or its processes live on "
                     "(%r): %s" % (alive, report[:300]))
    else:
        print("negative control: hung block reported: %s" % report.splitlines()[0])
    # A dangling marker and a marker before a non-bash fence.
    page = "<!-- runnable -->\n\ntext\n\n<!-- runnable -->\n```sh\necho x\n```\n"
    blocks, errors = parse_page(page)
    if blocks or len(errors) != 2:
        fails.append("negative control: marker errors not found: %r %r" % (blocks, errors))
    else:
        print("negative control: %d marker errors found" % len(errors))
    # A broken link, a good one, an anchor-only one, and a page over the limit.
    root = os.path.join(tmp, "neg_docs")
    os.makedirs(os.path.join(root, "docs", "howto"))
    with open(os.path.join(root, "README.md"), "w") as f:
        f.write("[ok](docs/howto/a.md#x) [anchor](#top) [gone](docs/missing.md) `[code](no.md)`\n")
    with open(os.path.join(root, "docs", "howto", "a.md"), "w") as f:
        f.write("line\n" * (PAGE_MAX_LINES + 1))
    checked, broken = check_links(root, doc_files(root))
    over = check_lengths(root, doc_files(root))
    readme = check_readme(root)
    if len(readme) != 5:
        fails.append("negative control: README check found %r" % readme)
    else:
        print("negative control: README check reported %d problems" % len(readme))
    if checked != 2 or broken != ["README.md -> docs/missing.md"] or len(over) != 1:
        fails.append("negative control: links %d %r, lengths %r" % (checked, broken, over))
    else:
        print("negative control: broken link and long page reported: %s; %s" % (broken[0], over[0]))
    # A flag the docs name that the tool does not have, and a tool that does not exist.
    root = os.path.join(tmp, "neg_tools")
    os.makedirs(os.path.join(root, "docs", "reference"))
    with open(os.path.join(root, "docs", "reference", "tools.md"), "w") as f:
        f.write("# Tools\n\n## hameritt_map\n\n`--out`, `--no-such-flag`\n\n## hameritt_nope\n")
    checked, problems = check_tools(root, BIN)
    if checked != 2 or len(problems) != 2 or "--no-such-flag" not in problems[0] or (
            "no such tool" not in problems[1]):
        fails.append("negative control: tools check: %d %r" % (checked, problems))
    else:
        print("negative control: tools check reported: %s" % "; ".join(p[:60] for p in problems))
    return fails


def main():
    if not os.path.isfile(os.path.join(DEVEL, "setup.bash")):
        print("FAIL: no devel space at %s (HAMERITT_BIN_DIR %r)" % (DEVEL, BIN))
        return 1
    tmp = tempfile.mkdtemp(prefix="docs_tutorials_")
    fails = negative_controls(tmp)

    files = doc_files(SRC)
    checked, broken = check_links(SRC, files)
    over = check_lengths(SRC, files)
    print("links: %d relative links in %d files, %d broken" % (checked, len(files), len(broken)))
    if checked < 50:
        fails.append("only %d relative links found: the link check reads nothing" % checked)
    fails += ["broken link: %s" % b for b in broken]
    fails += ["too long: %s" % o for o in over]
    print("lengths: %d files over their limit" % len(over))
    readme = check_readme(SRC)
    print("README: %d problems (quick start, picture, measured record)" % len(readme))
    fails += readme
    tools, problems = check_tools(SRC, BIN)
    print("tools: %d tools' --help against docs/reference/tools.md, %d problems" % (tools,
                                                                                  len(problems)))
    if tools < 9:
        fails.append("only %d tools found in docs/reference/tools.md" % tools)
    fails += problems

    pages = sorted(glob.glob(os.path.join(SRC, "docs", "tutorials", "[0-9][0-9]-*.md")))
    if len(pages) < 6:
        fails.append("only %d tutorial pages found" % len(pages))
    total = 0
    for path in pages:
        name = os.path.relpath(path, SRC)
        scratch = make_scratch(tmp, os.path.basename(path)[:-3])
        ok, n, done, report = run_page(name, open(path).read(), scratch)
        print(report if ok else "FAIL " + report)
        sys.stdout.flush()
        total += done
        if not ok:
            fails.append("tutorial failed: %s" % report.splitlines()[0])
    print("tutorials: %d pages, %d runnable blocks run" % (len(pages), total))
    if fails:
        print("FAIL:\n  " + "\n  ".join(fails))
        return 1
    subprocess.call(["rm", "-rf", tmp])
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
