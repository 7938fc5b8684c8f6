#!/usr/bin/python3
"""Outside-judge re-verification of the semantics of generated scenarios (stdlib only).

Runs $HAMERITT_BIN_DIR/hameritt_generate for a batch of every class, then recomputes from the
JSON files alone (no project code) what the documents claim:
  1. every scene relation (operator semantics, EVENTUALLY_* first grid time, evidence numbers,
     related entity class/attributes, PART_OF group membership and block geometry);
  2. area_search: targets inside aoi_1, priors normalised, tiling their AOI, peaked on the target;
  3. route_search: targets stay in the route band, access-denial KOZ windows match the target;
  4. pursuit: target starts in aoi_1, aoi_1 nlt == departure time, vignette EVENTUALLY_NEXT_TO;
  5. confusers look like a target and are told apart from it;
  6. general: unique ids, UAV start outside KOZs, increasing trajectories, fingerprint, manifest,
     scenario ids.
Finally it mutates copies of generated documents and checks that each mutation is detected.
Prints one line per failure and a final "N passed, M failed"; exits 1 on any failure or when
fewer than MIN_CHECKS checks ran.

Conventions (ENU metres, yaw CCW from +x): an entity box is pose (x, y, z = bottom, yaw) and size
[length along yaw, width, height]. Two conventions beyond the test brief, as documented in
src/scenario/relations.cpp: line of sight to a street or driveway is always true (surfaces are
never occluded), and line of sight is only evaluated (else false) within the relation radius.
"""

import bisect
import copy
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

MIN_CHECKS = 1000
EVIDENCE_TOL = 2e-3
# Slack for band containment: none. Targets start well inside their band, not on its edge.
ROUND_EPS = 0.0
SURFACES = ("street", "driveway", "parking_lot", "alley")
DIRECTIONAL = {"LEFT_OF": (90.0,), "IN_FRONT_OF": (180.0,), "RIGHT_OF": (270.0,),
               "ORTHOGONAL_TO": (90.0, 270.0)}
BASE_OPS = ("NEXT_TO", "NOT_NEXT_TO", "ON_TOP_OF", "NOT_ON_TOP_OF", "LEFT_OF", "RIGHT_OF",
            "IN_FRONT_OF", "ORTHOGONAL_TO")


# ----------------------------------------------------------------------------------------------
# Check bookkeeping


class Checker:
    def __init__(self, quiet=False):
        self.passed = 0
        self.failed = 0
        self.quiet = quiet
        self.categories = set()  # categories of failed checks
        self.messages = []

    def check(self, cond, category, where, what):
        if cond:
            self.passed += 1
            return True
        self.failed += 1
        self.categories.add(category)
        msg = "FAIL [%s] %s: %s" % (category, where, what)
        self.messages.append(msg)
        if not self.quiet:
            print(msg)
        return False


# ----------------------------------------------------------------------------------------------
# Geometry


def wrap_pi(a):
    r = math.fmod(a + math.pi, 2.0 * math.pi)
    if r < 0:
        r += 2.0 * math.pi
    return r - math.pi


def wrap360(d):
    r = math.fmod(d, 360.0)
    if r < 0:
        r += 360.0
    if r >= 360.0:
        r = 0.0
    return r


def ang_diff(a, b):
    return abs(math.remainder(a - b, 360.0))


class Box:
    """Oriented box: footprint centre (x, y), bottom z, yaw, size (l, w, h)."""
    __slots__ = ("x", "y", "z", "yaw", "l", "w", "h", "c", "s", "zc", "ztop", "corners",
                 "minx", "maxx", "miny", "maxy", "tol")

    def __init__(self, x, y, z, yaw, l, w, h):
        self.x, self.y, self.z, self.yaw = float(x), float(y), float(z), float(yaw)
        self.l, self.w, self.h = abs(float(l)), abs(float(w)), abs(float(h))
        self.c = math.cos(self.yaw)
        self.s = math.sin(self.yaw)
        self.zc = self.z + 0.5 * self.h
        self.ztop = self.z + self.h
        hl, hw = 0.5 * self.l, 0.5 * self.w
        self.corners = [(self.x + dx * self.c - dy * self.s, self.y + dx * self.s + dy * self.c)
                        for dx, dy in ((hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw))]
        xs = [p[0] for p in self.corners]
        ys = [p[1] for p in self.corners]
        self.minx, self.maxx, self.miny, self.maxy = min(xs), max(xs), min(ys), max(ys)
        self.tol = 1e-9 * max(1.0, abs(self.x), abs(self.y), abs(self.zc), self.l, self.w, self.h)

    def centre(self):
        return (self.x, self.y, self.zc)

    def body2(self, px, py):
        dx, dy = px - self.x, py - self.y
        return (dx * self.c + dy * self.s, -dx * self.s + dy * self.c)

    def footprint_contains(self, px, py, eps=1e-9):
        bx, by = self.body2(px, py)
        return abs(bx) <= 0.5 * self.l + eps and abs(by) <= 0.5 * self.w + eps

    def hits_segment(self, a, b):
        """3D segment a-b touches the (closed, slightly padded) box."""
        ax, ay = self.body2(a[0], a[1])
        bx, by = self.body2(b[0], b[1])
        p = (ax, ay, a[2] - self.zc)
        d = (bx - ax, by - ay, b[2] - a[2])
        half = (0.5 * self.l + self.tol, 0.5 * self.w + self.tol, 0.5 * self.h + self.tol)
        t0, t1 = 0.0, 1.0
        for k in range(3):
            if d[k] == 0.0:
                if p[k] < -half[k] or p[k] > half[k]:
                    return False
                continue
            e = (-half[k] - p[k]) / d[k]
            f = (half[k] - p[k]) / d[k]
            if e > f:
                e, f = f, e
            if e > t0:
                t0 = e
            if f < t1:
                t1 = f
            if t0 > t1:
                return False
        return True


def box_of(pose, size):
    return Box(pose["x"], pose["y"], pose["z"], pose["yaw"], size[0], size[1], size[2])


def seg_point_dist(px, py, ax, ay, bx, by):
    dx, dy = bx - ax, by - ay
    L2 = dx * dx + dy * dy
    u = 0.0 if L2 == 0 else max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / L2))
    qx, qy = ax + u * dx - px, ay + u * dy - py
    return math.hypot(qx, qy)


def convex_overlap(pa, pb):
    """Separating-axis test of two convex polygons (closed: touching counts as overlap)."""
    for poly in (pa, pb):
        n = len(poly)
        for i in range(n):
            x1, y1 = poly[i]
            x2, y2 = poly[(i + 1) % n]
            ax, ay = -(y2 - y1), x2 - x1
            amin = min(ax * x + ay * y for x, y in pa)
            amax = max(ax * x + ay * y for x, y in pa)
            bmin = min(ax * x + ay * y for x, y in pb)
            bmax = max(ax * x + ay * y for x, y in pb)
            if amax < bmin or bmax < amin:
                return False
    return True


def footprint_distance(a, b):
    if convex_overlap(a.corners, b.corners):
        return 0.0
    best = float("inf")
    for p, q in ((a.corners, b.corners), (b.corners, a.corners)):
        for px, py in p:
            for i in range(4):
                x1, y1 = q[i]
                x2, y2 = q[(i + 1) % 4]
                d = seg_point_dist(px, py, x1, y1, x2, y2)
                if d < best:
                    best = d
    return best


def poly_area(poly):
    a = 0.0
    n = len(poly)
    for i in range(n):
        x1, y1 = poly[i]
        x2, y2 = poly[(i + 1) % n]
        a += x1 * y2 - x2 * y1
    return abs(a) * 0.5


def point_in_poly(px, py, poly, eps=1e-9):
    """Closed point-in-polygon: points within eps of an edge count as inside."""
    n = len(poly)
    inside = False
    for i in range(n):
        x1, y1 = poly[i]
        x2, y2 = poly[(i + 1) % n]
        if seg_point_dist(px, py, x1, y1, x2, y2) <= eps:
            return True
        if (y1 > py) != (y2 > py):
            xi = x1 + (py - y1) * (x2 - x1) / (y2 - y1)
            if px < xi:
                inside = not inside
    return inside


def orient(ax, ay, bx, by, cx, cy):
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


def segs_intersect(a, b, c, d):
    d1 = orient(c[0], c[1], d[0], d[1], a[0], a[1])
    d2 = orient(c[0], c[1], d[0], d[1], b[0], b[1])
    d3 = orient(a[0], a[1], b[0], b[1], c[0], c[1])
    d4 = orient(a[0], a[1], b[0], b[1], d[0], d[1])
    if ((d1 > 0 and d2 < 0) or (d1 < 0 and d2 > 0)) and ((d3 > 0 and d4 < 0) or (d3 < 0 and d4 > 0)):
        return True
    for p, q, r in ((c, d, a), (c, d, b), (a, b, c), (a, b, d)):
        if seg_point_dist(r[0], r[1], p[0], p[1], q[0], q[1]) <= 1e-12:
            return True
    return False


def polys_intersect(pa, pb):
    """General (possibly non-convex) closed polygons share a point."""
    if point_in_poly(pa[0][0], pa[0][1], pb) or point_in_poly(pb[0][0], pb[0][1], pa):
        return True
    for i in range(len(pa)):
        a, b = pa[i], pa[(i + 1) % len(pa)]
        for j in range(len(pb)):
            if segs_intersect(a, b, pb[j], pb[(j + 1) % len(pb)]):
                return True
    return False


# ----------------------------------------------------------------------------------------------
# Trajectories


class Traj:
    def __init__(self, pts):
        self.pts = pts
        self.times = [p[0] for p in pts]

    def at(self, t):
        pts = self.pts
        if t <= self.times[0]:
            return tuple(pts[0][1:5])
        if t >= self.times[-1]:
            return tuple(pts[-1][1:5])
        i = bisect.bisect_right(self.times, t)
        a, b = pts[i - 1], pts[i]
        span = b[0] - a[0]
        u = (t - a[0]) / span if span > 0 else 1.0
        return (a[1] + u * (b[1] - a[1]), a[2] + u * (b[2] - a[2]), a[3] + u * (b[3] - a[3]),
                wrap_pi(a[4] + u * wrap_pi(b[4] - a[4])))


# ----------------------------------------------------------------------------------------------
# Entities and the occluder index


class Ent:
    """A world or scenario entity: id, class, attributes, base box, optional trajectory."""

    def __init__(self, d, world):
        self.id = d["id"]
        self.cls = d["class"]
        self.attrs = d.get("attributes", {})
        self.role = d.get("role")
        self.world = world
        self.size = d["size"]
        self.box0 = box_of(d["pose"], d["size"])
        tr = d.get("trajectory") or []
        self.traj = Traj(tr) if tr else None
        self._cache = {}

    @property
    def moving(self):
        return self.traj is not None

    def box(self, t):
        if self.traj is None:
            return self.box0
        b = self._cache.get(t)
        if b is None:
            x, y, z, yaw = self.traj.at(t)
            b = Box(x, y, z, yaw, self.size[0], self.size[1], self.size[2])
            if len(self._cache) > 20000:
                self._cache.clear()
            self._cache[t] = b
        return b


def occluder_boxes(e):
    if e.cls in SURFACES:
        return []
    b = e.box0
    if e.cls in ("tree", "street_tree"):
        h = b.h
        return [Box(b.x, b.y, b.z, b.yaw, 0.4, 0.4, h / 3.0),
                Box(b.x, b.y, b.z + h / 3.0, b.yaw, b.l, b.w, h * 2.0 / 3.0)]
    return [b]


class OccluderGrid:
    CELL = 16.0

    def __init__(self, ents):
        self.boxes = []
        self.owner = []
        self.cells = {}
        for e in ents:
            for b in occluder_boxes(e):
                k = len(self.boxes)
                self.boxes.append(b)
                self.owner.append(e.id)
                for ix in range(int(math.floor(b.minx / self.CELL)), int(math.floor(b.maxx / self.CELL)) + 1):
                    for iy in range(int(math.floor(b.miny / self.CELL)), int(math.floor(b.maxy / self.CELL)) + 1):
                        self.cells.setdefault((ix, iy), []).append(k)

    def blocked(self, a, b, ignore):
        minx, maxx = min(a[0], b[0]), max(a[0], b[0])
        miny, maxy = min(a[1], b[1]), max(a[1], b[1])
        seen = set()
        C = self.CELL
        for ix in range(int(math.floor((minx - 0.01) / C)), int(math.floor((maxx + 0.01) / C)) + 1):
            for iy in range(int(math.floor((miny - 0.01) / C)), int(math.floor((maxy + 0.01) / C)) + 1):
                for k in self.cells.get((ix, iy), ()):
                    if k in seen:
                        continue
                    seen.add(k)
                    bx = self.boxes[k]
                    if bx.maxx < minx - 0.01 or bx.minx > maxx + 0.01 or bx.maxy < miny - 0.01 or bx.miny > maxy + 0.01:
                        continue
                    if self.owner[k] in ignore:
                        continue
                    if bx.hits_segment(a, b):
                        return True
        return False


def attrs_key(cls, attrs):
    return cls + "|" + json.dumps(attrs, sort_keys=True)


class WorldCtx:
    def __init__(self, world_doc, cfg):
        self.doc = world_doc
        self.cfg = cfg
        self.ents = [Ent(d, True) for d in world_doc["entities"]]
        self.by_id = {}
        self.dup_ids = []
        for e in self.ents:
            if e.id in self.by_id:
                self.dup_ids.append(e.id)
            self.by_id[e.id] = e
        self.occ = OccluderGrid(self.ents)
        self.by_look = {}
        for e in self.ents:
            self.by_look.setdefault(attrs_key(e.cls, e.attrs), []).append(e)
        self.blocks = {b["name"]: b["outline"] for b in world_doc.get("blocks", [])}


# ----------------------------------------------------------------------------------------------
# Relations


class Facts:
    __slots__ = ("distance", "bearing", "dz", "los", "over")


class Scene:
    """A scenario over the shared world: lookups, occluders, relation measurements."""

    def __init__(self, wctx, mission, sim):
        self.w = wctx
        self.cfg = wctx.cfg
        self.mission = mission
        self.sim = sim
        self.ents = [Ent(d, False) for d in sim.get("entities", [])]
        self.by_id = {e.id: e for e in self.ents}
        self.static_occ = [(e.id, b) for e in self.ents if not e.moving for b in [e.box0]]
        self.groups = {g["id"]: g for g in sim.get("groups", [])}

    def lookup(self, eid):
        e = self.by_id.get(eid)
        if e is not None:
            return e
        return self.w.by_id.get(eid)

    def line_of_sight(self, ta, ba, tb, bb):
        a, b = ba.centre(), bb.centre()
        ignore = (ta.id, tb.id)
        if self.w.occ.blocked(a, b, ignore):
            return False
        for oid, ob in self.static_occ:
            if oid in ignore:
                continue
            if ob.maxx < min(a[0], b[0]) - 0.01 or ob.minx > max(a[0], b[0]) + 0.01:
                continue
            if ob.maxy < min(a[1], b[1]) - 0.01 or ob.miny > max(a[1], b[1]) + 0.01:
                continue
            if ob.hits_segment(a, b):
                return False
        return True

    def measure(self, target, tbox, related, rbox, need_los=True):
        f = Facts()
        f.distance = footprint_distance(tbox, rbox)
        ang = math.degrees(math.atan2(rbox.y - tbox.y, rbox.x - tbox.x) - tbox.yaw)
        f.bearing = wrap360(ang)
        f.dz = tbox.z - rbox.ztop
        f.over = rbox.footprint_contains(tbox.x, tbox.y)
        if related.cls in SURFACES:
            f.los = True
        elif f.distance <= self.cfg["radius"] and need_los:
            f.los = self.line_of_sight(target, tbox, related, rbox)
        else:
            f.los = False
        return f

    def holds(self, op, f, rcls):
        if not applies(op, rcls):
            return False
        cfg = self.cfg
        near = f.distance <= cfg["radius"]
        nxt = f.distance < cfg["next_to_distance"] and f.los
        on_top = f.over and abs(f.dz) <= cfg["on_top_tolerance"]
        tol = cfg["bearing_tolerance_deg"]
        if op == "NEXT_TO":
            return nxt
        if op == "NOT_NEXT_TO":
            return near and not nxt
        if op == "ON_TOP_OF":
            return on_top
        if op == "NOT_ON_TOP_OF":
            return near and not on_top
        if op in DIRECTIONAL:
            return near and f.los and any(ang_diff(f.bearing, n) <= tol for n in DIRECTIONAL[op])
        return False

    def op_at(self, op, target, related, t):
        tb, rb = target.box(t), related.box(t)
        f = self.measure(target, tb, related, rb)
        return self.holds(op, f, related.cls), f


def applies(op, rcls):
    surface = rcls in SURFACES
    if op in ("ON_TOP_OF", "NOT_ON_TOP_OF"):
        return surface
    if op in ("NEXT_TO", "NOT_NEXT_TO"):
        return not surface
    if op in DIRECTIONAL:
        return not surface and rcls != "fence"
    return False


def split_op(op):
    if op.startswith("EVENTUALLY_"):
        return True, op[len("EVENTUALLY_"):]
    return False, op


def relation_text(r):
    # Entities are named by class (as in the paper), abstract groups by their id.
    related = r["related"]["id"] if r["operator"] == "PART_OF" else r["related"]["class"]
    s = "[%s] [%s] [%s]" % (related, r["operator"], r["target"])
    attrs = r["related"].get("attributes", {})
    if attrs:
        s += " [" + ", ".join("%s: %s" % (k, v) for k, v in attrs.items()) + "]"
    return s


def grid_times(dt, end):
    k = 0
    while k * dt <= end + 1e-9:
        yield k, k * dt
        k += 1


# ----------------------------------------------------------------------------------------------
# Per-scenario checks


def check_relations(sc, ck, sid):
    cfg = sc.cfg
    dt = cfg["eventually_dt"]
    for n, r in enumerate(sc.mission.get("scene_relations", [])):
        where = "%s relation %d (%s)" % (sid, n, r.get("text", r.get("operator")))
        op_full = r["operator"]
        ev, op = split_op(op_full)
        rel = r["related"]
        ck.check(r.get("text") == relation_text(r), "relation", where, "text %r != %r" % (r.get("text"), relation_text(r)))
        target = sc.by_id.get(r["target"])
        if not ck.check(target is not None, "relation", where, "target %s is not a scenario entity" % r["target"]):
            continue
        evidence = r.get("evidence", {})
        if op == "PART_OF":
            g = sc.groups.get(rel["id"])
            if not ck.check(g is not None, "relation", where, "no group %s" % rel["id"]):
                continue
            ck.check(not ev, "relation", where, "EVENTUALLY_PART_OF is not an operator")
            ck.check(rel["class"] == "group" and rel.get("attributes") == {"kind": g["kind"]},
                     "relation", where, "related %s/%s does not describe group kind %s" % (rel["class"], rel.get("attributes"), g["kind"]))
            ck.check(r["target"] in g["members"], "relation", where, "%s not a member of %s %s" % (r["target"], g["id"], g["members"]))
            if g["kind"] == "block":
                outline = sc.w.blocks.get(g["id"])
                if ck.check(outline is not None, "relation", where, "no world block named %s" % g["id"]):
                    b = target.box(0.0)
                    ck.check(point_in_poly(b.x, b.y, outline, 1e-6), "relation", where,
                             "%s centre (%.3f, %.3f) outside block %s outline" % (target.id, b.x, b.y, g["id"]))
            continue
        if not ck.check(op in BASE_OPS, "relation", where, "unknown operator %s" % op_full):
            continue
        related = sc.lookup(rel["id"])
        if not ck.check(related is not None, "relation", where, "related %s not found" % rel["id"]):
            continue
        ck.check(related.cls == rel["class"] and related.attrs == rel.get("attributes", {}), "relation", where,
                 "related %s is %s %s, relation says %s %s" % (related.id, related.cls, related.attrs, rel["class"], rel.get("attributes")))
        ck.check(applies(op, related.cls), "relation", where, "%s does not apply to class %s" % (op, related.cls))
        if not ev:
            ck.check("time" not in evidence, "relation", where, "non-EVENTUALLY relation with a time")
            t_ev = 0.0
            ok, f = sc.op_at(op, target, related, 0.0)
            ck.check(ok, "relation", where, "%s does not hold at t=0 (distance %.3f bearing %.3f dz %.3f los %s over %s)"
                     % (op, f.distance, f.bearing, f.dz, f.los, f.over))
        else:
            t_ev = evidence.get("time")
            if not ck.check(isinstance(t_ev, (int, float)), "eventually", where, "no evidence time"):
                continue
            k = int(round(t_ev / dt))
            ck.check(k >= 1 and abs(k * dt - t_ev) <= 1e-6, "eventually", where, "time %s is not k*%s, k>=1" % (t_ev, dt))
            ck.check(t_ev <= sc.sim.get("duration", float("inf")) + 1e-9, "eventually", where,
                     "time %s beyond duration %s" % (t_ev, sc.sim.get("duration")))
            ok, f = sc.op_at(op, target, related, t_ev)
            ck.check(ok, "eventually", where, "%s does not hold at t=%s (distance %.3f bearing %.3f dz %.3f los %s)"
                     % (op, t_ev, f.distance, f.bearing, f.dz, f.los))
            earlier = None
            for j in range(0, k):
                if sc.op_at(op, target, related, j * dt)[0]:
                    earlier = j * dt
                    break
            ck.check(earlier is None, "eventually", where, "%s already holds at t=%s, before evidence time %s" % (op, earlier, t_ev))
        # Evidence at the evidence time.
        want = {"distance": f.distance, "bearing_deg": f.bearing, "dz": f.dz}
        for key, val in want.items():
            got = evidence.get(key)
            if not ck.check(isinstance(got, (int, float)), "evidence", where, "evidence %s missing" % key):
                continue
            diff = ang_diff(got, val) if key == "bearing_deg" else abs(got - val)
            ck.check(diff <= EVIDENCE_TOL, "evidence", where, "evidence %s=%s, recomputed %.4f at t=%s" % (key, got, val, t_ev))
        ck.check(evidence.get("line_of_sight") == f.los, "evidence", where,
                 "evidence line_of_sight=%s, recomputed %s at t=%s" % (evidence.get("line_of_sight"), f.los, t_ev))


def aoi(mission, aid):
    for a in mission.get("areas_of_interest", []):
        if a["id"] == aid:
            return a
    return None


def check_priors(sc, ck, sid):
    m = sc.mission
    for p in m.get("area_priors", []):
        where = "%s prior %s" % (sid, p.get("aoi_id"))
        a = aoi(m, p["aoi_id"])
        if not ck.check(a is not None, "prior", where, "no AOI %s" % p["aoi_id"]):
            continue
        cells = p["cells"]
        total = sum(c["probability"] for c in cells)
        ck.check(abs(total - 1.0) <= 1e-6, "prior", where, "probabilities sum to %.9f" % total)
        n = (2 ** p["depth"]) ** 2
        ck.check(len(cells) == n, "prior", where, "%d cells for depth %d (want %d)" % (len(cells), p["depth"], n))
        area = poly_area(a["polygon"])
        cell_area = sum(poly_area(c["polygon"]) for c in cells)
        ck.check(abs(cell_area - area) <= 1e-3 * area, "prior", where, "cells cover %.3f m2, AOI %.3f m2" % (cell_area, area))


def check_area_search(sc, ck, sid):
    m = sc.mission
    a1 = aoi(m, "aoi_1")
    if not ck.check(a1 is not None, "aoi", sid, "no aoi_1"):
        return
    prior = None
    for p in m.get("area_priors", []):
        if p["aoi_id"] == "aoi_1":
            prior = p
    ck.check(prior is not None, "prior", sid, "no prior for aoi_1")
    for t in m["objective"]["targets"]:
        e = sc.by_id.get(t["id"])
        if not ck.check(e is not None, "aoi", sid, "target %s not in sim_config" % t["id"]):
            continue
        ck.check(not e.moving, "aoi", sid, "area_search target %s moves" % e.id)
        b = e.box0
        ck.check(point_in_poly(b.x, b.y, a1["polygon"]), "aoi", sid, "target %s centre (%.3f, %.3f) outside aoi_1" % (e.id, b.x, b.y))
        if prior is None:
            continue
        inside = [c for c in prior["cells"] if point_in_poly(b.x, b.y, c["polygon"], 1e-6)]
        if not ck.check(inside, "prior", sid, "no aoi_1 prior cell contains target %s" % e.id):
            continue
        best = max(c["probability"] for c in inside)
        others = [c["probability"] for c in prior["cells"] if c not in inside]
        ck.check(all(best > o for o in others), "prior", sid,
                 "target %s cell probability %s is not the strict maximum (%s)" % (e.id, best, max(others) if others else None))


def check_route_search(sc, ck, sid):
    m = sc.mission
    routes = m.get("routes", [])
    if not ck.check(routes, "route", sid, "no routes"):
        return
    band = routes[0]["band_polygon"]
    targets = []
    for t in m["objective"]["targets"]:
        e = sc.by_id.get(t["id"])
        if not ck.check(e is not None, "route", sid, "target %s not in sim_config" % t["id"]):
            continue
        targets.append(e)
        if e.moving:
            end = e.traj.times[-1]
            bad = None
            k = 0
            while True:
                tt = min(k * 0.25, end)
                x, y, _, _ = e.traj.at(tt)
                if not point_in_poly(x, y, band, ROUND_EPS):
                    bad = (tt, x, y)
                    break
                if tt >= end:
                    break
                k += 1
            ck.check(bad is None, "route", sid, "target %s leaves the band at %s" % (e.id, bad))
        else:
            ck.check(point_in_poly(e.box0.x, e.box0.y, band, ROUND_EPS), "route", sid, "static target %s outside the band" % e.id)
    for z in m.get("keep_out_zones", []):
        if z.get("purpose") != "access_denial":
            continue
        where = "%s %s" % (sid, z["id"])
        tw = z.get("time_window", {})
        net, nlt = tw.get("net"), tw.get("nlt")
        if not ck.check(net is not None and nlt is not None and net < nlt, "koz", where, "bad window %s" % tw):
            continue
        # The zone closes the street for exactly the time the target cars (a convoy of one or
        # two) are on it: some target inside <=> window active, to the 10 ms sampling step.
        movers = [e for e in targets if e.moving]
        end = max([e.traj.times[-1] for e in movers] or [0.0])
        entered = False
        good = True
        detail = ""
        k = 0
        while k * 0.01 <= end + 1e-9:
            tt = k * 0.01
            ins = False
            for e in movers:
                x, y, _, _ = e.traj.at(tt)
                if point_in_poly(x, y, z["polygon"]):
                    ins = True
                    break
            if ins:
                entered = True
                if not (net - 0.01 <= tt <= nlt + 0.01):
                    good = False
                    detail = "a target is inside at t=%.2f, window [%s, %s]" % (tt, net, nlt)
                    break
            elif net + 0.01 <= tt <= nlt - 0.01:
                good = False
                detail = "no target inside at t=%.2f, window [%s, %s]" % (tt, net, nlt)
                break
            k += 1
        if good and not entered:
            good = False
            detail = "no target enters the KOZ"
        ck.check(good, "koz", where, detail)


def starts_moving(e):
    pts = e.traj.pts
    x0, y0, z0 = pts[0][1:4]
    for i in range(1, len(pts)):
        if (pts[i][1], pts[i][2], pts[i][3]) != (x0, y0, z0):
            return pts[i - 1][0]
    return None


def check_pursuit(sc, ck, sid):
    m = sc.mission
    a1 = aoi(m, "aoi_1")
    if not ck.check(a1 is not None, "pursuit", sid, "no aoi_1"):
        return
    for t in m["objective"]["targets"]:
        e = sc.by_id.get(t["id"])
        if not ck.check(e is not None and e.moving, "pursuit", sid, "target %s missing or not moving" % t["id"]):
            continue
        b = e.box(0.0)
        ck.check(point_in_poly(b.x, b.y, a1["polygon"]), "pursuit", sid, "target %s not in aoi_1 at t=0" % e.id)
        depart = starts_moving(e)
        nlt = a1.get("time_window", {}).get("nlt")
        ck.check(depart is not None and nlt is not None and abs(nlt - depart) <= 0.5, "pursuit", sid,
                 "aoi_1 nlt %s vs target %s departure %s" % (nlt, e.id, depart))
    vignette = set()
    for g in sc.groups.values():
        if g["kind"] == "vignette":
            vignette.update(g["members"])
    found = any(r["operator"] == "EVENTUALLY_NEXT_TO" and r["related"]["class"] == "pedestrian"
                and r["related"]["id"] in vignette for r in m.get("scene_relations", []))
    ck.check(found, "pursuit", sid, "no EVENTUALLY_NEXT_TO with a vignette pedestrian")


def same_look(a, b):
    return all(a.attrs.get(k) == b.attrs.get(k) for k in ("make", "model", "color"))


def confuser_satisfies(sc, conf, r):
    """True when relation r (of a target) also holds for the static confuser `conf`."""
    ev, op = split_op(r["operator"])
    rel = r["related"]
    if op == "PART_OF":
        g = sc.groups.get(rel["id"])
        return g is not None and conf.id in g["members"]
    cfg = sc.cfg
    dt = cfg["eventually_dt"]
    cb = conf.box0
    reach = cfg["radius"] + 0.5 * math.hypot(cb.l, cb.w)
    key = attrs_key(rel["class"], rel.get("attributes", {}))
    cands = list(sc.w.by_look.get(key, []))
    cands += [e for e in sc.ents if attrs_key(e.cls, e.attrs) == key]
    for s in cands:
        if s.id == conf.id:
            continue
        reach_s = reach + 0.5 * math.hypot(s.box0.l, s.box0.w)
        if not s.moving:
            if math.hypot(s.box0.x - cb.x, s.box0.y - cb.y) > reach_s:
                continue
            if sc.holds(op, sc.measure(conf, cb, s, s.box0), s.cls):
                return True
            continue
        end = sc.sim.get("duration", 0.0) if ev else 0.0
        for _, t in grid_times(dt, end):
            sb = s.box(t)
            if math.hypot(sb.x - cb.x, sb.y - cb.y) > reach_s:
                continue
            if sc.holds(op, sc.measure(conf, cb, s, sb), s.cls):
                return True
    return False


def check_confusers(sc, ck, sid, cls):
    m = sc.mission
    targets = [e for e in sc.ents if e.role == "target"]
    for c in sc.ents:
        if c.role != "confuser":
            continue
        where = "%s confuser %s" % (sid, c.id)
        looks = [t for t in targets if same_look(t, c)]
        ck.check(looks, "confuser", where, "no target with make/model/color %s" % c.attrs)
        ck.check(not c.moving, "confuser", where, "confuser moves")
        if cls == "route_search":
            if m.get("routes"):
                band = m["routes"][0]["band_polygon"]
                ck.check(not polys_intersect(c.box0.corners, band), "confuser", where, "footprint intersects the route band")
            continue
        for t in looks:
            tb = t.box(0.0)
            t_aois = [a for a in m.get("areas_of_interest", []) if point_in_poly(tb.x, tb.y, a["polygon"])]
            if any(not point_in_poly(c.box0.x, c.box0.y, a["polygon"]) for a in t_aois):
                ck.check(True, "confuser", where, "")
                continue
            rels = [r for r in m.get("scene_relations", []) if r["target"] == t.id]
            failing = None
            for r in rels:
                if not confuser_satisfies(sc, c, r):
                    failing = r["text"]
                    break
            ck.check(failing is not None, "confuser", where,
                     "inside the AOI of %s and satisfies all of its %d relations" % (t.id, len(rels)))


def check_general(sc, ck, sid, fingerprint):
    m, s = sc.mission, sc.sim
    ids = [e.id for e in sc.ents]
    dups = sorted(set(i for i in ids if ids.count(i) > 1) | set(i for i in ids if i in sc.w.by_id))
    ck.check(not dups, "general", sid, "duplicate entity ids %s" % dups)
    u = s["uav"]["start"]
    for z in m.get("keep_out_zones", []):
        ck.check(not point_in_poly(u["x"], u["y"], z["polygon"]), "general", sid, "UAV start inside %s" % z["id"])
    for e in sc.ents:
        if e.moving:
            ts = e.traj.times
            bad = [i for i in range(1, len(ts)) if not ts[i] > ts[i - 1]]
            ck.check(not bad, "general", sid, "trajectory of %s not strictly increasing at samples %s" % (e.id, bad[:5]))
    ck.check(s["world"]["fingerprint"] == fingerprint, "general", sid,
             "world fingerprint %s != %s" % (s["world"]["fingerprint"], fingerprint))
    for doc, name in ((m, "mission"), (s, "sim_config")):
        want = "%s-%016x" % (doc["class"], doc["seed"])
        ck.check(doc["scenario_id"] == want, "general", sid, "%s scenario_id %s != %s" % (name, doc["scenario_id"], want))
    ck.check((m["scenario_id"], m["class"], m["seed"]) == (s["scenario_id"], s["class"], s["seed"]),
             "general", sid, "mission and sim_config disagree on id/class/seed")
    for t in m["objective"]["targets"]:
        e = sc.by_id.get(t["id"])
        ok = e is not None and e.role == "target" and e.cls == t["class"] and all(
            e.attrs.get(k) == t[k] for k in ("vehicle_class", "make", "model", "color"))
        ck.check(ok, "general", sid, "objective target %s does not match a sim_config target entity" % t["id"])


def check_block_groups(sc, ck, sid):
    for g in sc.groups.values():
        if g["kind"] != "block":
            continue
        outline = sc.w.blocks.get(g["id"])
        if not ck.check(outline is not None, "group", sid, "no world block %s" % g["id"]):
            continue
        for mid in g["members"]:
            e = sc.by_id.get(mid)
            if not ck.check(e is not None, "group", sid, "group %s member %s unknown" % (g["id"], mid)):
                continue
            b = e.box(0.0)
            ck.check(point_in_poly(b.x, b.y, outline, 1e-6), "group", sid, "member %s of %s outside its outline" % (mid, g["id"]))


def project(cam, ux, uy, uz, uyaw, px, py, pz, margin=0.0):
    """Pixel (u, v) of a world point in a payload camera of a level UAV, or None outside."""
    mx, my, mz = cam["mount"]["xyz"]
    roll, pitch, myaw = (math.radians(a) for a in cam["mount"]["rpy_deg"])
    c, s = math.cos(uyaw), math.sin(uyaw)
    cx, cy, cz = ux + c * mx - s * my, uy + s * mx + c * my, uz + mz
    # Into the body frame (FLU), then undo the mount yaw, pitch (positive looks down), roll.
    dx, dy, dz = px - cx, py - cy, pz - cz
    bx, by, bz = c * dx + s * dy, -s * dx + c * dy, dz
    cyw, syw = math.cos(myaw), math.sin(myaw)
    bx, by = cyw * bx + syw * by, -syw * bx + cyw * by
    cp, sp = math.cos(pitch), math.sin(pitch)
    bx, bz = cp * bx - sp * bz, sp * bx + cp * bz
    cr, sr = math.cos(roll), math.sin(roll)
    by, bz = cr * by + sr * bz, -sr * by + cr * bz
    if bx <= 1e-6:
        return None
    f = 0.5 * cam["width"] / math.tan(math.radians(cam["hfov_deg"]) / 2)
    u = 0.5 * cam["width"] + f * (-by) / bx
    v = 0.5 * cam["height"] + f * (-bz) / bx
    if margin <= u <= cam["width"] - margin and margin <= v <= cam["height"] - margin:
        return u, v
    return None


def check_perception_path(sc, ck, sid):
    """uav.perception_path: strictly increasing samples from the UAV start; an exact plan sees
    every target; each target it lists projects into its camera's image at some sample, with
    the target where its trajectory puts it at that time."""
    uav = sc.sim["uav"]
    pp = uav.get("perception_path")
    if pp is None:
        return
    tr = pp["trajectory"]
    ts = [q[0] for q in tr]
    bad = [i for i in range(1, len(ts)) if not ts[i] > ts[i - 1]]
    ck.check(not bad and (not ts or ts[0] >= 0), "perception", sid,
             "perception_path not strictly increasing at samples %s" % bad[:5])
    if tr:
        st = uav["start"]
        ck.check(abs(tr[0][1] - st["x"]) < 1e-6 and abs(tr[0][2] - st["y"]) < 1e-6, "perception", sid,
                 "perception_path does not start at the UAV start")
    targets = [t["id"] for t in sc.mission["objective"]["targets"]]
    seen = pp["targets_seen"]
    ck.check(all(t in targets for t in seen), "perception", sid, "targets_seen %s not all targets %s" % (seen, targets))
    if pp["status"] == "exact":
        ck.check(sorted(seen) == sorted(targets), "perception", sid,
                 "exact perception_path sees %s, targets are %s" % (seen, targets))
    cams = {c["name"]: c for c in uav["payload"]["cameras"]}
    cam = cams.get(pp.get("camera"))
    if not ck.check(cam is not None, "perception", sid, "unknown camera %s" % pp.get("camera")):
        return
    for tid in seen:
        e = sc.by_id.get(tid)
        if e is None:
            continue
        ok = False
        for q in tr:
            b = e.box(q[0])
            if project(cam, q[1], q[2], q[3], q[4], b.x, b.y, b.zc) is not None:
                ok = True
                break
        ck.check(ok, "perception", sid, "target %s never projects into the %s camera" % (tid, cam["name"]))


def verify_scenario(wctx, fingerprint, mission, sim, ck):
    sid = mission.get("scenario_id", "?")
    sc = Scene(wctx, mission, sim)
    cls = mission["class"]
    check_general(sc, ck, sid, fingerprint)
    check_relations(sc, ck, sid)
    check_block_groups(sc, ck, sid)
    check_priors(sc, ck, sid)
    if cls == "area_search":
        check_area_search(sc, ck, sid)
    elif cls == "route_search":
        check_route_search(sc, ck, sid)
    elif cls == "pursuit":
        check_pursuit(sc, ck, sid)
    else:
        ck.check(False, "general", sid, "unknown class %s" % cls)
    check_confusers(sc, ck, sid, cls)
    check_perception_path(sc, ck, sid)


# ----------------------------------------------------------------------------------------------
# Self-check: mutated documents must be detected


def self_checks(wctx, fingerprint, docs, ck):
    def detect(name, mission, sim, category):
        sub = Checker(quiet=True)
        verify_scenario(wctx, fingerprint, mission, sim, sub)
        ck.check(category in sub.categories, "selfcheck", name,
                 "mutation not detected as [%s] (failed categories %s)" % (category, sorted(sub.categories)))

    def find(pred):
        for m, s in docs:
            if pred(m, s):
                return copy.deepcopy(m), copy.deepcopy(s)
        return None, None

    flip = {"LEFT_OF": "RIGHT_OF", "RIGHT_OF": "LEFT_OF", "IN_FRONT_OF": "LEFT_OF", "ORTHOGONAL_TO": "IN_FRONT_OF"}

    # 1. Directional operator flipped (text kept consistent so only semantics can catch it).
    m, s = find(lambda m, s: any(r["operator"] in flip for r in m["scene_relations"]))
    ck.check(m is not None, "selfcheck", "flip", "no directional relation in the batch")
    if m is not None:
        r = next(r for r in m["scene_relations"] if r["operator"] in flip)
        r["operator"] = flip[r["operator"]]
        r["text"] = relation_text(r)
        detect("flip operator " + m["scenario_id"], m, s, "relation")

    # 2. Area-search target moved out of its AOI.
    m, s = find(lambda m, s: m["class"] == "area_search")
    if m is not None:
        tid = m["objective"]["targets"][0]["id"]
        for e in s["entities"]:
            if e["id"] == tid:
                xs = [p[0] for p in aoi(m, "aoi_1")["polygon"]]
                e["pose"]["x"] = max(xs) + 50.0
        detect("target out of AOI " + m["scenario_id"], m, s, "aoi")

    # 3. Evidence distance off by 0.5 m.
    m, s = find(lambda m, s: any("distance" in r["evidence"] for r in m["scene_relations"]))
    if m is not None:
        r = next(r for r in m["scene_relations"] if "distance" in r["evidence"])
        r["evidence"]["distance"] += 0.5
        detect("evidence distance " + m["scenario_id"], m, s, "evidence")

    # 4. Access-denial KOZ window shifted by 2 s.
    m, s = find(lambda m, s: any(z["purpose"] == "access_denial" for z in m["keep_out_zones"]))
    ck.check(m is not None, "selfcheck", "koz", "no access_denial KOZ in the batch")
    if m is not None:
        z = next(z for z in m["keep_out_zones"] if z["purpose"] == "access_denial")
        z["time_window"]["net"] += 2.0
        detect("koz window " + m["scenario_id"], m, s, "koz")

    # 5. Pursuit aoi_1 nlt off by 3 s.
    m, s = find(lambda m, s: m["class"] == "pursuit")
    if m is not None:
        aoi(m, "aoi_1")["time_window"]["nlt"] = aoi(m, "aoi_1")["time_window"].get("nlt", 0) + 3.0
        detect("pursuit nlt " + m["scenario_id"], m, s, "pursuit")

    # 6. EVENTUALLY evidence time moved one grid step later (the op already held before).
    m, s = find(lambda m, s: any(r["operator"].startswith("EVENTUALLY_") for r in m["scene_relations"]))
    if m is not None:
        r = next(r for r in m["scene_relations"] if r["operator"].startswith("EVENTUALLY_"))
        r["evidence"]["time"] += 0.5
        detect("eventually time " + m["scenario_id"], m, s, "eventually")

    # 7. Route-search confuser moved onto the target's path.
    m, s = find(lambda m, s: m["class"] == "route_search" and any(e["role"] == "confuser" for e in s["entities"]))
    ck.check(m is not None, "selfcheck", "route confuser", "no route_search confuser in the batch")
    if m is not None:
        tgt = next(e for e in s["entities"] if e["role"] == "target")
        mid = tgt["trajectory"][len(tgt["trajectory"]) // 2]
        c = next(e for e in s["entities"] if e["role"] == "confuser")
        c["pose"]["x"], c["pose"]["y"] = mid[1] + 0.0, mid[2] + 0.0
        detect("route confuser " + m["scenario_id"], m, s, "confuser")

    # 8. Prior peak moved away from the target cell.
    def unique_cell(m, s):
        if m["class"] != "area_search":
            return False
        t = next(e for e in s["entities"] if e["role"] == "target")["pose"]
        p = next(p for p in m["area_priors"] if p["aoi_id"] == "aoi_1")
        return sum(point_in_poly(t["x"], t["y"], c["polygon"], 1e-6) for c in p["cells"]) == 1
    m, s = find(unique_cell)
    ck.check(m is not None, "selfcheck", "prior", "no area_search target strictly inside one prior cell")
    if m is not None:
        p = next(p for p in m["area_priors"] if p["aoi_id"] == "aoi_1")
        hi = max(p["cells"], key=lambda c: c["probability"])
        lo = min(p["cells"], key=lambda c: c["probability"])
        hi["probability"], lo["probability"] = lo["probability"], hi["probability"]
        detect("prior peak " + m["scenario_id"], m, s, "prior")

    # 9. Confuser in the target's AOI given the target's exact context: a copy of the target.
    def twin_ok(m, s):
        return m["class"] == "area_search" and any(e["role"] == "confuser" for e in s["entities"])
    m, s = find(twin_ok)
    if m is not None:
        tgt = next(e for e in s["entities"] if e["role"] == "target")
        c = next(e for e in s["entities"] if e["role"] == "confuser")
        # Keep only the relations that need no line of sight (the twin overlaps the target,
        # which occludes), so that the twin satisfies every one of them.
        m["scene_relations"] = [r for r in m["scene_relations"]
                                if r["operator"] in ("ON_TOP_OF", "NOT_ON_TOP_OF", "PART_OF")]
        c["pose"] = copy.deepcopy(tgt["pose"])
        c["pose"]["x"] += 1e-3
        c["size"] = list(tgt["size"])
        # Make the confuser a member of every group the target belongs to.
        for g in s["groups"]:
            if tgt["id"] in g["members"] and c["id"] not in g["members"]:
                g["members"].append(c["id"])
        detect("confuser twin " + m["scenario_id"], m, s, "confuser")

    # 10. Trajectory with two samples swapped in time.
    m, s = find(lambda m, s: any(len(e["trajectory"]) > 3 for e in s["entities"]))
    if m is not None:
        e = next(e for e in s["entities"] if len(e["trajectory"]) > 3)
        e["trajectory"][1][0], e["trajectory"][2][0] = e["trajectory"][2][0], e["trajectory"][1][0]
        detect("trajectory order " + m["scenario_id"], m, s, "general")

    # 10b. Perception path: samples out of order; an exact path that misses a target.
    m, s = find(lambda m, s: len(s["uav"].get("perception_path", {}).get("trajectory", [])) > 3)
    if m is not None:
        tr = s["uav"]["perception_path"]["trajectory"]
        tr[1][0], tr[2][0] = tr[2][0], tr[1][0]
        detect("perception_path order " + m["scenario_id"], m, s, "perception")
    m, s = find(lambda m, s: s["uav"].get("perception_path", {}).get("status") == "exact")
    if m is not None:
        s["uav"]["perception_path"]["targets_seen"] = []
        detect("perception_path unseen " + m["scenario_id"], m, s, "perception")

    # 11. A PART_OF relation naming a group the target is not in.
    m, s = find(lambda m, s: any(r["operator"] == "PART_OF" for r in m["scene_relations"]))
    if m is not None:
        r = next(r for r in m["scene_relations"] if r["operator"] == "PART_OF")
        for g in s["groups"]:
            if g["id"] == r["related"]["id"]:
                g["members"] = [x for x in g["members"] if x != r["target"]]
        detect("part_of " + m["scenario_id"], m, s, "relation")


# ----------------------------------------------------------------------------------------------


def env_dir(var):
    value = os.environ.get(var)
    if not value or not os.path.isdir(value):
        print("test_scenario_semantics: $%s must name a directory (got %r)" % (var, value), file=sys.stderr)
        sys.exit(1)
    return value


def load(path):
    with open(path) as f:
        return json.load(f)


def episode_crowd(sim, sim_path):
    """The crowd of a city scenario that a batch wrote by reference to a traffic episode file,
    as the entities the self-contained file lists: each pedestrian's keyframes around the
    window shifted by the offset, its pose at the window's start (a queuing one at its pose)."""
    ref = sim["traffic"]
    ep = load(os.path.join(os.path.dirname(sim_path), ref["file"]))
    t0, dur = ref["offset"], sim["duration"]
    out = []
    for pid, p in zip(ref["pedestrians"], ep["pedestrians"]):
        k = p["keyframes"]
        rows = [k[i:i + 4] for i in range(0, len(k), 4)]
        traj = []
        x, y, yaw = p["pose"]
        if rows:
            a = max(0, bisect.bisect_right([r[0] for r in rows], t0) - 1)
            b = min(len(rows), bisect.bisect_left([r[0] for r in rows], t0 + dur) + 1)
            traj = [[r[0] - t0, r[1], r[2], 0.0, r[3]] for r in rows[a:b]]
            (ta, xa, ya, _, wa), (tb, xb, yb, _, wb) = traj[0], traj[min(1, len(traj) - 1)]
            u = 0.0 if tb <= ta else min(1.0, max(0.0, -ta / (tb - ta)))
            x, y, yaw = xa + u * (xb - xa), ya + u * (yb - ya), wa if u < 0.5 else wb
        out.append({"id": pid, "class": "pedestrian", "role": "pedestrian",
                    "attributes": {"clothing_color": p["clothing_color"],
                                   "activity": p["activity"]},
                    "pose": {"x": x, "y": y, "z": 0.0, "yaw": yaw},
                    "size": [0.5, 0.6, p["height"]], "trajectory": traj})
    return out


def main(world="suburb", count=150, min_checks=MIN_CHECKS):
    """Checks a batch of `count` scenarios generated with --world `world`."""
    start = time.time()
    bin_dir = env_dir("HAMERITT_BIN_DIR")
    src_dir = env_dir("HAMERITT_SOURCE_DIR")
    exe = os.path.join(bin_dir, "hameritt_generate")
    cfg_all = load(os.path.join(src_dir, "config", "generator.json"))
    cfg = cfg_all["relations"]
    ck = Checker()
    tmp = tempfile.mkdtemp(prefix="hameritt_semantics_")
    try:
        cmd = [exe, "--class", "all", "--count", str(count), "--seed", "99", "--out", tmp, "--quiet",
               "--world", world]
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
        if proc.returncode != 0:
            print("test_scenario_semantics: %s failed (%d): %s" % (" ".join(cmd), proc.returncode, proc.stderr.strip()))
            print("0 passed, 1 failed")
            return 1
        manifest = load(os.path.join(tmp, "manifest.json"))
        world = load(os.path.join(tmp, "world.json"))
        fingerprint = world["fingerprint"]
        wctx = WorldCtx(world, cfg)
        ck.check(not wctx.dup_ids, "general", "world.json", "duplicate world ids %s" % wctx.dup_ids[:10])
        ck.check(manifest.get("world", {}).get("fingerprint") == fingerprint, "general", "manifest.json",
                 "world fingerprint %s != %s" % (manifest.get("world", {}).get("fingerprint"), fingerprint))

        dirs = sorted(d for d in os.listdir(tmp) if os.path.isdir(os.path.join(tmp, d)))
        listed = {e["path"]: e for e in manifest.get("scenarios", [])}
        ck.check(len(manifest.get("scenarios", [])) == manifest.get("count"), "general", "manifest.json",
                 "%d scenarios listed, count %s" % (len(manifest.get("scenarios", [])), manifest.get("count")))
        ck.check(set(dirs) == set(listed), "general", "manifest.json",
                 "dirs not listed %s; listed, no dir %s" % (sorted(set(dirs) - set(listed))[:5], sorted(set(listed) - set(dirs))[:5]))
        docs = []
        for d in dirs:
            mission = load(os.path.join(tmp, d, "mission.json"))
            sim = load(os.path.join(tmp, d, "sim_config.json"))
            if "traffic" in sim:
                sim["entities"] += episode_crowd(sim, os.path.join(tmp, d, "sim_config.json"))
            entry = listed.get(d)
            if entry is not None:
                ck.check((entry["id"], entry["class"], entry["seed"]) == (mission["scenario_id"], mission["class"], mission["seed"])
                         and entry["id"] == d, "general", d,
                         "manifest entry %s/%s/%s vs mission %s/%s/%s" % (entry["id"], entry["class"], entry["seed"],
                                                                        mission["scenario_id"], mission["class"], mission["seed"]))
            verify_scenario(wctx, fingerprint, mission, sim, ck)
            docs.append((mission, sim))
        real_checks = ck.passed + ck.failed
        self_checks(wctx, fingerprint, docs, ck)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if real_checks < min_checks:
        print("FAIL [guard] only %d checks ran on the batch (want at least %d)" % (real_checks, min_checks))
        ck.failed += 1
    print("(%d scenarios, %d checks on the batch, %.1f s)" % (len(docs), real_checks, time.time() - start))
    print("%d passed, %d failed" % (ck.passed, ck.failed))
    return 1 if ck.failed else 0


if __name__ == "__main__":
    sys.exit(main())
