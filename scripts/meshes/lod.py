"""Level-of-detail deviation bounds and the lod.json table."""

import heapq
import json
import math

from .geometry import add, cross, dot, lerp, mul, norm, sub, unit


# ----------------------------------------------------------------------------------------------
# Level-of-detail deviation: an upper bound on the two-sided Hausdorff distance between the fine
# and the coarse surfaces, in design metres.
# ----------------------------------------------------------------------------------------------
DEV_SPACING = 0.005  # grid spacing on the sampled triangles (m): leaf cells have edges <= this


class TriangleSet:
    """Triangles (design metres) with exact point-to-surface distance queries, sped up by a
    uniform grid: each grid cell lists all triangles sorted by the distance between the cell's
    box and the triangle's bounding box (a lower bound on any point's distance), so a query
    stops as soon as that lower bound exceeds the nearest distance found."""

    def __init__(self, tris, cell):
        self.cell = cell
        self.tris = []
        for a, b, c in tris:
            ab, ac = sub(b, a), sub(c, a)
            n = unit(cross(ab, ac))
            lo = tuple(min(a[i], b[i], c[i]) for i in range(3))
            hi = tuple(max(a[i], b[i], c[i]) for i in range(3))
            self.tris.append((a, b, c, ab, ac, sub(c, b), n, lo, hi))
        self.cells = {}
        self.cache = {}

    def dist(self, p, k):
        """Exact distance from p to triangle k (closest point by Voronoi region, Ericson)."""
        a, b, c, ab, ac, bc, n, _, _ = self.tris[k]
        ap = (p[0] - a[0], p[1] - a[1], p[2] - a[2])
        d1 = ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2]
        d2 = ac[0] * ap[0] + ac[1] * ap[1] + ac[2] * ap[2]
        if d1 <= 0.0 and d2 <= 0.0:
            return norm(ap)
        bp = (p[0] - b[0], p[1] - b[1], p[2] - b[2])
        d3 = ab[0] * bp[0] + ab[1] * bp[1] + ab[2] * bp[2]
        d4 = ac[0] * bp[0] + ac[1] * bp[1] + ac[2] * bp[2]
        if d3 >= 0.0 and d4 <= d3:
            return norm(bp)
        vc = d1 * d4 - d3 * d2
        if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
            return norm(sub(ap, mul(ab, d1 / (d1 - d3))))
        cp = (p[0] - c[0], p[1] - c[1], p[2] - c[2])
        d5 = ab[0] * cp[0] + ab[1] * cp[1] + ab[2] * cp[2]
        d6 = ac[0] * cp[0] + ac[1] * cp[1] + ac[2] * cp[2]
        if d6 >= 0.0 and d5 <= d6:
            return norm(cp)
        vb = d5 * d2 - d1 * d6
        if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
            return norm(sub(ap, mul(ac, d2 / (d2 - d6))))
        va = d3 * d6 - d5 * d4
        if va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
            return norm(sub(bp, mul(bc, (d4 - d3) / ((d4 - d3) + (d5 - d6)))))
        return abs(n[0] * ap[0] + n[1] * ap[1] + n[2] * ap[2])  # inside: distance to the plane

    def _cell_list(self, key):
        lst = self.cells.get(key)
        if lst is None:
            s = self.cell
            clo = (key[0] * s, key[1] * s, key[2] * s)
            lst = []
            for k, t in enumerate(self.tris):
                lo, hi = t[7], t[8]
                g = 0.0
                for i in range(3):
                    e = max(lo[i] - (clo[i] + s), clo[i] - hi[i], 0.0)
                    g += e * e
                lst.append((math.sqrt(g), k))
            lst.sort()
            self.cells[key] = lst
        return lst

    def nearest(self, p):
        """(distance from p to the set, indices of the triangles within 1e-9 of it)."""
        r = self.cache.get(p)
        if r is not None:
            return r
        s = self.cell
        found = []
        best = math.inf
        for lb, k in self._cell_list((math.floor(p[0] / s), math.floor(p[1] / s),
                                      math.floor(p[2] / s))):
            if lb > best + 1e-9:
                break
            d = self.dist(p, k)
            found.append((d, k))
            if d < best:
                best = d
        r = (best, tuple(k for d, k in found if d <= best + 1e-9))
        self.cache[p] = r
        return r


def covering_radius(p0, p1, p2):
    """Largest distance from a point of the triangle to its nearest vertex (exact: the maximum
    lies on the circumcentre if inside, or where a perpendicular bisector crosses an edge)."""
    vs = (p0, p1, p2)
    cands = []
    for i in range(3):
        for j in range(i + 1, 3):
            w = sub(vs[j], vs[i])
            k = dot(vs[j], vs[j]) - dot(vs[i], vs[i])
            for e in range(3):
                a, b = vs[e], vs[(e + 1) % 3]
                ew = dot(sub(b, a), w)
                if abs(ew) > 1e-15:
                    t = (k - 2.0 * dot(a, w)) / (2.0 * ew)
                    if 0.0 <= t <= 1.0:
                        cands.append(lerp(a, b, t))
    ab, ac = sub(p1, p0), sub(p2, p0)
    n = cross(ab, ac)
    nn = dot(n, n)
    cc = add(p0, mul(add(mul(cross(n, ab), dot(ac, ac)), mul(cross(ac, n), dot(ab, ab))),
                     0.5 / nn))  # circumcentre
    v = sub(cc, p0)
    d00, d01, d11 = dot(ab, ab), dot(ab, ac), dot(ac, ac)
    den = d00 * d11 - d01 * d01
    b1 = (d11 * dot(v, ab) - d01 * dot(v, ac)) / den
    b2 = (d00 * dot(v, ac) - d01 * dot(v, ab)) / den
    if b1 >= 0.0 and b2 >= 0.0 and b1 + b2 <= 1.0:
        cands.append(cc)
    return max([min(norm(sub(c, p)) for p in vs) for c in cands] + [0.0])


def directed_bound(tris, target, spacing=DEV_SPACING):
    """(upper, lower) bounds on max over the surface `tris` of the distance to `target`.

    Every triangle is sampled on its barycentric grid of 2^k subdivisions (cell edges <=
    spacing), refined best-first. A cell's bound is the smaller of
      * max vertex distance + the cell's covering radius (the distance is 1-Lipschitz), and
      * max over its vertices of the distance to ONE triangle S of the target (the distance to
        a triangle is convex, so its maximum over the cell is at a vertex), S among the
        nearest triangles of the cell's vertices (0 when the cell lies in S, e.g. shared faces).
    Cells whose bound cannot exceed the largest sample distance or leaf bound so far are not
    refined; the result `upper` bounds the distance over every point of the surface, `lower`
    is the largest distance found at a sample (the true maximum lies in between)."""
    heap = []
    lower = 0.0
    count = 0

    def vertex(p):
        nonlocal lower
        r = target.nearest(p)
        if r[0] > lower:
            lower = r[0]
        return r

    def bound(vs, rs, cov):
        ub = max(r[0] for r in rs) + cov
        for k in sorted(set(k for r in rs for k in r[1])):
            m = 0.0
            for p, r in zip(vs, rs):
                d = r[0] if k in r[1] else target.dist(p, k)
                if d > m:
                    m = d
                    if m >= ub:
                        break
            if m < ub:
                ub = m
        return ub

    for t in tris:
        rs = [vertex(p) for p in t]
        cov = covering_radius(*t)
        edge = max(norm(sub(t[1], t[0])), norm(sub(t[2], t[1])), norm(sub(t[0], t[2])))
        heap.append((-bound(t, rs, cov), count, t, rs, cov, edge))
        count += 1
    heapq.heapify(heap)
    upper = 0.0
    while heap:
        nub, _, t, rs, cov, edge = heapq.heappop(heap)
        if -nub <= max(lower, upper):
            break
        if edge <= spacing:
            upper = -nub
            continue
        m01, m12, m20 = (tuple((t[i][j] + t[(i + 1) % 3][j]) * 0.5 for j in range(3))
                         for i in range(3))
        r01, r12, r20 = vertex(m01), vertex(m12), vertex(m20)
        for vs, rr in (((t[0], m01, m20), (rs[0], r01, r20)), ((m01, t[1], m12), (r01, rs[1], r12)),
                       ((m20, m12, t[2]), (r20, r12, rs[2])), ((m01, m12, m20), (r01, r12, r20))):
            ub = bound(vs, rr, cov * 0.5)
            if ub > max(lower, upper):
                heapq.heappush(heap, (-ub, count, vs, rr, cov * 0.5, edge * 0.5))
                count += 1
    return max(lower, upper), lower


def lod_deviation(fine, coarse, spacing=DEV_SPACING):
    """Upper bound (design metres) on the two-sided Hausdorff distance between the fine and the
    coarse mesh as written (their final coordinates scaled back by the design size), foliage
    and the rest separately: returns {"foliage"|"other": (upper, lower)}."""
    size = fine.design_size

    def groups(m):
        g = {"foliage": [], "other": []}
        for mat, tris in m.final:
            g["foliage" if mat == "foliage" else "other"] += [
                tuple((p[0] * size[0], p[1] * size[1], p[2] * size[2]) for p in t) for t in tris]
        return g

    gf, gc = groups(fine), groups(coarse)
    cell = max(size) / 24.0
    out = {}
    for key in ("other", "foliage"):
        if not gf[key] and not gc[key]:
            continue
        assert gf[key] and gc[key], (coarse.name, key)
        ab = directed_bound(gf[key], TriangleSet(gc[key], cell), spacing)
        ba = directed_bound(gc[key], TriangleSet(gf[key], cell), spacing)
        out[key] = (max(ab[0], ba[0]), max(ab[1], ba[1]))
    return out


def round_up_mm(x):
    return math.ceil((x + 1e-9) * 1000.0) / 1000.0


LOD_NOTE = ("upper bound, in design metres, on the two-sided Hausdorff distance between the fine "
            "mesh and the level's surface as written (foliage to foliage and the rest to the rest, "
            "the larger), rounded up to the millimetre; every level is measured against the fine "
            "mesh; the renderer scales axis i by box_i / design_size_m[i], so in its metres the "
            "bound is max_deviation_m * max_i(box_i / design_size_m[i]) (foliage scaled by s <= 1 "
            "about the fine canopy centre: times s or less)")


def lod_table(meshes):
    """[(fine, coarse, {"foliage"|"other": (upper, lower)})] for every coarse mesh (finalized),
    in the order of `meshes`."""
    by_name = {m.name: m for m in meshes}
    return [(by_name[m.base], m, lod_deviation(by_name[m.base], m)) for m in meshes if m.lod]


def ntris(m):
    return sum(len(t) for _, t in m.final)


def max_deviation(dev):
    return round_up_mm(max(v[0] for v in dev.values()))


def lod_levels(table):
    """[(fine, [(coarse, dev), ...] finest level first)] in the order of the fine meshes'
    first coarse level in `table`."""
    out, index = [], {}
    for fine, coarse, dev in table:
        if fine.name not in index:
            index[fine.name] = len(out)
            out.append((fine, []))
        out[index[fine.name]][1].append((coarse, dev))
    for _, levels in out:
        levels.sort(key=lambda cd: cd[0].lod)
    return out


def check_levels(table):
    """Errors: a mesh whose levels do not have strictly fewer triangles and a strictly larger
    deviation than the previous one (the fine mesh: deviation 0)."""
    errs = []
    for fine, levels in lod_levels(table):
        tris, dev = ntris(fine), 0.0
        for coarse, d in levels:
            if not (ntris(coarse) < tris and max_deviation(d) > dev):
                errs.append("%s: %d triangles, deviation %.3f m after %d, %.3f m"
                            % (coarse.name, ntris(coarse), max_deviation(d), tris, dev))
            tris, dev = ntris(coarse), max_deviation(d)
    return errs


def lod_json(table):
    """The text of models/meshes/lod.json (one mesh per line, deterministic)."""
    rows = []
    for fine, levels in lod_levels(table):
        rows.append(json.dumps({
            "mesh": fine.name, "triangles": ntris(fine),
            "design_size_m": [round(x, 6) for x in fine.design_size],
            "levels": [{"file": coarse.name + ".obj", "triangles": ntris(coarse),
                        "max_deviation_m": max_deviation(dev)} for coarse, dev in levels]}))
    return ("{\n"
            '  "schema": "hameritt_mesh_lod",\n'
            '  "schema_version": 2,\n'
            '  "generator": "scripts/make_meshes.py",\n'
            '  "max_deviation_note": %s,\n'
            '  "meshes": [\n    %s\n  ]\n}\n' % (json.dumps(LOD_NOTE), ",\n    ".join(rows)))


def foliage_centre(m):
    """Centre of the bounding box of the foliage triangles, design metres (None if none)."""
    pts = [p for mat, tris in m.final if mat == "foliage" for t in tris for p in t]
    if not pts:
        return None
    return tuple(0.5 * (min(p[i] for p in pts) + max(p[i] for p in pts)) * m.design_size[i]
                 for i in range(3))


def print_lod_table(table):
    print("%-21s %5s %5s  %-9s %s" % ("level", "tris", "fine", "deviation",
                                      "(design m; found at a sample .. bound, per surface)"))
    for fine, coarse, dev in table:
        extra = ""
        fc, cc = foliage_centre(fine), foliage_centre(coarse)
        if fc is not None:
            extra = "; canopy centre offset %s m" % " ".join("%+.4f" % (cc[i] - fc[i])
                                                             for i in range(3))
        print("%-21s %5d %5d  %-9.3f %s%s" % (
            coarse.name, ntris(coarse), ntris(fine), max_deviation(dev),
            ", ".join("%s %.4f .. %.4f" % (k, v[1], v[0]) for k, v in sorted(dev.items())),
            extra))
