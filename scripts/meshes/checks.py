"""Checks of the written OBJ/MTL files and of the meshes in memory."""

import os

from .parameters import UNIT_BOX, budget
from .geometry import centroid, cross, dot, norm, sub, unit
from .lod import check_levels


# ----------------------------------------------------------------------------------------------
# Checks
# ----------------------------------------------------------------------------------------------
def check_decal(pi, mat, tris, behind):
    """A decal part: one planar convex polygon (a fan of triangles), non-degenerate, wound
    consistently, facing away from `behind` (the centre of the solid it stands for)."""
    errs = []
    what = "part %d (%s, decal)" % (pi, mat)
    ns = []
    for t in tris:
        n = cross(sub(t[1], t[0]), sub(t[2], t[0]))
        if norm(n) < 1e-12:
            return [what + ": degenerate triangle %s" % (t,)]
        ns.append(unit(n))
    n0 = ns[0]
    if any(dot(n, n0) < 0.9999 for n in ns):
        errs.append(what + ": triangles not coplanar or not consistently wound")
    if any(abs(dot(sub(p, tris[0][0]), n0)) > 1e-5 for t in tris for p in t):
        errs.append(what + ": not planar")
    if dot(n0, sub(centroid([p for t in tris for p in t]), behind)) <= 0:
        errs.append(what + ": faces inward (towards the solid it stands for)")
    edges = {}
    for t in tris:
        for i in range(3):
            e = (t[i], t[(i + 1) % 3])
            edges[e] = edges.get(e, 0) + 1
    if any(k != 1 for k in edges.values()):
        return errs + [what + ": an edge used twice in the same direction"]
    nxt = {}
    for (a, b) in edges:
        if (b, a) not in edges:  # boundary edge
            if a in nxt:
                return errs + [what + ": boundary is not one simple loop"]
            nxt[a] = b
    loop = [next(iter(sorted(nxt)))] if nxt else []
    while loop and nxt[loop[-1]] != loop[0] and len(loop) <= len(nxt):
        loop.append(nxt[loop[-1]])
    if not loop or len(loop) != len(nxt) or len(tris) != len(loop) - 2:
        return errs + [what + ": not one polygon fan (boundary loop of %d edges, %d triangles)"
                       % (len(nxt), len(tris))]
    for i in range(len(loop)):
        a, b, c = loop[i - 2], loop[i - 1], loop[i]
        if dot(cross(sub(b, a), sub(c, b)), n0) < -1e-12:
            errs.append(what + ": polygon not convex")
            break
    return errs


def check_parts(m):
    """In-memory checks on the final (normalized, rounded) parts: closed, outward, convex
    (the parts of a multi-material solid together); decal and sheet parts (lod > 0): planar
    convex polygons facing outward."""
    errs = []
    solids = {}
    for pi, (mat, tris) in enumerate(m.final):
        if pi in m.final_decals:
            errs += check_decal(pi, mat, tris, m.final_decals[pi])
            continue
        g = m.groups.get(pi, pi)
        if g in solids:
            solids[g] = (solids[g][0] + "+" + mat, solids[g][1] + tris)
        else:
            solids[g] = (mat, list(tris))
    for pi, (mat, tris) in sorted(solids.items()):
        pts = [p for t in tris for p in t]
        c = centroid(pts)
        edges = {}
        for t in tris:
            n = cross(sub(t[1], t[0]), sub(t[2], t[0]))
            if norm(n) < 1e-12:
                errs.append("part %d (%s): degenerate triangle %s" % (pi, mat, t))
                continue
            if dot(n, sub(centroid(t), c)) <= 0:
                errs.append("part %d (%s): face normal points towards the part centre" % (pi, mat))
            for i in range(3):
                e = (t[i], t[(i + 1) % 3])
                edges[e] = edges.get(e, 0) + 1
        for (a, b), k in edges.items():
            if k != 1 or edges.get((b, a), 0) != 1:
                errs.append("part %d (%s): not closed/consistently wound at edge %s-%s"
                            % (pi, mat, a, b))
                break
    return errs


def check_file(path, budget, normalized, within=False):
    """Checks on the written OBJ/MTL (within: a class mesh's lod > 0, which must lie within the
    unit box instead of spanning it). Returns (errors, triangles, materials, lo, hi, per_mat)."""
    errs = []
    d = os.path.dirname(path)
    vs, vns, mats_used, ntri, cur = [], [], [], 0, None
    mtllib = None
    per_mat = {}
    with open(path) as f:
        for ln in f:
            tok = ln.split()
            if not tok or tok[0].startswith("#"):
                continue
            if tok[0] == "v":
                vs.append(tuple(float(x) for x in tok[1:4]))
            elif tok[0] == "vn":
                vns.append(tuple(float(x) for x in tok[1:4]))
            elif tok[0] == "mtllib":
                mtllib = tok[1]
            elif tok[0] == "usemtl":
                cur = tok[1]
                if cur not in mats_used:
                    mats_used.append(cur)
            elif tok[0] == "f":
                if len(tok) != 4:
                    errs.append("non-triangle face: " + ln.strip())
                    continue
                if cur is None:
                    errs.append("face before any usemtl")
                ids, nids = [], []
                for t in tok[1:]:
                    p = t.split("/")
                    if len(p) != 3 or p[1] != "":
                        errs.append("face vertex not v//vn: " + t)
                        break
                    ids.append(int(p[0]) - 1)
                    nids.append(int(p[2]) - 1)
                if len(ids) != 3:
                    continue
                if len(set(nids)) != 1:
                    errs.append("face with differing normals (not flat): " + ln.strip())
                a, b, c = (vs[i] for i in ids)
                n = cross(sub(b, a), sub(c, a))
                if norm(n) < 1e-12:
                    errs.append("degenerate face: " + ln.strip())
                elif dot(unit(n), vns[nids[0]]) < 0.999:
                    errs.append("normal disagrees with winding: " + ln.strip())
                ntri += 1
                per_mat[cur] = per_mat.get(cur, 0) + 1
    if mtllib is None:
        errs.append("no mtllib")
        defined = []
    else:
        defined = []
        mp = os.path.join(d, mtllib)
        if not os.path.exists(mp):
            errs.append("missing " + mtllib)
        else:
            with open(mp) as f:
                for ln in f:
                    tok = ln.split()
                    if tok and tok[0] == "newmtl":
                        defined.append(tok[1])
                    if tok and tok[0] == "Kd":
                        if not all(0.0 <= float(x) <= 1.0 for x in tok[1:4]):
                            errs.append("Kd out of [0,1]: " + ln.strip())
    for mname in mats_used:
        if mname not in defined:
            errs.append("usemtl %s not in %s" % (mname, mtllib))
    if ntri > budget:
        errs.append("%d triangles > budget %d" % (ntri, budget))
    lo = tuple(min(v[i] for v in vs) for i in range(3))
    hi = tuple(max(v[i] for v in vs) for i in range(3))
    if normalized and within:
        for i in range(3):
            if lo[i] < UNIT_BOX[i][0] or hi[i] > UNIT_BOX[i][1]:
                errs.append("axis %s spans [%r, %r], not within the unit box"
                            % ("xyz"[i], lo[i], hi[i]))
    elif normalized:
        for i in range(3):
            if lo[i] != UNIT_BOX[i][0] or hi[i] != UNIT_BOX[i][1]:
                errs.append("axis %s spans [%r, %r], not the unit box" % ("xyz"[i], lo[i], hi[i]))
    return errs, ntri, mats_used, lo, hi, per_mat


def run_checks(outdir, meshes=None):
    names = [m.name for m in meshes] if meshes else None
    if names is None:
        names = sorted(f[:-4] for f in os.listdir(outdir) if f.endswith(".obj"))
    ok = True
    print("%-21s %5s %6s  %-24s %s" % ("mesh", "tris", "budget", "extent (x y z)", "materials"))
    for name in names:
        normalized = name != "sentinel"
        base, _, level = name.partition("_lod")
        coarse = bool(level)
        m = [mm for mm in meshes if mm.name == name][0] if meshes else None
        if m is not None:
            budget_ = m.budget
        elif coarse:
            budget_ = budget(base, base.split("_")[0], int(level))
        else:
            budget_ = 1500 if name == "sentinel" else (300 if name == "pedestrian" else 400)
        errs, ntri, mats, lo, hi, per_mat = check_file(
            os.path.join(outdir, name + ".obj"), budget_, normalized, within=coarse)
        if m is not None:
            errs += check_parts(m)
        ext = " ".join("%.3f" % (hi[i] - lo[i]) for i in range(3))
        print("%-21s %5d %6d  %-24s %s%s" % (name, ntri, budget_, ext,
                                             " ".join("%s(%d)" % (k, per_mat[k]) for k in mats),
                                             "  [within the unit box]" if coarse else ""))
        for e in errs[:10]:
            print("    ERROR: " + e)
        if errs:
            ok = False
    print("all checks passed" if ok else "CHECKS FAILED")
    return ok


def report_levels(table):
    """Prints the level-order errors of lod.json (check_levels); True if there are none."""
    errs = check_levels(table)
    for e in errs:
        print("ERROR: lod.json levels: " + e)
    return not errs
