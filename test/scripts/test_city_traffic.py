#!/usr/bin/python3
"""The city's signalised traffic and crowds judged from outside, on the sim_config.json files that
hameritt_generate --world city writes (numpy; nothing of hameritt's own readers):

  * every traffic car's trajectory, sampled every 0.1 s, against the signal timeline recomputed
    here from the written plan: no car's front enters an intersection box while its axis shows
    red, nor the left arrow when it goes straight on; a car that turns enters on the arrow only;
  * no two cars' footprints ever overlap (all pairs, every 0.1 s, separating-axis test), and a
    follower in the same lane (same heading, less than a metre across) keeps the standstill gap
    and a time gap;
  * pedestrians who cross at a signal are on the carriageway only while its traffic is red;
    the share of jaywalkers among the crossers is the configured probability (3 sigma); some
    queue at the bus stops of the written world.json;
  * >= 100 moving cars and >= 300 pedestrians per km^2 inside the tile at every sample;
  * a cycle set in world.json is the one written; a signal key out of its range exits 2 naming
    the key and the range, with nothing written;
  * the mission's own moving cars (the route search's targets) enter the boxes only on their
    signal, as the traffic does.
Each check runs first on a doctored copy (a car made late, the plan shifted by half a cycle, a
doubled probability, a follower moved closer) and must flag it: the negative controls.
Prints one line per failure and a "N passed, N failed" summary; exits 1 on any failure.
"""

import glob
import hashlib
import json
import math
import os
import subprocess
import sys
import tempfile

try:
    import numpy as np
except ImportError as e:  # Debian: python3-numpy
    print("test_city_traffic: %s" % e, file=sys.stderr)
    sys.exit(1)

from tool_checks import BIN, ENV, SRC, check, counts, run  # noqa: E402
DT = 0.1


# ------------------------------------------------------------------ the signal timeline
def phase(plan, inter, axis, t):
    """The state of `axis` at intersection `inter` at times t (array): 'L', 'G', 'Y' or 'R'.
    Cycle: axis 0 left arrow, green, yellow, all-red; then axis 1 the same."""
    left, green, yellow, all_red = plan["left"], plan["green"], plan["yellow"], plan["all_red"]
    cycle = 2 * (left + green + yellow + all_red)
    tau = np.mod(np.asarray(t) - inter["offset"] - (0.5 * cycle if axis == 1 else 0.0), cycle)
    out = np.full(tau.shape, "R")
    out[tau < left + green + yellow] = "Y"
    out[tau < left + green] = "G"
    out[tau < left] = "L"
    return out


# ------------------------------------------------------------------ trajectories
def sample(traj, times):
    """x, y, yaw of a [t, x, y, z, yaw] trajectory at `times` (held before and after)."""
    a = np.asarray(traj, dtype=float)
    yaw = np.unwrap(a[:, 4])
    return (np.interp(times, a[:, 0], a[:, 1]), np.interp(times, a[:, 0], a[:, 2]),
            np.interp(times, a[:, 0], yaw))


def car_states(cars, times):
    """Arrays (N, T) of x, y, yaw, and the (N,) lengths and widths."""
    xs, ys, yaws = [], [], []
    for c in cars:
        x, y, yaw = sample(c["trajectory"], times)
        xs.append(x)
        ys.append(y)
        yaws.append(yaw)
    size = np.array([c["size"] for c in cars], dtype=float)
    return np.array(xs), np.array(ys), np.array(yaws), size[:, 0], size[:, 1]


def red_entries(cars, plan, times, states, judge_turns=True):
    """(entries, turning entries, entries against the signal): a car's front entering an
    intersection box (its carriageway between the outer edges of the crosswalks, from outside
    both streets' boxes) while it runs along the axis. A car whose heading has turned by more
    than 45 degrees when its front leaves the box again turns: it may enter only on its axis'
    left arrow (a right turn: on either street's arrow); a car going straight on enters on green
    or yellow only. judge_turns=False judges
    every entry as straight on (a negative control)."""
    xs, ys, yaws, lengths, _ = states
    fx = xs + 0.5 * lengths[:, None] * np.cos(yaws)
    fy = ys + 0.5 * lengths[:, None] * np.sin(yaws)
    entries = turns = bad = 0
    for inter in plan["intersections"]:
        dx, dy = fx - inter["x"], fy - inter["y"]
        if np.min(dx * dx + dy * dy) > 60.0 ** 2:
            continue
        boxes = []
        for axis in (0, 1):
            h = inter["heading"][axis]
            ux, uy = math.cos(h), math.sin(h)
            along = dx * ux + dy * uy
            across = ux * dy - uy * dx
            boxes.append((np.abs(along) < 0.5 * inter["width"][1 - axis] + plan["sidewalk"])
                         & (np.abs(across) < 0.5 * inter["width"][axis]))
        anywhere = boxes[0] | boxes[1]
        for axis in (0, 1):
            aligned = np.abs(np.cos(yaws - inter["heading"][axis])) > 0.9
            enter = boxes[axis][:, 1:] & ~anywhere[:, :-1] & aligned[:, 1:]
            car_i, k = np.nonzero(enter)
            if len(k) == 0:
                continue
            st = phase(plan, inter, axis, times[k + 1])
            cross = phase(plan, inter, 1 - axis, times[k + 1])
            for i, kk, s, c in zip(car_i, k + 1, st, cross):
                out = np.nonzero(~anywhere[i, kk:])[0]
                if not len(out) and cars[i]["trajectory"][-1][0] >= times[-1] - 1e-6:
                    continue  # still moving in the box when the span ends: the turn is unknown
                end = kk + out[0] if len(out) else len(times) - 1
                turned = yaws[i, end] - yaws[i, kk]
                turning = judge_turns and abs(turned) > 0.25 * math.pi
                entries += 1
                turns += turning
                if not turning:
                    bad += s in ("R", "L")
                elif turned > 0:  # left
                    bad += s != "L"
                else:  # right: on either street's arrow
                    bad += s != "L" and c != "L"
    return entries, turns, bad


def corners(x, y, yaw, length, width):
    """(..., 4, 2) corners of boxes."""
    c, s = np.cos(yaw), np.sin(yaw)
    out = []
    for a, b in ((1, 1), (1, -1), (-1, -1), (-1, 1)):
        out.append(np.stack([x + c * a * 0.5 * length - s * b * 0.5 * width,
                             y + s * a * 0.5 * length + c * b * 0.5 * width], axis=-1))
    return np.stack(out, axis=-2)


def sat_overlap(ca, cb, yaw_a, yaw_b):
    """Separating-axis test of rectangles given as corner arrays (M, 4, 2): True where they
    overlap (no separating axis among the four edge normals)."""
    separated = np.zeros(ca.shape[0], dtype=bool)
    for yaw in (yaw_a, yaw_b):
        for ang in (yaw, yaw + 0.5 * math.pi):
            ax = np.stack([np.cos(ang), np.sin(ang)], axis=-1)[:, None, :]
            pa = np.sum(ca * ax, axis=-1)
            pb = np.sum(cb * ax, axis=-1)
            separated |= (pa.max(axis=1) < pb.min(axis=1)) | (pb.max(axis=1) < pa.min(axis=1))
    return ~separated


def overlaps_and_gaps(cars, times, states, bounds):
    """(overlapping pair samples, same-lane follower samples, smallest bumper gap, smallest time
    gap of a follower moving faster than 3 m/s, both heading the same way within 6 degrees). Two
    cars inside the tile (`bounds`: lo, hi) follow each other in a lane when their headings agree
    and their centres are less than a metre apart across the heading (beyond the tile the loops
    of a street's two lanes widen across each other's line)."""
    xs, ys, yaws, lengths, widths = states
    lo, hi = bounds
    inside = (xs >= lo[0]) & (xs <= hi[0]) & (ys >= lo[1]) & (ys <= hi[1])
    n = len(cars)
    reach = 0.5 * np.hypot(lengths, widths)
    overl = follow = 0
    min_gap = min_tgap = float("inf")
    ii, jj = np.triu_indices(n, 1)
    lim = reach[ii] + reach[jj]
    for k in range(len(times)):
        d = np.hypot(xs[ii, k] - xs[jj, k], ys[ii, k] - ys[jj, k])
        near = d < lim
        if np.any(near):
            a, b = ii[near], jj[near]
            ca = corners(xs[a, k], ys[a, k], yaws[a, k], lengths[a], widths[a])
            cb = corners(xs[b, k], ys[b, k], yaws[b, k], lengths[b], widths[b])
            overl += int(np.sum(sat_overlap(ca, cb, yaws[a, k], yaws[b, k])))
        # Followers: same heading, within 40 m, less than a metre apart across the heading.
        f = (d < 40.0) & inside[ii, k] & inside[jj, k]
        if not np.any(f):
            continue
        a, b = ii[f], jj[f]
        ok = np.cos(yaws[a, k] - yaws[b, k]) > 0.95
        a, b = a[ok], b[ok]
        lat = np.abs(np.cos(yaws[a, k]) * (ys[b, k] - ys[a, k])
                     - np.sin(yaws[a, k]) * (xs[b, k] - xs[a, k]))
        a, b = a[lat < 1.0], b[lat < 1.0]
        if len(a) == 0:
            continue
        # Which one leads: the other's centre is ahead along the heading.
        hx, hy = np.cos(yaws[a, k]), np.sin(yaws[a, k])
        ahead = (xs[b, k] - xs[a, k]) * hx + (ys[b, k] - ys[a, k]) * hy
        lead = np.where(ahead > 0, b, a)
        back = np.where(ahead > 0, a, b)
        gap = np.abs(ahead) - 0.5 * (lengths[lead] + lengths[back])
        follow += len(gap)
        min_gap = min(min_gap, float(gap.min()))
        if k + 1 < len(times):
            v = np.hypot(xs[back, k + 1] - xs[back, k], ys[back, k + 1] - ys[back, k]) / DT
            # The time gap on straight lanes only: on a curve the chord is shorter than the lane.
            moving = (v > 3.0) & (np.cos(yaws[lead, k] - yaws[back, k]) > 0.995)
            if np.any(moving):
                min_tgap = min(min_tgap, float(np.min(gap[moving] / v[moving])))
    return overl, follow, min_gap, min_tgap


def crossings_off_red(peds, plan, times):
    """(samples of signal crossers on a signalised carriageway next to a node, of which the
    carriageway's axis was not red)."""
    checked = bad = 0
    for p in peds:
        if p["activity"] != "crossing":
            continue
        x, y, _ = sample(p["trajectory"], times)
        for inter in plan["intersections"]:
            dx, dy = x - inter["x"], y - inter["y"]
            if np.min(dx * dx + dy * dy) > 50.0 ** 2:
                continue
            for axis in (0, 1):
                h = inter["heading"][axis]
                ux, uy = math.cos(h), math.sin(h)
                along = dx * ux + dy * uy
                across = ux * dy - uy * dx
                half_other = 0.5 * inter["width"][1 - axis]
                on = ((np.abs(across) < 0.5 * inter["width"][axis])
                      & (np.abs(along) < half_other + plan["sidewalk"])
                      & (np.abs(along) > half_other))
                k = np.nonzero(on)[0]
                checked += len(k)
                bad += int(np.sum(phase(plan, inter, axis, times[k]) != "R"))
    return checked, bad


def path_at(lanes, path, s):
    """x, y of arc lengths s (clamped) along a car's path: its lane pieces (each given as x0, y0,
    x1, y1, ...) joined end to start."""
    p = np.concatenate([np.asarray(lanes[i]["points"], dtype=float).reshape(-1, 2)[(0 if k == 0 else 1):]
                        for k, i in enumerate(path)])
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
    return np.interp(s, cum, p[:, 0]), np.interp(s, cum, p[:, 1])


def sha_ok(path, ref):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest() == ref["sha256"]


def episode_cars(ref, sim, sim_path):
    """The episode (decoded JSON) and the traffic cars of a scenario that references a traffic
    episode file, as entities with a [t, x, y, z, yaw] trajectory over the scenario's window:
    the knots (t, s) along the lane of its path shifted by the offset, the yaw that of the chord
    from s - 1.5 m to s + 1.5 m."""
    path = os.path.join(os.path.dirname(sim_path), ref["file"])
    with open(path, "rb") as f:
        raw = f.read()
    check(sha_ok(path, ref), "sha256 of " + ref["file"])
    ep = json.loads(raw)
    check(ep["episode"] == ref["episode"], "episode index of " + ref["file"])
    t0, dur = ref["offset"], sim["duration"]
    check(0 <= t0 and t0 + dur <= ep["length"], "window within the episode",
          "%.3f + %.3f > %.3f" % (t0, dur, ep["length"]))
    check(len(ref["cars"]) == len(ep["cars"]), "one id per episode car")
    out = []
    for cid, car in zip(ref["cars"], ep["cars"]):
        k = np.asarray(car["knots"], dtype=float).reshape(-1, 2)
        # The knots of the window and one on each side of it.
        a = max(0, int(np.searchsorted(k[:, 0], t0, side="right")) - 1)
        b = min(len(k), int(np.searchsorted(k[:, 0], t0 + dur, side="left")) + 1)
        k = k[a:b]
        lanes, path = ep["lanes"], car["path"]
        for a_, b_ in zip(path, path[1:]):
            check(lanes[a_]["points"][-2:] == lanes[b_]["points"][:2], "a path's pieces join")
        x, y = path_at(lanes, path, k[:, 1])
        xa, ya = path_at(lanes, path, k[:, 1] - 1.5)
        xb, yb = path_at(lanes, path, k[:, 1] + 1.5)
        yaw = np.arctan2(yb - ya, xb - xa)
        traj = [[t - t0, xi, yi, 0.0, w] for t, xi, yi, w in zip(k[:, 0], x, y, yaw)]
        out.append({"id": cid, "class": "car", "role": "traffic", "size": car["size"],
                    "attributes": {"lane": ep["lanes"][car["path"][0]]["name"]},
                    "pose": {"x": x[0], "y": y[0], "z": 0.0, "yaw": yaw[0]},
                    "trajectory": traj})
    return ep, out


def episode_pedestrians(ref, ep, sim):
    """The crowd of a scenario that references a traffic episode: each pedestrian's keyframes
    (t, x, y, yaw) around the window, shifted by the offset; a queuing one stands at its pose."""
    t0, dur = ref["offset"], sim["duration"]
    check(len(ref["pedestrians"]) == len(ep["pedestrians"]), "one id per episode pedestrian")
    out = []
    for pid, p in zip(ref["pedestrians"], ep["pedestrians"]):
        k = np.asarray(p["keyframes"], dtype=float).reshape(-1, 4)
        pose = {"x": p["pose"][0], "y": p["pose"][1], "z": 0.0, "yaw": p["pose"][2]}
        traj = []
        if len(k):
            check(k[0, 0] == 0.0 and k[-1, 0] >= ep["length"] and np.all(np.diff(k[:, 0]) > 0),
                  "keyframes from 0 to the episode's end, t increasing")
            a = max(0, int(np.searchsorted(k[:, 0], t0, side="right")) - 1)
            b = min(len(k), int(np.searchsorted(k[:, 0], t0 + dur, side="left")) + 1)
            traj = [[t - t0, x, y, 0.0, w] for t, x, y, w in k[a:b]]
            x0, y0, _ = sample(traj, np.array([0.0]))
            pose = {"x": float(x0[0]), "y": float(y0[0]), "z": 0.0, "yaw": traj[0][4]}
        out.append({"id": pid, "class": "pedestrian", "role": "pedestrian",
                    "size": [0.5, 0.6, p["height"]],
                    "attributes": {"activity": p["activity"],
                                   "clothing_color": p["clothing_color"]},
                    "pose": pose, "trajectory": traj})
    return out


def load(d):
    out = []
    for path in sorted(glob.glob(os.path.join(d, "**", "sim_config.json"), recursive=True)):
        with open(path) as f:
            sim = json.load(f)
        if "traffic" in sim:
            ep, cars = episode_cars(sim["traffic"], sim, path)
            sim["entities"] += episode_pedestrians(sim["traffic"], ep, sim) + cars
        out.append(sim)
    return out


def entities(sim, role):
    res = []
    for e in sim["entities"]:
        if e["role"] != role:
            continue
        res.append({"id": e["id"], "size": e["size"], "trajectory": e["trajectory"],
                    "lane": e.get("attributes", {}).get("lane", ""),
                    "activity": e.get("attributes", {}).get("activity", ""),
                    "pose": e["pose"]})
    return res


def judge_mission_cars(sim, name, controls):
    """(cars, entries, entries against the signal) of the mission's own moving cars (every role
    but traffic: the targets, a hostile vehicle), judged like the traffic over the time limit;
    the control: the plan shifted by half a cycle flags some of their entries."""
    cars = [{"id": e["id"], "size": e["size"], "trajectory": e["trajectory"]}
            for e in sim["entities"]
            if e["class"] == "car" and e["role"] != "traffic" and e.get("trajectory")]
    if not cars:
        return 0, 0, 0
    plan = sim["signals"]
    times = np.arange(0.0, sim["duration"] + 1e-9, DT)
    states = car_states(cars, times)
    entries, _, bad = red_entries(cars, plan, times, states)
    check(bad == 0, name + ": the mission's cars enter only on their signal",
          "%d entries, %d against the signal" % (entries, bad))
    if controls and entries > 0:
        cyc = 2 * (plan["left"] + plan["green"] + plan["yellow"] + plan["all_red"])
        shifted = dict(plan)
        shifted["intersections"] = [dict(i, offset=(i["offset"] + 0.5 * cyc) % cyc)
                                    for i in plan["intersections"]]
        e2, _, bad2 = red_entries(cars, shifted, times, states)
        check(bad2 > 0, "control: shifted plan flags a mission car", "%d of %d" % (bad2, e2))
    return len(cars), entries, bad


def judge_scenario(sim, world, name, controls):
    plan = sim["signals"]
    dur = sim["duration"]
    times = np.arange(0.0, dur + 1e-9, DT)
    cars = entities(sim, "traffic")
    peds = entities(sim, "pedestrian")
    states = car_states(cars, times)
    check(len(cars) >= 100 and len(peds) >= 300, name + ": cars and pedestrians",
          "%d, %d" % (len(cars), len(peds)))

    entries, turns, bad = red_entries(cars, plan, times, states)
    check(entries > 300 and bad == 0, name + ": no car enters against its signal",
          "%d entries, %d on red" % (entries, bad))
    check(turns > 20, name + ": cars turn at the intersections", "%d turning entries" % turns)
    bounds = (world["bounds"]["min"], world["bounds"]["max"])
    overl, follow, min_gap, min_tgap = overlaps_and_gaps(cars, times, states, bounds)
    check(overl == 0, name + ": no two cars overlap", "%d overlapping samples" % overl)
    check(follow > 1000, name + ": same-lane followers sampled", str(follow))
    # The standstill gap is 2 m; the written keyframes keep positions within 5 cm of the
    # simulated ones (two cars: 10 cm), and numbers are rounded to 1 mm.
    check(min_gap >= 2.0 - 0.11, name + ": bumper gap >= the standstill gap", "%.3f" % min_gap)
    check(min_tgap >= 1.0, name + ": time gap of moving followers >= 1 s", "%.3f" % min_tgap)
    checked, off = crossings_off_red(peds, plan, times)
    check(checked > 200 and off == 0, name + ": crossers on a carriageway only while it is red",
          "%d samples, %d off red" % (checked, off))

    lo, hi = world["bounds"]["min"], world["bounds"]["max"]
    km2 = (hi[0] - lo[0]) * (hi[1] - lo[1]) / 1e6
    xs, ys = states[0], states[1]
    inside = (xs >= lo[0]) & (xs <= hi[0]) & (ys >= lo[1]) & (ys <= hi[1])
    step = int(round(1.0 / DT))
    moved = np.hypot(xs[:, step:] - xs[:, :-step], ys[:, step:] - ys[:, :-step]) > 0.5
    moving = np.sum(inside[:, :-step] & moved, axis=0) / km2
    check(moving.mean() >= 100.0, name + ": >= 100 moving cars per km^2 (mean)",
          "%.1f" % moving.mean())
    ped_in = np.zeros(len(times))
    for p in peds:
        if p["trajectory"]:
            x, y, _ = sample(p["trajectory"], times)
        else:
            x = np.full(len(times), p["pose"]["x"])
            y = np.full(len(times), p["pose"]["y"])
        ped_in += (x >= lo[0]) & (x <= hi[0]) & (y >= lo[1]) & (y <= hi[1])
    check(ped_in.min() / km2 >= 300.0, name + ": >= 300 pedestrians per km^2 (min)",
          "%.1f" % (ped_in.min() / km2))

    if controls:
        # The plan shifted by half a cycle: the same cars now enter on red.
        shifted = dict(plan)
        cyc = 2 * (plan["left"] + plan["green"] + plan["yellow"] + plan["all_red"])
        shifted["intersections"] = [dict(i, offset=(i["offset"] + 0.5 * cyc) % cyc)
                                    for i in plan["intersections"]]
        e2, _, bad2 = red_entries(cars, shifted, times, states)
        check(bad2 > e2 // 4, "control: shifted plan flags red entries", "%d of %d" % (bad2, e2))
        # Turning cars judged as going straight on: their entries on the arrow are flagged.
        _, t3, bad3 = red_entries(cars, plan, times, states, judge_turns=False)
        check(t3 == 0 and bad3 >= turns, "control: turns on the arrow flagged as straight",
              "%d of %d turns" % (bad3, turns))
        # The plan shifted by the arrow's length: the turning cars now enter on green.
        early = dict(plan)
        early["intersections"] = [dict(i, offset=(i["offset"] - plan["left"]) % cyc)
                                  for i in plan["intersections"]]
        _, t4, bad4 = red_entries(cars, early, times, states)
        check(t4 == turns and bad4 >= turns, "control: a turn off the arrow is flagged",
              "%d flagged, %d turns" % (bad4, turns))
        c2, off2 = crossings_off_red(peds, shifted, times)
        check(off2 > 0, "control: shifted plan flags crossers", "%d of %d" % (off2, c2))
        # One car three seconds late: the car behind runs into it.
        late = [dict(c) for c in cars]
        tr = [[p[0] + 3.0] + p[1:] for p in late[0]["trajectory"]]
        late[0]["trajectory"] = [[0.0] + tr[0][1:]] + tr
        short = times[times <= 120.0]  # the controls' overlap checks: the first two minutes
        o2, _, _, _ = overlaps_and_gaps(late, short, car_states(late, short), bounds)
        check(o2 > 0, "control: a late car overlaps", str(o2))
        # A car added 0.8 s behind another, in its lane: too close.
        lo, hi = bounds
        lead = next(c for c in cars if lo[0] + 50 < c["trajectory"][0][1] < hi[0] - 50
                    and lo[1] + 50 < c["trajectory"][0][2] < hi[1] - 50)
        tail = dict(lead)
        tr = [[p[0] + 0.8] + p[1:] for p in lead["trajectory"]]
        tail["trajectory"] = [[0.0] + tr[0][1:]] + tr
        close = cars + [tail]
        _, _, g3, tg3 = overlaps_and_gaps(close, short, car_states(close, short), bounds)
        check(g3 < 2.0 - 0.11 or tg3 < 1.0, "control: a car 0.8 s behind another breaks the gap",
              "%.3f m %.3f s" % (g3, tg3))
    return (len(cars), len(peds), entries, turns, follow, min_gap, min_tgap, checked,
            moving.mean(), ped_in.min() / km2)


def main():
    with tempfile.TemporaryDirectory(prefix="hameritt_traffic_") as tmp:
        world_path = os.path.join(tmp, "world.json")
        r = run("hameritt_world", "--world", "city", "--out", world_path)
        check(r.returncode == 0, "hameritt_world --world city", r.stderr)
        with open(world_path) as f:
            world = json.load(f)
        d = os.path.join(tmp, "batch")
        r = run("hameritt_generate", "--world", "city", "--class", "area_search,route_search",
                "--count", "2", "--seed", "11", "--out", d, "--quiet")
        check(r.returncode == 0, "generate --world city", r.stderr)
        sims = load(d)
        check(len(sims) == 2, "scenarios written", str(len(sims)))
        check(all("traffic" in s for s in sims), "a batch references its traffic episodes")
        episodes = sorted(glob.glob(os.path.join(d, "traffic_episode_*.json")))
        check(1 <= len(episodes) <= 2, "one episode file per episode used", str(episodes))
        for path in episodes:
            with open(path) as f:
                ep = json.load(f)
            car_min = len(ep["cars"]) * ep["length"] / 60.0
            knots = sum(len(c["knots"]) // 2 for c in ep["cars"])
            frames = sum(len(p["keyframes"]) // 4 for p in ep["pedestrians"])
            check(len(ep["pedestrians"]) >= 300, "episode pedestrians", str(len(ep["pedestrians"])))
            print("%s: %d bytes, %d cars, %d knots, %.0f bytes per car-minute, "
                  "%d pedestrians, %d keyframes"
                  % (os.path.basename(path), os.path.getsize(path), len(ep["cars"]), knots,
                     os.path.getsize(path) / car_min, len(ep["pedestrians"]), frames))
        for path in sorted(glob.glob(os.path.join(d, "*", "sim_config.json"))):
            print("%s: %d bytes" % (os.path.relpath(path, d), os.path.getsize(path)))

        # A changed episode file: this judge and hameritt_validate both refuse it.
        victim = sorted(glob.glob(os.path.join(d, "*", "sim_config.json")))[0]
        with open(victim) as f:
            ref = json.load(f)["traffic"]
        ep_path = os.path.join(os.path.dirname(victim), ref["file"])
        with open(ep_path, "rb") as f:
            good = f.read()
        r = run("hameritt_validate", victim)
        check(r.returncode == 0, "hameritt_validate accepts the reference", r.stderr)
        bad = bytearray(good)
        bad[len(bad) // 2] = ord("1") if bad[len(bad) // 2] != ord("1") else ord("2")
        with open(ep_path, "wb") as f:
            f.write(bytes(bad))
        check(not sha_ok(ep_path, ref), "control: the judge flags a changed episode file")
        r = run("hameritt_validate", victim)
        check(r.returncode == 2 and "traffic_episode" in r.stderr and "traffic.sha256" in r.stderr,
              "hameritt_validate refuses a changed episode file", r.stderr)
        with open(ep_path, "wb") as f:
            f.write(good)
        params = world["params"]["city"] if "city" in world["params"] else {}
        pj = params.get("jaywalk_probability", 0.15)
        crossers = jay = queuing = far = 0
        stops = [(e["pose"]["x"], e["pose"]["y"]) for e in world["entities"]
                 if e["class"] == "bus_stop"]
        mission_cars = mission_entries = 0
        for i, sim in enumerate(sims):
            check(sim["world"]["params"].get("type") == "city", "scenario %d is a city scenario" % i)
            n_own, e_own, _ = judge_mission_cars(sim, "scenario %d" % i, controls=True)
            mission_cars += n_own
            mission_entries += e_own
            figures = judge_scenario(sim, world, "scenario %d" % i, controls=(i == 0))
            print("scenario %d: %d cars, %d pedestrians, %d box entries (%d turning), %d follower samples "
                  "(smallest gap %.3f m, time gap %.3f s), %d crosswalk samples, %.1f moving "
                  "cars/km^2 (mean), %.1f pedestrians/km^2 (min)"
                  % ((i,) + figures))
            for p in entities(sim, "pedestrian"):
                if p["activity"] in ("crossing", "jaywalking"):
                    crossers += 1
                    jay += p["activity"] == "jaywalking"
                if p["activity"] == "queuing":
                    queuing += 1
                    check(not p["trajectory"], "a queuing pedestrian stands")
                    best = min(math.hypot(p["pose"]["x"] - x, p["pose"]["y"] - y) for x, y in stops)
                    far += best > 8.5
        check(mission_cars > 0 and mission_entries > 0, "the route search's targets are judged",
              "%d cars, %d entries" % (mission_cars, mission_entries))
        print("mission cars %d, box entries %d, all on their signal" % (mission_cars,
                                                                      mission_entries))
        share = jay / max(crossers, 1)
        sigma = math.sqrt(pj * (1 - pj) / max(crossers, 1))
        check(crossers > 100, "crossers", str(crossers))
        check(abs(share - pj) <= 3 * sigma, "jaywalk share within 3 sigma",
              "%.3f vs %.3f (3 sigma %.3f)" % (share, pj, 3 * sigma))
        p2 = 2 * pj
        check(abs(share - p2) > 3 * math.sqrt(p2 * (1 - p2) / max(crossers, 1)),
              "control: a doubled probability is rejected")
        check(queuing > 0 and far == 0, "pedestrians queue at bus stops",
              "%d queuing, %d far from a stop" % (queuing, far))
        print("crossers %d, jaywalking %d (share %.3f, p %.2f, 3 sigma %.3f), queuing %d"
              % (crossers, jay, share, pj, 3 * sigma, queuing))

        # A cycle set in world.json is the one written; out of range exits 2, nothing written.
        with open(os.path.join(SRC, "config", "world.json")) as f:
            base = json.load(f)
        cfg = os.path.join(tmp, "world_cycle.json")
        with open(cfg, "w") as f:
            json.dump(dict(base, type="city", city={"signal_green": 20.0, "signal_yellow": 3.0,
                                                    "signal_left": 0.0}), f)
        d2 = os.path.join(tmp, "cycle")
        r = run("hameritt_generate", "--world-config", cfg, "--class", "pursuit", "--count", "1",
                "--seed", "3", "--out", d2, "--quiet")
        check(r.returncode == 0, "generate with a custom cycle", r.stderr)
        s2 = load(d2)
        if s2:
            sg = s2[0]["signals"]
            check((sg["green"], sg["yellow"], sg["left"], sg["cycle"]) == (20.0, 3.0, 0.0, 50.0),
                  "the configured cycle is written", json.dumps(sg)[:200])
        for key, value, msg in (("signal_green", 90.0, "expected 5 to 60, got 90"),
                                ("signal_yellow", 2.0, "expected 3 to 6, got 2"),
                                ("signal_left", -1.0, "expected 0 to 20, got -1"),
                                ("jaywalk_probability", 1.5, "expected 0 to 1, got 1.5"),
                                ("traffic_episodes", 65.0, "expected 1 to 64, got 65"),
                                ("traffic_episodes", 2.5, "expected an integer from 1 to 64")):
            with open(cfg, "w") as f:
                json.dump(dict(base, type="city", city={key: value}), f)
            out = os.path.join(tmp, "never")
            r = run("hameritt_generate", "--world-config", cfg, "--class", "all", "--count", "1",
                    "--seed", "1", "--out", out)
            check(r.returncode == 2 and ("world.city.%s: %s" % (key, msg)) in r.stderr,
                  "%s out of range exits 2 naming the key and range" % key, r.stderr)
            check(not os.path.exists(out), "nothing written for a bad " + key)
    print(counts.summary())
    return 1 if counts.failed else 0


if __name__ == "__main__":
    sys.exit(main())
