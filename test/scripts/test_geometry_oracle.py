#!/usr/bin/python3
"""Geometry oracle: our polygon operations and keep-out-zone checker against Shapely (GEOS).

Generates CASES (default 100,000) seeded cases, random and adversarial (touching edges,
collinear overlaps, vertices on edges, segments through vertices, tiny zones, huge
coordinates, degenerate segments, self-touching rings), answers them all with one run of
$HAMERITT_BIN_DIR/geometry_oracle (our C++: geometry::Polygon, adk::segmentInsidePolygon,
adk::violationIntervals), and compares every answer with an independent computation on
python3-shapely:

  area                  Polygon.area                      |diff| <= TOL * L^2
  contains(q)           Polygon.intersects(Point)         equal, or q within TOL of the ring
  distance(q)           Polygon.distance(Point)           |diff| <= TOL
  intersectsSegment     Polygon.intersects(LineString)    equal, or the segment within TOL
  inside length         intersection(LineString).length   |diff| <= TOL
  intersects(other)     Polygon.intersects(Polygon)       equal, or the polygons within TOL
  distance(other)       Polygon.distance(Polygon)         |diff| <= TOL
  isSimple              is_valid, >= 3 distinct vertices, no repeated consecutive vertex
  violation duration    Shapely pieces of the 2-D segment, clipped to the altitude band
                        and the time window in Python  |diff| <= TOL_T

TOL = 1e-9 * max(1, L) where L is the largest coordinate magnitude of the case: our code
works in doubles with 1e-9 tolerances (geometry::kEpsilon, the KOZ parameter tolerance), so a
point within TOL of an edge may be called on it. TOL_T = 1e-9 * max(1, |tb|) + (tb - ta) *
TOL / |ab| (an edge moved by TOL moves an entry time by that much). Booleans get no tolerance
beyond "the two shapes are within TOL of each other"; isSimple none beyond "the ring is within
TOL of a non-simple one". Where a segment runs along an edge (collinear within rounding) the
inside length is ill-conditioned (GEOS itself may answer 0): a length or duration that misses
the direct comparison must lie between the answers for the polygon shrunk and grown by 4 TOL,
or, counted and printed, by WIDE = 16 TOL (near-tangent segments).

Prints the counts per case family and per check; exits 1 on any disagreement beyond the
tolerance (the first ones are listed with the case line, to reproduce by hand:
  echo 'LINE' | $HAMERITT_BIN_DIR/geometry_oracle).
"""

import math
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
REL = 1e-9
# Near-tangent segments: a point within TOL of an edge counts as inside, so where a segment runs
# almost along an edge an interval end may move along it by several TOL (seen: 11 TOL on a
# micrometre sliver zone). Answers within the polygon grown/shrunk by WIDE TOL pass, counted.
WIDE = 16
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
    return [(cx + r * (1 - jitter * rng.random()) * math.cos(a),
             cy + r * (1 - jitter * rng.random()) * math.sin(a)) for a in angles]


def rect(x0, y0, x1, y1):
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def on_edge(poly, t=None):
    """A point on the polygon's ring (vertex when t is 0)."""
    i = rng.randrange(len(poly))
    (x0, y0), (x1, y1) = poly[i], poly[(i + 1) % len(poly)]
    t = rng.choice([0.0, 0.5, 0.25, rng.random()]) if t is None else t
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
        s, t = rng.choice([(-0.5, 0.5), (0.25, 1.5), (-1, 2), (0.2, 0.7), (1.0, 2.0)])
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


# ---------------------------------------------------------------- run and compare
def main():
    binary = os.path.join(os.environ.get("HAMERITT_BIN_DIR", ""), "geometry_oracle")
    cases = [make_case() for _ in range(CASES)]
    text = "\n".join(case_line(c) for c in cases) + "\n"
    proc = subprocess.run([binary], input=text, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        print("geometry_oracle failed:", proc.stderr[-2000:])
        return 1
    answers = proc.stdout.splitlines()
    if len(answers) != len(cases):
        print(f"geometry_oracle answered {len(answers)} of {len(cases)} cases")
        return 1
    lines = text.splitlines()
    checks = {}
    bad = []
    wide = [0, 0]  # answers accepted with the polygon grown/shrunk by 4 TOL, by WIDE TOL
    families = {}

    def check(name, ok, i, detail):
        n = checks.setdefault(name, [0, 0])
        n[0] += 1
        if not ok:
            n[1] += 1
            if len(bad) < 20:
                bad.append(f"{name} ({cases[i]['family']}): {detail}\n  case: {lines[i]}")

    for i, (c, ans) in enumerate(zip(cases, answers)):
        families[c["family"]] = families.get(c["family"], 0) + 1
        f = ans.split()
        area, contains, dist_q = float(f[0]), f[1] == "1", float(f[2])
        seg_hit, inside_len = f[3] == "1", float(f[4])
        poly_hit, poly_dist, simple, viol = f[6] == "1", float(f[7]), f[8] == "1", float(f[9])
        coords = [abs(x) for p in c["poly"] + c["other"] + [c["a"][:2], c["b"][:2], c["q"]] for x in p]
        scale = max(1.0, max(coords))
        tol = REL * scale
        expect_simple = oracle_simple(c["poly"])
        check("isSimple", simple == expect_simple or near_degenerate(c["poly"], tol), i,
              f"ours {simple}, oracle {expect_simple}")
        if not (expect_simple and simple):
            continue  # Shapely's other answers are undefined for invalid polygons
        P = Polygon(c["poly"])
        a2, b2 = c["a"][:2], c["b"][:2]
        q = Point(c["q"])
        seg = shape2(a2, b2)
        check("area", abs(area - P.area) <= REL * scale * scale, i, f"ours {area!r}, oracle {P.area!r}")
        exp = P.intersects(q)
        check("contains", contains == exp or P.exterior.distance(q) <= tol, i,
              f"ours {contains}, oracle {exp}, ring distance {P.exterior.distance(q)!r}")
        exp_d = P.distance(q)
        check("distance(point)", abs(dist_q - exp_d) <= tol, i, f"ours {dist_q!r}, oracle {exp_d!r}")
        exp = P.intersects(seg)
        check("intersectsSegment", seg_hit == exp or P.exterior.distance(seg) <= tol, i,
              f"ours {seg_hit}, oracle {exp}, ring distance {P.exterior.distance(seg)!r}")
        exp_len = P.intersection(seg).length if a2 != b2 else 0.0
        ok = abs(inside_len - exp_len) <= tol * 4
        if not ok and a2 != b2:
            # Along an edge within rounding the length is ill-conditioned: ours must lie between
            # the answers for the polygon shrunk and grown by 4 TOL.
            for k in (4, WIDE):
                lo = P.buffer(-k * tol).intersection(seg).length
                hi = P.buffer(k * tol).intersection(seg).length
                ok = between(inside_len, lo, hi, k * tol)
                if ok:
                    wide[k == WIDE] += 1
                    break
        check("inside length", ok, i, f"ours {inside_len!r}, oracle {exp_len!r}")
        if oracle_simple(c["other"]):
            O = Polygon(c["other"])
            exp = P.intersects(O)
            check("intersects(polygon)", poly_hit == exp or P.exterior.distance(O.exterior) <= tol, i,
                  f"ours {poly_hit}, oracle {exp}")
            exp_d = P.distance(O)
            check("distance(polygon)", abs(poly_dist - exp_d) <= tol, i,
                  f"ours {poly_dist!r}, oracle {exp_d!r}")
        exp_v = violation_duration(P, c)
        ab = math.dist(a2, b2)
        if ab == 0:
            ok = abs(viol - exp_v) <= REL * max(1.0, c["tb"]) or P.exterior.distance(Point(a2)) <= tol
        else:
            ok = abs(viol - exp_v) <= REL * max(1.0, c["tb"]) + (c["tb"] - c["ta"]) * 4 * tol / ab
        if not ok:
            slack = REL * max(1.0, c["tb"]) + (c["tb"] - c["ta"]) * 4 * tol / max(ab, tol)
            for k in (4, WIDE):
                ok = between(viol, violation_duration(P.buffer(-k * tol), c),
                             violation_duration(P.buffer(k * tol), c), k / 4 * slack)
                if ok:
                    wide[k == WIDE] += 1
                    break
        check("violation duration", ok, i, f"ours {viol!r}, oracle {exp_v!r}")

    total = sum(n for n, _ in checks.values())
    failed = sum(k for _, k in checks.values())
    print(f"geometry oracle: {len(cases)} cases (seed {SEED}): "
          + ", ".join(f"{k} {v}" for k, v in sorted(families.items())))
    print(f"  lengths and durations accepted only with the polygon grown/shrunk by 4 TOL: "
          f"{wide[0]}, by {WIDE} TOL (near-tangent segments): {wide[1]}")
    for name, (n, k) in checks.items():
        print(f"  {name}: {n} compared, {k} disagreements beyond tolerance")
    for b in bad:
        print("DISAGREE", b)
    print(f"{total - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
