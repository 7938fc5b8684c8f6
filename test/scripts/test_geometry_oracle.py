#!/usr/bin/python3
"""Geometry oracle: our polygon operations and keep-out-zone checker against Shapely (GEOS).

Generates CASES (default 100,000) seeded cases, random and adversarial (touching edges,
collinear overlaps, vertices on edges, segments through vertices, tiny zones, huge
coordinates, degenerate segments, self-touching rings), answers them all with one run of
$HAMERITT_BIN_DIR/geometry_oracle (our C++: geometry::Polygon, adk::segmentInsidePolygon,
adk::violationIntervals), and compares every answer with an independent computation:

  area                  Polygon.area                      |diff| <= 4 TOL x size
  contains(q)           exact, or Polygon.intersects(Point)   see "yes/no" below
  distance(q)           Polygon.distance(Point)           |diff| <= TOL
  intersectsSegment     exact, or Polygon.intersects(LineString)
  inside length         intersection(LineString).length   |diff| <= 4 TOL
  intersects(other)     exact, or Polygon.intersects(Polygon)
  distance(other)       Polygon.distance(Polygon)         |diff| <= 4 TOL
  isSimple              is_valid, >= 3 distinct vertices, no repeated consecutive vertex
  violation duration    Shapely pieces of the 2-D segment, clipped to the altitude band
                        and the time window in Python  |diff| <= TOL_T

Yes/no answers: where the point (segment, other ring) lies within 2 BAND of the ring, BAND =
1e-9 x max(1, |coordinate|) being the library's declared boundary band (geometry::kEpsilon),
the boundary is decided exactly in rational arithmetic (fractions.Fraction: a double is a
rational): on the ring (touching it) the answer must be yes, with no tolerance. Query points
and segment ends are built on the ring exactly (vertices on a dyadic grid, points at k/256 of
an edge). Within the band but not meeting the ring exactly, and not overlapping it by
Shapely, the case is set aside from that comparison and counted ("excluded"). Everywhere else
Shapely's answer must be matched exactly.

Tolerances on numbers are relative to the zone's own size (the diagonal of its bounding box):
TOL = 1e-9 x size + 1e-12 x |coordinate| (the second term: the inputs' own rounding, some
4,500 units in the last place). Durations: TOL_T = 1e-12 x max(1, |tb|) + (tb - ta) x 4 TOL /
max(|ab|, size). Where a segment runs along an edge within the band the inside length is
ill-conditioned: a length or duration that misses the direct comparison must lie between the
answers for the polygon shrunk and grown by one BAND, or, counted apart, by four.

The counts of excluded and widened cases are bounded (MAX_EXCLUDED, MAX_WIDENED,
MAX_WIDENED_4, as fractions of all cases), and the exact boundary classes must be frequent
(at least 30 % of cases on the ring and touching, 10 % of polygon pairs touching).

Negative control, in the same run: the first CONTROL_CASES cases are answered again by the
driver with HAMERITT_ORACLE_WRONG=boundary_outside (a library that calls the ring outside);
the comparison must report disagreements in the exact boundary checks of contains and
intersectsSegment, else the test fails.

Prints the counts per case family, per check and per boundary class; exits 1 on any
disagreement beyond the tolerance or any bound exceeded (the first disagreements are listed
with the case line, to reproduce by hand: echo 'LINE' | $HAMERITT_BIN_DIR/geometry_oracle).
"""

import math
from fractions import Fraction
import os
import random
import subprocess
import sys

try:
    from shapely.geometry import LineString, Point, Polygon
except ImportError:  # Debian: apt-get install python3-shapely
    print("test_geometry_oracle: python3-shapely is not installed", file=sys.stderr)
    sys.exit(1)

CASES = int(os.environ.get("HAMERITT_ORACLE_CASES", "100000"))
SEED = int(os.environ.get("HAMERITT_ORACLE_SEED", "1"))
# Tolerance on lengths, relative to the zone's size, and the floor from the rounding of the
# coordinates (relative to their magnitude; about 4,500 units in the last place).
REL = 1e-9
REL_COORD = 1e-12
# The library's boundary band, geometry::kEpsilon * max(1, |coordinate|) (src/geometry/polygon.cpp).
BAND = 1e-9
# Upper bounds, as fractions of all cases, on the cases set aside (within the band of the ring
# and not meeting it exactly) and on the lengths and durations accepted only with the polygon
# grown/shrunk by the band (x1) or by four bands (x4).
MAX_EXCLUDED = 0.015
MAX_WIDENED = 0.01
MAX_WIDENED_4 = 0.003
# Cases run through the negative control (the wrong library).
CONTROL_CASES = 5000
NAN = float("nan")

rng = random.Random(SEED)


# ---------------------------------------------------------------- case generation
def star(cx, cy, r, n, jitter=0.6):
    """A simple star-shaped polygon: angles sorted, radii in [r (1 - jitter), r]."""
    angles = sorted(rng.uniform(0, 2 * math.pi) for _ in range(n))
    # Distinct angles keep the ring simple.
    for i in range(1, n):
        if angles[i] - angles[i - 1] < 1e-3:
            angles[i] = angles[i - 1] + 1e-3
    if angles[-1] - angles[0] > 2 * math.pi - 1e-3:
        return rect(cx - r, cy - r, cx + r, cy + r)
    # Vertices on a dyadic grid 2^-40 of the coordinates' magnitude: a point at t = k/256 along
    # an edge is then a double exactly (so exactly on the ring), and the ring stays irregular.
    q = 2.0 ** (math.floor(math.log2(max(abs(cx), abs(cy)) + r)) - 40)
    return [(round((cx + r * (1 - jitter * rng.random()) * math.cos(a)) / q) * q,
             round((cy + r * (1 - jitter * rng.random()) * math.sin(a)) / q) * q) for a in angles]


def rect(x0, y0, x1, y1):
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def on_edge(poly, t=None):
    """A point on the polygon's ring (vertex when t is 0)."""
    i = rng.randrange(len(poly))
    (x0, y0), (x1, y1) = poly[i], poly[(i + 1) % len(poly)]
    t = rng.choice([0.0, 0.5, 0.25, rng.randrange(1, 256) / 256]) if t is None else t
    return (x0 + t * (x1 - x0), y0 + t * (y1 - y0))


def random_point(poly, spread=1.5):
    xs = [p[0] for p in poly]
    ys = [p[1] for p in poly]
    cx, cy = (min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2
    w = max(max(xs) - min(xs), max(ys) - min(ys), 1e-300)
    return (cx + spread * w * (rng.random() - 0.5), cy + spread * w * (rng.random() - 0.5))


def segment_for(poly):
    """Segment end points: random, through vertices, along an edge, ending on the ring."""
    kind = rng.randrange(6)
    if kind == 0:
        return random_point(poly), random_point(poly)
    if kind == 1:  # through a vertex (both ends on the line through it)
        v = poly[rng.randrange(len(poly))]
        p = random_point(poly)
        return p, (2 * v[0] - p[0], 2 * v[1] - p[1])
    if kind == 2:  # collinear with an edge, overlapping it partly
        i = rng.randrange(len(poly))
        (x0, y0), (x1, y1) = poly[i], poly[(i + 1) % len(poly)]
        s, t = rng.choice([(-0.5, 0.5), (0.25, 1.5), (-1, 2), (0.1875, 0.6875), (1.0, 2.0)])
        return (x0 + s * (x1 - x0), y0 + s * (y1 - y0)), (x0 + t * (x1 - x0), y0 + t * (y1 - y0))
    if kind == 3:  # from outside to a point on the ring (touching)
        return random_point(poly, 3.0), on_edge(poly)
    if kind == 4:  # vertex to vertex (a diagonal or an edge)
        return poly[rng.randrange(len(poly))], poly[rng.randrange(len(poly))]
    p = random_point(poly)  # degenerate: a point
    return p, p


def polygon_case(family):
    """One polygon (and a companion polygon) of a family; coordinates as floats."""
    if family == "random":
        s = rng.choice([1.0, 50.0, 1000.0])
        return star(rng.uniform(-s, s), rng.uniform(-s, s), s * rng.uniform(0.05, 1), rng.randint(3, 12))
    if family == "grid":  # integer rectangles and triangles: exact touching and collinear cases
        x0, y0 = rng.randint(-20, 20), rng.randint(-20, 20)
        w, h = rng.randint(1, 10), rng.randint(1, 10)
        if rng.random() < 0.5:
            return rect(x0, y0, x0 + w, y0 + h)
        return [(x0, y0), (x0 + w, y0), (x0, y0 + h)]
    if family == "collinear_vertex":  # a straight vertex in the middle of an edge
        x0, y0, w, h = rng.randint(-10, 10), rng.randint(-10, 10), rng.randint(2, 10), rng.randint(1, 10)
        return [(x0, y0), (x0 + w / 2, y0), (x0 + w, y0), (x0 + w, y0 + h), (x0, y0 + h)]
    if family == "tiny":
        s = rng.choice([1e-3, 1e-5, 1e-6])
        return star(rng.uniform(-100, 100), rng.uniform(-100, 100), s, rng.randint(3, 8))
    if family == "huge":  # far from the origin (ENU kilometres to thousands of kilometres)
        c = rng.choice([1e4, 1e5, 1e6])
        return star(c * rng.uniform(-1, 1), c * rng.uniform(-1, 1), rng.uniform(1, 500), rng.randint(3, 10))
    if family == "not_simple":  # bow ties, spikes, repeated and self-touching vertices
        x0, y0 = rng.randint(-10, 10), rng.randint(-10, 10)
        return rng.choice([
            [(x0, y0), (x0 + 4, y0 + 4), (x0 + 4, y0), (x0, y0 + 4)],  # bow tie
            [(x0, y0), (x0 + 4, y0), (x0 + 4, y0), (x0 + 4, y0 + 4)],  # repeated vertex
            [(x0, y0), (x0 + 4, y0), (x0 + 8, y0), (x0 + 2, y0)],  # zero area (a spike)
            [(x0, y0), (x0 + 4, y0), (x0 + 4, y0 + 4), (x0 + 2, y0), (x0, y0 + 4)],  # touches
            [(x0, y0), (x0 + 4, y0), (x0 + 4, y0 + 4), (x0, y0 + 4), (x0, y0)],  # closed ring
        ])
    raise ValueError(family)


def companion(poly, family):
    """A second polygon: touching along an edge, at a vertex, overlapping, or apart."""
    kind = rng.randrange(4)
    xs = [p[0] for p in poly]
    ys = [p[1] for p in poly]
    w = max(max(xs) - min(xs), max(ys) - min(ys))
    if kind == 0 and family in ("grid", "collinear_vertex"):  # shares (part of) an edge
        return rect(max(xs), min(ys) + rng.randint(-2, 2), max(xs) + rng.randint(1, 5), max(ys))
    if kind == 1:  # a triangle with one vertex on the ring
        p = on_edge(poly)
        d = w * rng.uniform(0.1, 1)
        a = rng.uniform(0, 2 * math.pi)
        return [p, (p[0] + d * math.cos(a), p[1] + d * math.sin(a)),
                (p[0] + d * math.cos(a + 0.5), p[1] + d * math.sin(a + 0.5))]
    c = random_point(poly, 3.0)
    return star(c[0], c[1], w * rng.uniform(0.01, 0.7), rng.randint(3, 7))


def bounds_for(zs):
    """Altitude band and time window: missing, open on one side, or closed."""
    k = rng.randrange(4)
    if k == 0:
        return NAN, NAN
    lo = rng.uniform(min(zs) - 5, max(zs) + 5)
    if k == 1:
        return lo, NAN
    if k == 2:
        return NAN, lo
    return lo, lo + rng.uniform(0, 30)


FAMILIES = [("random", 0.40), ("grid", 0.25), ("collinear_vertex", 0.10), ("tiny", 0.10),
            ("huge", 0.10), ("not_simple", 0.05)]


def make_case():
    r = rng.random()
    for family, weight in FAMILIES:
        r -= weight
        if r < 0:
            break
    poly = polygon_case(family)
    a2, b2 = segment_for(poly)
    za, zb = rng.uniform(0, 60), rng.choice([rng.uniform(0, 60), None])
    zb = za if zb is None else zb
    ta = rng.uniform(0, 1000)
    tb = ta + rng.choice([rng.uniform(0.01, 50), 1.0])
    q = rng.choice([random_point(poly), on_edge(poly), poly[rng.randrange(len(poly))]])
    zmin, zmax = bounds_for([za, zb])
    net, nlt = bounds_for([ta, tb])
    other = companion(poly, family)
    return dict(family=family, poly=poly, a=(a2[0], a2[1], za), b=(b2[0], b2[1], zb), ta=ta,
                tb=tb, q=q, zmin=zmin, zmax=zmax, net=net, nlt=nlt, other=other)


def case_line(c):
    nums = [len(c["poly"])] + [x for p in c["poly"] for x in p]
    nums += list(c["a"]) + list(c["b"]) + [c["ta"], c["tb"]] + list(c["q"])
    nums += [c["zmin"], c["zmax"], c["net"], c["nlt"]]
    nums += [len(c["other"])] + [x for p in c["other"] for x in p]
    return " ".join(repr(float(x)) if not isinstance(x, int) else str(x) for x in nums)


# ---------------------------------------------------------------- the independent answers
def shape2(a, b):
    return Point(a) if a == b else LineString([a, b])


def inside_pieces(poly, a, b):
    """Parameter intervals [u0, u1] of a + u (b - a) inside the closed polygon (Shapely)."""
    if a == b:
        return [(0.0, 1.0)] if poly.intersects(Point(a)) else []
    inter = poly.intersection(LineString([a, b]))
    dx, dy = b[0] - a[0], b[1] - a[1]
    dd = dx * dx + dy * dy
    out = []
    parts = getattr(inter, "geoms", [inter])
    for g in parts:
        if g.is_empty:
            continue
        us = [((x - a[0]) * dx + (y - a[1]) * dy) / dd for x, y in g.coords]
        out.append((max(0.0, min(us)), min(1.0, max(us))))
    return out


def violation_duration(poly, c):
    a, b = c["a"], c["b"]
    pieces = inside_pieces(poly, a[:2], b[:2])
    lo, hi = 0.0, 1.0
    dz = b[2] - a[2]
    zmin = -math.inf if math.isnan(c["zmin"]) else c["zmin"]
    zmax = math.inf if math.isnan(c["zmax"]) else c["zmax"]
    if dz == 0:
        if not (zmin <= a[2] <= zmax):
            return 0.0
    else:
        u0, u1 = (zmin - a[2]) / dz, (zmax - a[2]) / dz
        if dz < 0:
            u0, u1 = u1, u0
        lo, hi = max(lo, u0), min(hi, u1)
    net = -math.inf if math.isnan(c["net"]) else c["net"]
    nlt = math.inf if math.isnan(c["nlt"]) else c["nlt"]
    ta, tb = c["ta"], c["tb"]
    total = 0.0
    for u0, u1 in pieces:
        u0, u1 = max(u0, lo), min(u1, hi)
        if u0 > u1:
            continue
        t0, t1 = max(ta + u0 * (tb - ta), net), min(ta + u1 * (tb - ta), nlt)
        if t0 <= t1:
            total += t1 - t0
    return total


def near_degenerate(ring, tol):
    """True when the ring is within tol of a non-simple one: a vertex within tol of an edge
    not incident to it, an edge shorter than tol, or an area below tol * diagonal (our
    isSimple() decides these with the same tolerance, so either answer is right)."""
    n = len(ring)
    if n < 3:
        return True
    xs = [p[0] for p in ring]
    ys = [p[1] for p in ring]
    diag = math.hypot(max(xs) - min(xs), max(ys) - min(ys))
    if abs(Polygon(ring).area) <= 2 * tol * diag:
        return True
    for i in range(n):
        if math.dist(ring[i], ring[(i + 1) % n]) <= tol:
            return True
        for j in range(n):
            if j != i and (j + 1) % n != i:
                if Point(ring[i]).distance(LineString([ring[j], ring[(j + 1) % n]])) <= 2 * tol:
                    return True
    return False


def between(value, lo, hi, slack):
    return lo - slack <= value <= hi + slack


def oracle_simple(ring):
    if len(ring) < 3:
        return False
    for i in range(len(ring)):
        if ring[i] == ring[(i + 1) % len(ring)]:
            return False
    p = Polygon(ring)
    return p.is_valid and p.area > 0


# ---------------------------------------------------------------- exact boundary predicates
# Doubles are rationals: Fraction(x) is x exactly, so these decide "on the ring" and "touches
# the ring" without rounding.
def orient(a, b, c):
    """Sign of the cross product (b - a) x (c - a), exactly: in doubles where the result is
    farther from 0 than their rounding error (Shewchuk's orient2d bound, 3.3e-16 of the terms'
    magnitudes, taken as 1e-15), else in rationals."""
    left = (b[0] - a[0]) * (c[1] - a[1])
    right = (b[1] - a[1]) * (c[0] - a[0])
    err = 1e-15 * (abs(left) + abs(right))
    if left - right > err:
        return 1
    if right - left > err:
        return -1
    ax, ay, bx, by, cx, cy = (Fraction(v) for v in (*a, *b, *c))
    v = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    return (v > 0) - (v < 0)


def within_box(p, a, b):
    return min(a[0], b[0]) <= p[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= p[1] <= max(a[1], b[1])


def on_segment_exact(p, a, b):
    return within_box(p, a, b) and orient(a, b, p) == 0


def segments_meet_exact(p1, p2, q1, q2):
    """The closed segments p1-p2 and q1-q2 share a point (exactly)."""
    if p1 == p2:
        return on_segment_exact(p1, q1, q2)
    if q1 == q2:
        return on_segment_exact(q1, p1, p2)
    d1, d2 = orient(q1, q2, p1), orient(q1, q2, p2)
    d3, d4 = orient(p1, p2, q1), orient(p1, p2, q2)
    if d1 * d2 < 0 and d3 * d4 < 0:
        return True
    return ((d1 == 0 and within_box(p1, q1, q2)) or (d2 == 0 and within_box(p2, q1, q2))
            or (d3 == 0 and within_box(q1, p1, p2)) or (d4 == 0 and within_box(q2, p1, p2)))


def edges(ring):
    return [(ring[i], ring[(i + 1) % len(ring)]) for i in range(len(ring))]


def on_ring_exact(ring, p):
    return any(on_segment_exact(p, a, b) for a, b in edges(ring))


def touches_ring_exact(ring, a, b):
    return any(segments_meet_exact(a, b, c, d) for c, d in edges(ring))


def rings_meet_exact(r1, r2):
    return any(segments_meet_exact(a, b, c, d) for a, b in edges(r1) for c, d in edges(r2))


# ---------------------------------------------------------------- run and compare
def run_driver(text, wrong=None):
    binary = os.path.join(os.environ.get("HAMERITT_BIN_DIR", ""), "geometry_oracle")
    env = dict(os.environ)
    env.pop("HAMERITT_ORACLE_WRONG", None)
    if wrong:
        env["HAMERITT_ORACLE_WRONG"] = wrong
    proc = subprocess.run([binary], input=text, capture_output=True, text=True, check=False,
                          env=env)
    if proc.returncode != 0:
        raise RuntimeError("geometry_oracle failed: " + proc.stderr[-2000:])
    return proc.stdout.splitlines()


def compare(cases, lines, answers):
    """Compares every answer; returns (checks, bad, tally) where checks maps a check name to
    [compared, disagreements] and tally counts the boundary classes and widened tolerances."""
    checks = {}
    bad = []
    tally = {k: 0 for k in ("on ring (exact)", "near ring, excluded", "segment touching (exact)",
                            "polygons touching (exact)",
                            "near-touching, excluded", "isSimple near-degenerate",
                            "widened x1 band", "widened x4 band")}

    by_family = {}

    def count(name, i):
        tally[name] += 1
        fam = by_family.setdefault(name, {})
        fam[cases[i]["family"]] = fam.get(cases[i]["family"], 0) + 1

    def check(name, ok, i, detail):
        n = checks.setdefault(name, [0, 0])
        n[0] += 1
        if not ok:
            n[1] += 1
            if len(bad) < 20:
                bad.append(f"{name} ({cases[i]['family']}): {detail}\n  case: {lines[i]}")

    def yes_no(name, ours, oracle, near, exact_meet, i):
        """A yes/no answer: exact where the shapes meet (on the ring: yes), Shapely's where they
        are farther apart than the library's band or Shapely says they overlap (then they
        meet away from the ring, robustly); within the band and not meeting: excluded."""
        if near and exact_meet():
            count({"contains": "on ring (exact)", "intersectsSegment": "segment touching (exact)"}.get(
                name, "polygons touching (exact)"), i)
            check(name + " [boundary, exact]", ours, i, f"ours {ours}, exact: on the boundary")
        elif near and not oracle:
            count("near ring, excluded" if name == "contains" else "near-touching, excluded", i)
        else:
            check(name, ours == oracle, i, f"ours {ours}, oracle {oracle}")

    for i, (c, ans) in enumerate(zip(cases, answers)):
        f = ans.split()
        area, contains, dist_q = float(f[0]), f[1] == "1", float(f[2])
        seg_hit, inside_len = f[3] == "1", float(f[4])
        poly_hit, poly_dist, simple, viol = f[6] == "1", float(f[7]), f[8] == "1", float(f[9])
        ring = c["poly"]
        xs, ys = [p[0] for p in ring], [p[1] for p in ring]
        # The zone's own size, and the magnitude of the coordinates of the case.
        size = math.hypot(max(xs) - min(xs), max(ys) - min(ys))
        mag = max(1.0, max(abs(x) for p in ring + c["other"] + [c["a"][:2], c["b"][:2], c["q"]]
                           for x in p))
        # Lengths: relative to the zone's size, plus a floor of REL_COORD * |coordinate| (a few
        # thousand units in the last place: the inputs themselves are rounded to doubles).
        tol = REL * size + REL_COORD * mag
        # The library's declared boundary band (geometry::kEpsilon * max(1, |coordinate|)): a
        # point closer to the ring than this may be called on it.
        band = BAND * mag
        expect_simple = oracle_simple(ring)
        if simple != expect_simple and near_degenerate(ring, band):
            count("isSimple near-degenerate", i)
        else:
            check("isSimple", simple == expect_simple, i, f"ours {simple}, oracle {expect_simple}")
        if not (expect_simple and simple):
            continue  # Shapely's other answers are undefined for invalid polygons
        P = Polygon(ring)
        a2, b2 = c["a"][:2], c["b"][:2]
        q = Point(c["q"])
        seg = shape2(a2, b2)
        check("area", abs(area - P.area) <= 4 * tol * size, i, f"ours {area!r}, oracle {P.area!r}")
        yes_no("contains", contains, P.intersects(q), P.exterior.distance(q) <= 2 * band,
               lambda: on_ring_exact(ring, c["q"]), i)
        exp_d = P.distance(q)
        if dist_q == 0 and 0 < exp_d <= 2 * band:
            count("near ring, excluded", i)  # called on the ring (within the band): distance 0
        else:
            check("distance(point)", abs(dist_q - exp_d) <= tol, i,
                  f"ours {dist_q!r}, oracle {exp_d!r}")
        yes_no("intersectsSegment", seg_hit, P.intersects(seg),
               P.exterior.distance(seg) <= 2 * band, lambda: touches_ring_exact(ring, a2, b2), i)
        exp_len = P.intersection(seg).length if a2 != b2 else 0.0
        ok = abs(inside_len - exp_len) <= 4 * tol
        if not ok and a2 != b2:
            # Along an edge within the band the length is ill-conditioned: ours must lie between
            # the answers for the polygon shrunk and grown by the band (counted, bounded).
            for k in (1, 4):
                lo = P.buffer(-k * band).intersection(seg).length
                hi = P.buffer(k * band).intersection(seg).length
                ok = between(inside_len, lo, hi, 4 * tol)
                if ok:
                    count(f"widened x{k} band", i)
                    break
        check("inside length", ok, i, f"ours {inside_len!r}, oracle {exp_len!r}")
        if oracle_simple(c["other"]):
            O = Polygon(c["other"])
            yes_no("intersects(polygon)", poly_hit, P.intersects(O),
                   P.exterior.distance(O.exterior) <= 2 * band,
                   lambda: rings_meet_exact(ring, c["other"]), i)
            exp_d = P.distance(O)
            if poly_dist == 0 and 0 < exp_d <= 2 * band:
                count("near-touching, excluded", i)  # called touching (within the band)
            else:
                check("distance(polygon)", abs(poly_dist - exp_d) <= 4 * tol, i,
                      f"ours {poly_dist!r}, oracle {exp_d!r}")
        exp_v = violation_duration(P, c)
        ab = math.dist(a2, b2)
        # Times: rounding of the times themselves, plus a length tolerance moved along the
        # segment (an interval end moves by (tb - ta) * tol / |ab|).
        slack_t = REL_COORD * max(1.0, abs(c["tb"])) + (c["tb"] - c["ta"]) * 4 * tol / max(ab, size)
        if ab == 0:
            ok = abs(viol - exp_v) <= slack_t or P.exterior.distance(Point(a2)) <= 2 * band
        else:
            ok = abs(viol - exp_v) <= slack_t
        if not ok and ab > 0:
            for k in (1, 4):
                ok = between(viol, violation_duration(P.buffer(-k * band), c),
                             violation_duration(P.buffer(k * band), c), slack_t)
                if ok:
                    count(f"widened x{k} band", i)
                    break
        check("violation duration", ok, i, f"ours {viol!r}, oracle {exp_v!r}")
    return checks, bad, tally, by_family


def main():
    cases = [make_case() for _ in range(CASES)]
    lines = [case_line(c) for c in cases]
    text = "\n".join(lines) + "\n"
    try:
        answers = run_driver(text)
    except RuntimeError as e:
        print(e)
        return 1
    if len(answers) != len(cases):
        print(f"geometry_oracle answered {len(answers)} of {len(cases)} cases")
        return 1
    families = {}
    for c in cases:
        families[c["family"]] = families.get(c["family"], 0) + 1
    checks, bad, tally, by_family = compare(cases, lines, answers)

    total = sum(n for n, _ in checks.values())
    failed = sum(k for _, k in checks.values())
    print(f"geometry oracle: {len(cases)} cases (seed {SEED}): "
          + ", ".join(f"{k} {v}" for k, v in sorted(families.items())))
    for name, (n, k) in checks.items():
        print(f"  {name}: {n} compared, {k} disagreements beyond tolerance")
    for name, v in tally.items():
        fams = ", ".join(f"{f} {n}" for f, n in sorted(by_family.get(name, {}).items()))
        print(f"  {name}: {v}" + (f" ({fams})" if fams else ""))
    for b in bad:
        print("DISAGREE", b)

    # Bounds on what the comparison set aside or widened, and a floor on the exact boundary
    # cases (without them the yes/no checks would not test the boundary at all).
    limits = []
    n = len(cases)
    for name, lo, hi in (("on ring (exact)", 0.3, 1.0), ("segment touching (exact)", 0.3, 1.0),
                         ("polygons touching (exact)", 0.1, 1.0),
                         ("near ring, excluded", 0.0, MAX_EXCLUDED),
                         ("near-touching, excluded", 0.0, MAX_EXCLUDED),
                         ("isSimple near-degenerate", 0.0, MAX_EXCLUDED),
                         ("widened x1 band", 0.0, MAX_WIDENED),
                         ("widened x4 band", 0.0, MAX_WIDENED_4)):
        if not lo * n <= tally[name] <= hi * n:
            limits.append(f"{name}: {tally[name]} of {n} cases, expected {lo:g} to {hi:g} of them")
    for m in limits:
        print("OUT OF BOUNDS", m)

    # Negative control: the same comparison must fail on a library that calls the ring outside.
    k = min(len(cases), CONTROL_CASES)
    wrong = run_driver("\n".join(lines[:k]) + "\n", "boundary_outside")
    wchecks = compare(cases[:k], lines[:k], wrong)[0]
    caught = {name: v[1] for name, v in wchecks.items() if v[1]}
    print(f"  negative control (boundary_outside, {k} cases): disagreements {caught}")
    control_ok = (caught.get("contains [boundary, exact]", 0) > 0
                  and caught.get("intersectsSegment [boundary, exact]", 0) > 0)
    if not control_ok:
        print("NEGATIVE CONTROL FAILED: the oracle did not catch boundary = outside")
    failed += len(limits) + (not control_ok)
    total += len(limits) + 1
    print(f"{total - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
