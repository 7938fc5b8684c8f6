#!/usr/bin/env python3
"""Generate the low-poly Wavefront OBJ/MTL meshes of hameritt's renderer (models/meshes/).

    /usr/bin/python3 scripts/make_meshes.py            # write models/meshes/*.obj|mtl, then check them
    /usr/bin/python3 scripts/make_meshes.py --check    # only check the files already there
    /usr/bin/python3 scripts/make_meshes.py --out DIR  # write somewhere else

Standard library only and deterministic: running it twice gives byte-identical files. Besides
the fine meshes it writes coarse levels of detail of the class meshes (<name>_lod1.obj and, for
the heaviest, <name>_lod2.obj, from the same builders with lod=1 or 2) and lod.json (an upper
bound on each level's deviation from the fine mesh).

Conventions (the renderer depends on them; see models/README.md):
* triangles only, every face "f v//vn" with its own (flat) normal, counter-clockwise seen from
  outside; every part is a closed convex solid (boxes, prisms, cylinders, cones, icospheres;
  at lod2 a few of them have faces of two materials), except the decals and sheets of coarse
  meshes (one planar convex polygon seen from one side: a thin slab's outer face or mid-plane).
* coarse meshes are normalized with their fine mesh's bounds: they lie within the unit box.
* class meshes: x forward (heading), y left, z up, origin at the centre of the bottom face; the
  vertices span exactly [-0.5, 0.5] x [-0.5, 0.5] x [0, 1] (the renderer scales each axis by the
  entity's box). Each part is designed in metres at a typical real size, then normalized.
* sentinel.obj (the UAV) stays in metres, base_link FLU frame, origin at the centre of mass.
* materials: one .mtl per .obj; "paint" is replaced by the entity colour at render time.
"""

import heapq
import json
import math
import os
import sys

FMT = "%.6f"
LOD_FILE = "lod.json"
UNIT_BOX = ((-0.5, 0.5), (-0.5, 0.5), (0.0, 1.0))

# ----------------------------------------------------------------------------------------------
# Materials (Kd). "paint" differs per mesh (a plausible default; the renderer replaces it).
# ----------------------------------------------------------------------------------------------
KD = {
    "roof": (0.30, 0.28, 0.27),
    "trim": (0.93, 0.93, 0.90),
    "window": (0.20, 0.26, 0.32),
    "door": (0.42, 0.24, 0.15),
    "garage_door": (0.86, 0.85, 0.81),
    "chimney": (0.55, 0.30, 0.24),
    "trunk": (0.40, 0.28, 0.18),
    "foliage": (0.26, 0.46, 0.19),
    "tire": (0.08, 0.08, 0.08),
    "glass": (0.14, 0.19, 0.24),
    "light_front": (0.95, 0.95, 0.86),
    "light_rear": (0.75, 0.08, 0.06),
    "bumper": (0.18, 0.18, 0.19),
    "skin": (0.80, 0.62, 0.50),
    "hair": (0.20, 0.14, 0.10),
    "pants": (0.20, 0.25, 0.36),
    "shoe": (0.12, 0.12, 0.12),
    "frame": (0.16, 0.16, 0.17),
    "arm": (0.22, 0.22, 0.24),
    "motor": (0.55, 0.55, 0.58),
    "prop": (0.10, 0.10, 0.10),
    "camera": (0.05, 0.05, 0.06),
}


# Triangle budgets of the class meshes per level of detail (lod1, lod2: the coarse meshes; a
# mesh name overrides its class). The pickup's open bed is three more boxes.
LOD_BUDGET = {0: {"house": 400, "garage": 400, "tree": 400, "car": 400, "fence": 400},
              1: {"house": 150, "garage": 80, "tree": 150, "car": 200, "car_pickup": 230,
                  "fence": 24, "tree_pine": 50},
              2: {"house": 50, "garage": 30, "tree": 40, "car": 60, "tree_pine": 24}}


def budget(name, cls, lod):
    return LOD_BUDGET[lod].get(name, LOD_BUDGET[lod][cls])


# lod1 canopy icosahedra: vertex radius / icosphere radius. Chosen numerically: it minimises
# the two-sided deviation of the lod1 canopy to the fine one (0.165 m; 0.314 m with the vertices
# on the icosphere, scale 1.0). For a sphere the balance is 1.0777 (deviation 0.078 r).
ICO_LOD_SCALE = 1.083

# lod2 canopy: per icosphere of the deciduous canopy (in make_tree_deciduous's order), a
# polyhedron in the icosphere's unit frame (then scaled by its radii): ("octahedron", rotation,
# vertex radii of its three axes) or ("bipyramid", sides, rotation, ring radius, pole radius,
# ring phase); rotation (ax, ay, az): Rz(az) Ry(ay) Rx(ax), its columns the polyhedron's axes.
# Found by a random search that minimised each one's sampled two-sided distance to its
# icosphere, within the unit box (crown 0.43 m with a pentagonal bipyramid, 0.49 m with the best
# octahedron found; the others 0.41-0.43 m).
LOD2_CANOPY = [("bipyramid", 5, (0.9816, -0.4301, -0.3465), 1.1917, 1.1904, -1.1382),
               ("octahedron", (-0.5765, 0.9542, 0.5369), (1.2271, 1.2206, 1.2574)),
               ("octahedron", (-0.3875, 0.7604, 0.325), (1.22, 1.22, 1.22)),
               ("octahedron", (-0.3875, 0.7604, 0.325), (1.22, 1.22, 1.22))]

# lod2 roof sheets (houses, garages): the roof slab collapsed to one plane per slope, this
# fraction of the slab thickness below its top at the ridge and at the eaves (the ridge cap
# stands above the ridge, the fascia hangs below the eaves).
LOD2_ROOF_SHEET = (0.32, 0.625)
# lod2 cars: the body's front and rear faces move this far inside the bumpers' outer faces
# (halfway through the 0.2 m bumpers, which are dropped), and the cabin's bottom reaches this
# far below the simplified body's top (so that no crack opens between them).
LOD2_BUMPER_INSET = 0.1
LOD2_CABIN_SINK = 0.02
# lod2 trunks (deciduous, pine): a triangular pyramid, base corner radius / the fine trunk's
# base radius, apex height / the fine trunk's height
LOD2_TRUNK = (1.33, 1.0)
# pine levels: trunk (sides, phase, radius scale; None: lod2_trunk), then per cone (sides,
# phase, radius scale); chosen numerically (a small grid over phases and scales)
LOD_PINE = {1: ((3, math.pi / 2, 1.33), [(10, 0.0, 1.0), (8, math.pi / 8, 1.02),
                                         (6, math.pi / 12, 1.035)]),
            2: (None, [(4, math.pi / 4, 1.15), (4, 0.0, 1.15), (4, math.pi / 4, 1.15)])}
# lod2 cars that keep their mirrors (as sheets on the mirrors' mid-planes, facing out)
LOD2_MIRRORS = ("car_sedan", "car_suv", "car_hatchback", "car_van")
# lod2 wheels: square sheets on the tyre's two faces, half-size / tyre radius
LOD2_WHEEL = 0.9

# ----------------------------------------------------------------------------------------------
# Small vector helpers
# ----------------------------------------------------------------------------------------------
def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def mul(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    return math.sqrt(dot(a, a))


def unit(a):
    n = norm(a)
    return (a[0] / n, a[1] / n, a[2] / n)


def lerp(a, b, t):
    return (a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t)


def centroid(points):
    n = float(len(points))
    return (sum(p[0] for p in points) / n, sum(p[1] for p in points) / n,
            sum(p[2] for p in points) / n)


def fmt(v):
    s = FMT % v
    if float(s) == 0.0:
        s = FMT % 0.0
    return s


def rnd(v):
    return float(fmt(v))


# ----------------------------------------------------------------------------------------------
# Mesh: a list of parts; each part is one closed convex solid of one material (or, lod > 0, a
# decal or sheet: one planar convex polygon seen from one side). A closed convex solid with faces
# of two materials (lod2) is one part per material, tied together in `groups`.
# ----------------------------------------------------------------------------------------------
class Mesh:
    def __init__(self, name, budget, normalized=True, paint=(0.8, 0.8, 0.8), lod=0):
        self.base = name           # the class mesh this is a level of detail of
        self.lod = lod
        self.name = name if lod == 0 else "%s_lod%d" % (name, lod)
        self.budget = budget
        self.normalized = normalized
        self.paint = paint
        self.kd_override = {}
        self.parts = []  # (material, [triangles (p0, p1, p2)])
        self.decals = {}  # part index -> a point behind the decal (centre of the solid it replaces)
        self.groups = {}  # part index -> index of the first part of its multi-material solid
        self.bounds_from = None  # lod > 0: the fine Mesh whose design bounds normalize this one

    # -- the one primitive everything is built from -------------------------------------------
    def solid(self, mat, polygons):
        """A closed convex solid given by its face polygons (any winding): every polygon is
        turned to face away from the solid's centre, then fan-triangulated."""
        c = centroid([p for poly in polygons for p in poly])
        tris = []
        for poly in polygons:
            tris += outward_fan(poly, c)
        self.parts.append((mat, tris))

    def solid_mats(self, mats, polygons):
        """A closed convex solid whose face polygons[i] has material mats[i] (one part per
        material, in order of first use, checked together as one solid)."""
        c = centroid([p for poly in polygons for p in poly])
        first = len(self.parts)
        for mat in [mt for i, mt in enumerate(mats) if mt not in mats[:i]]:
            tris = []
            for mt, poly in zip(mats, polygons):
                if mt == mat:
                    tris += outward_fan(poly, c)
            self.groups[len(self.parts)] = first
            self.parts.append((mat, tris))

    def sheet(self, mat, poly, behind):
        """Level of detail > 0: one planar convex polygon facing away from the point `behind`
        (the centre of what it stands for): a thin slab's outer face (a decal) or mid-plane, or a
        face of a part whose other faces are dropped. Seen from behind it is culled."""
        self.decals[len(self.parts)] = behind
        self.parts.append((mat, outward_fan(poly, behind)))

    def box_sheet(self, mat, lo, hi, face, frac):
        """A sheet parallel to the box face `face` ("x"|"y"|"z", +1|-1), `frac` of the box's
        thickness out from the opposite face (0.5: the mid-plane; 1: the face itself), facing
        that way."""
        axis, sg = face
        i = "xyz".index(axis)
        poly = box_faces(lo, hi, (self.name, mat))[BOX_FACE[face]]
        w = lo[i] + (hi[i] - lo[i]) * (frac if sg > 0 else 1.0 - frac)
        poly = [tuple(w if j == i else p[j] for j in range(3)) for p in poly]
        behind = [0.5 * (lo[j] + hi[j]) for j in range(3)]
        behind[i] = lo[i] if sg > 0 else hi[i]
        self.sheet(mat, poly, tuple(behind))

    def decal(self, mat, polygons, k):
        """Level of detail > 0: instead of the closed convex solid `polygons` (a thin slab on a
        host face), only its outer face polygons[k], triangulated exactly as solid() would
        (facing away from the solid's centre, counter-clockwise seen from outside). The one
        exception to the closed-part convention: a planar convex polygon seen only from outside."""
        c = centroid([p for poly in polygons for p in poly])
        self.decals[len(self.parts)] = c
        self.parts.append((mat, outward_fan(polygons[k], c)))

    def hexa(self, mat, bottom, top):
        """Hexahedron from two corresponding quads (planar faces expected)."""
        self.solid(mat, hexa_faces(bottom, top))

    def box(self, mat, lo, hi):
        self.solid(mat, box_faces(lo, hi, (self.name, mat)))

    def box_or_decal(self, mat, lo, hi, face):
        """A box, or (lod > 0) a decal on its face ("x"|"y"|"z", +1|-1)."""
        if self.lod:
            self.decal(mat, box_faces(lo, hi, (self.name, mat)), BOX_FACE[face])
        else:
            self.box(mat, lo, hi)

    def extrude(self, mat, poly, offset):
        """Prism: a convex planar polygon and its copy moved by offset."""
        top = [add(p, offset) for p in poly]
        n = len(poly)
        faces = [list(poly), top]
        for i in range(n):
            j = (i + 1) % n
            faces.append([poly[i], poly[j], top[j], top[i]])
        self.solid(mat, faces)

    def ring(self, c, r, n, u, v, phase):
        return [add(c, add(mul(u, r * math.cos(phase + 2 * math.pi * k / n)),
                           mul(v, r * math.sin(phase + 2 * math.pi * k / n)))) for k in range(n)]

    def frustum(self, mat, a, b, ra, rb, n, u_hint=(1, 0, 0), v_hint=None, phase=0.0):
        """n-sided prism/frustum from point a (radius ra) to point b (radius rb)."""
        u, v = basis(sub(b, a), u_hint, v_hint)
        ra_ = self.ring(a, ra, n, u, v, phase)
        rb_ = self.ring(b, rb, n, u, v, phase)
        faces = [ra_, rb_]
        for i in range(n):
            j = (i + 1) % n
            faces.append([ra_[i], ra_[j], rb_[j], rb_[i]])
        self.solid(mat, faces)

    def cone(self, mat, base, apex, r, n, u_hint=(1, 0, 0), v_hint=None, phase=0.0):
        u, v = basis(sub(apex, base), u_hint, v_hint)
        rg = self.ring(base, r, n, u, v, phase)
        faces = [rg] + [[rg[i], rg[(i + 1) % n], apex] for i in range(n)]
        self.solid(mat, faces)

    def beam(self, mat, a, b, side, wa, ha, wb=None, hb=None):
        """Box-like beam from a to b; cross-section half-width w along `side` (made
        perpendicular to the axis) and half-height h along axis x side; tapered if wb/hb."""
        wb = wa if wb is None else wb
        hb = ha if hb is None else hb
        u, v = basis(sub(b, a), side, None)

        def quad(c, w, h):
            return [add(c, add(mul(u, su * w), mul(v, sv * h)))
                    for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1))]

        self.hexa(mat, quad(a, wa, ha), quad(b, wb, hb))

    def ellipsoid(self, mat, c, radii, lod2_shape=None):
        """Icosphere (one subdivision, 80 triangles) scaled to the radii; it has vertices on
        the six axis points, so its extents are exactly c +- radii. Level of detail 1: the
        base icosahedron (20 triangles) scaled by ICO_LOD_SCALE (extents +-0.8507 * that);
        2: the polyhedron lod2_shape (see LOD2_CANOPY)."""
        faces = []
        for tri in (unit_polyhedron(lod2_shape) if self.lod >= 2 else
                    icosahedron(ICO_LOD_SCALE) if self.lod else icosphere1()):
            faces.append([add(c, (p[0] * radii[0], p[1] * radii[1], p[2] * radii[2]))
                          for p in tri])
        self.solid(mat, faces)

    def slab(self, mat, quad, host_centre, t_out, t_in):
        """A thin box on a planar face: quad (4 coplanar points on the host's face), pushed
        t_out outward and t_in inward (outward = away from host_centre)."""
        n = unit(cross(sub(quad[1], quad[0]), sub(quad[3], quad[0])))
        if dot(n, sub(centroid(quad), host_centre)) < 0:
            n = mul(n, -1.0)
        faces = hexa_faces([sub(p, mul(n, t_in)) for p in quad],
                           [add(p, mul(n, t_out)) for p in quad])
        if self.lod:
            self.decal(mat, faces, 1)  # the outer face
        else:
            self.solid(mat, faces)

    # -- output -----------------------------------------------------------------------------------
    def design_bounds(self):
        """(lo, hi) of the design-metre vertices: the normalization of this mesh, or (lod > 0)
        of its fine mesh, so that both overlap exactly when scaled by the same box."""
        if self.bounds_from is not None:
            return self.bounds_from.design_bounds()
        pts = [p for _, tris in self.parts for t in tris for p in t]
        lo = [min(p[i] for p in pts) for i in range(3)]
        hi = [max(p[i] for p in pts) for i in range(3)]
        return lo, hi

    def finalize(self):
        """Normalize (class meshes) and round; returns [(mat, [tri])] in final coordinates."""
        lo, hi = self.design_bounds()

        def unrounded(p):
            q = [(p[i] - lo[i]) / (hi[i] - lo[i]) for i in range(3)]
            return (q[0] - 0.5, q[1] - 0.5, q[2])

        def tf(p):
            if not self.normalized:
                return (rnd(p[0]), rnd(p[1]), rnd(p[2]))
            q = [(p[i] - lo[i]) / (hi[i] - lo[i]) for i in range(3)]
            return (rnd(q[0] - 0.5), rnd(q[1] - 0.5), rnd(q[2]))

        self.design_size = tuple(hi[i] - lo[i] for i in range(3))
        self.final = [(mat, [tuple(tf(p) for p in t) for t in tris]) for mat, tris in self.parts]
        self.final_decals = {k: unrounded(c) if self.normalized else c
                             for k, c in self.decals.items()}
        return self.final

    def materials(self):
        mats = []
        for mat, _ in self.parts:
            if mat not in mats:
                mats.append(mat)
        return mats

    def kd(self, mat):
        if mat in self.kd_override:
            return self.kd_override[mat]
        if mat == "paint":
            return self.paint
        return KD[mat]

    def write(self, outdir):
        final = self.finalize()
        mats = self.materials()
        vidx, vlist, nidx, nlist = {}, [], {}, []
        faces = {m: [] for m in mats}
        for mat, tris in final:
            for t in tris:
                nrm = unit(cross(sub(t[1], t[0]), sub(t[2], t[0])))
                nk = " ".join(fmt(c) for c in nrm)
                if nk not in nidx:
                    nidx[nk] = len(nlist) + 1
                    nlist.append(nk)
                ids = []
                for p in t:
                    k = " ".join(fmt(c) for c in p)
                    if k not in vidx:
                        vidx[k] = len(vlist) + 1
                        vlist.append(k)
                    ids.append(vidx[k])
                faces[mat].append((ids, nidx[nk]))
        ntri = sum(len(f) for f in faces.values())
        lines = ["# hameritt %s: generated by scripts/make_meshes.py, do not edit" % self.name,
                 "# %s, %d triangles, materials: %s" % (
                     "unit box [-0.5,0.5]x[-0.5,0.5]x[0,1], x forward, y left, z up"
                     if self.normalized else "metres, base_link FLU frame", ntri, " ".join(mats))]
        if self.lod:
            lines.append("# level of detail %d of %s.obj: normalized with its design bounds (lies "
                         "within the unit box), deviation bound in %s" % (self.lod, self.base,
                                                                          LOD_FILE))
        lines += ["mtllib %s.mtl" % self.name, "o %s" % self.name]
        lines += ["v " + k for k in vlist]
        lines += ["vn " + k for k in nlist]
        for m in mats:
            lines.append("usemtl " + m)
            for ids, n in faces[m]:
                lines.append("f %d//%d %d//%d %d//%d" % (ids[0], n, ids[1], n, ids[2], n))
        with open(os.path.join(outdir, self.name + ".obj"), "w", newline="\n") as f:
            f.write("\n".join(lines) + "\n")
        ml = ["# hameritt %s materials: generated by scripts/make_meshes.py, do not edit"
              % self.name]
        for m in mats:
            kd = self.kd(m)
            ml += ["", "newmtl " + m, "Ka 0.000000 0.000000 0.000000",
                   "Kd " + " ".join(fmt(c) for c in kd), "Ks 0.000000 0.000000 0.000000",
                   "Ns 1.000000", "d 1.000000", "illum 1"]
        with open(os.path.join(outdir, self.name + ".mtl"), "w", newline="\n") as f:
            f.write("\n".join(ml) + "\n")
        return ntri


def outward_fan(poly, c):
    """Fan triangles of a convex planar polygon, turned to face away from the point c."""
    poly = list(poly)
    pc = centroid(poly)
    n = (0.0, 0.0, 0.0)
    for i in range(1, len(poly) - 1):
        n = add(n, cross(sub(poly[i], poly[0]), sub(poly[i + 1], poly[0])))
    if dot(n, sub(pc, c)) < 0:
        poly.reverse()
    return [(poly[0], poly[i], poly[i + 1]) for i in range(1, len(poly) - 1)]


def hexa_faces(bottom, top):
    """Face polygons of the hexahedron between two corresponding quads: bottom, top, then the
    side faces (bottom[i], bottom[i + 1], ...)."""
    faces = [list(bottom), list(top)]
    for i in range(4):
        j = (i + 1) % 4
        faces.append([bottom[i], bottom[j], top[j], top[i]])
    return faces


# index in box_faces() of the face on each side
BOX_FACE = {("z", -1): 0, ("z", 1): 1, ("y", -1): 2, ("x", 1): 3, ("y", 1): 4, ("x", -1): 5}


def box_faces(lo, hi, what=None):
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    assert x1 > x0 and y1 > y0 and z1 > z0, (what, lo, hi)
    return hexa_faces([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)],
                      [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)])


def basis(axis, u_hint, v_hint):
    """Orthonormal (u, v) perpendicular to axis, u close to u_hint (v to v_hint if given)."""
    w = unit(axis)
    u = sub(u_hint, mul(w, dot(u_hint, w)))
    if norm(u) < 1e-9:
        raise ValueError("u_hint parallel to axis")
    u = unit(u)
    v = cross(w, u)
    if v_hint is not None and dot(v, v_hint) < 0:
        v = mul(v, -1.0)
    return u, v


_ICO = None


def icosahedron0():
    """The unit icosahedron (12 vertices on the unit sphere, 20 faces) icosphere1() refines."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    vs = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
          (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    vs = [unit(v) for v in vs]
    fs = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
          (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
          (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    return vs, fs


def icosahedron(scale):
    """The icosphere's base icosahedron, vertices at radius `scale` (20 triangles)."""
    vs, fs = icosahedron0()
    return [tuple(mul(vs[i], scale) for i in f) for f in fs]


def rotation_axes(ax, ay, az):
    """The columns of Rz(az) Ry(ay) Rx(ax)."""
    cx, sx, cy, sy, cz, sz = (math.cos(ax), math.sin(ax), math.cos(ay), math.sin(ay),
                              math.cos(az), math.sin(az))
    r = [[cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx],
         [sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx],
         [-sy, cy * sx, cy * cx]]
    return [(r[0][k], r[1][k], r[2][k]) for k in range(3)]


def unit_polyhedron(shape):
    """Triangles of a LOD2_CANOPY polyhedron (unit frame, any winding)."""
    if shape[0] == "octahedron":
        _, angles, radii = shape
        vs = []
        for d, r in zip(rotation_axes(*angles), radii):
            vs += [mul(d, r), mul(d, -r)]
        return [(vs[i], vs[j], vs[k]) for i in (0, 1) for j in (2, 3) for k in (4, 5)]
    _, n, angles, r_ring, r_pole, phase = shape
    u, v, w = rotation_axes(*angles)
    ring = [add(mul(u, r_ring * math.cos(phase + 2 * math.pi * k / n)),
                mul(v, r_ring * math.sin(phase + 2 * math.pi * k / n))) for k in range(n)]
    return [(ring[k], ring[(k + 1) % n], mul(w, sg * r_pole)) for sg in (1.0, -1.0)
            for k in range(n)]


def icosphere1():
    global _ICO
    if _ICO is None:
        vs, fs = icosahedron0()
        out = []
        for a, b, c in fs:
            pa, pb, pc = vs[a], vs[b], vs[c]
            ab, bc, ca = unit(lerp(pa, pb, 0.5)), unit(lerp(pb, pc, 0.5)), unit(lerp(pc, pa, 0.5))
            out += [(pa, ab, ca), (pb, bc, ab), (pc, ca, bc), (ab, bc, ca)]
        # snap the axis points exactly (so extents are exact)
        snapped = []
        for tri in out:
            st = []
            for p in tri:
                st.append(tuple(round(c) if abs(abs(c) - 1.0) < 1e-9 or abs(c) < 1e-9 else c
                                for c in p))
            snapped.append(tuple(st))
        _ICO = snapped
    return _ICO


def quad_point(A, B, C, D, u, v):
    """Bilinear point on quad A (bottom-left), B (bottom-right), C (top-right), D (top-left)."""
    return lerp(lerp(A, B, u), lerp(D, C, u), v)


def sub_quad(A, B, C, D, u0, u1, v0, v1):
    return [quad_point(A, B, C, D, u0, v0), quad_point(A, B, C, D, u1, v0),
            quad_point(A, B, C, D, u1, v1), quad_point(A, B, C, D, u0, v1)]


# ----------------------------------------------------------------------------------------------
# Houses and garages: a gable building (walls = pentagonal prism, two roof slabs, fascia boards,
# ridge cap). `along` is the ridge axis ("y" for houses, "x" for garages).
# ----------------------------------------------------------------------------------------------
def gable_building(m, along, half_across_wall, half_along_wall, half_across_roof, half_along_roof,
                   wall_h, height, roof_t, fascia=0.04, ridge_cap=True):
    """lod 1: the fascia boards become decals on their outer (eave) faces, no ridge cap.
    lod 2: each roof slab and its fascia become one sheet from the ridge to the eaves,
    LOD2_ROOF_SHEET of the slab's thickness below its top (no fascia, no ridge cap)."""
    def P(a, b, z):  # (across, along, z) -> (x, y, z)
        return (a, b, z) if along == "y" else (b, a, z)

    # slope chosen so that the roof underside meets the wall top at the wall line
    s = (height - roof_t - wall_h) / half_across_wall
    ridge_under = height - roof_t
    wa, wb = half_across_wall, half_along_wall
    prof = [(-wa, 0.0), (wa, 0.0), (wa, wall_h), (0.0, ridge_under), (-wa, wall_h)]
    m.extrude("paint", [P(a, -wb, z) for a, z in prof], P(0.0, 2 * wb, 0.0))
    ra, rb = half_across_roof, half_along_roof
    if m.lod >= 2:
        z_ridge = height - LOD2_ROOF_SHEET[0] * roof_t
        z_eave = height - s * ra - LOD2_ROOF_SHEET[1] * roof_t
        for sg in (-1.0, 1.0):
            m.sheet("roof", [P(0.0, -rb, z_ridge), P(sg * ra, -rb, z_eave), P(sg * ra, rb, z_eave),
                             P(0.0, rb, z_ridge)], P(0.0, 0.0, 0.0))
        return s
    slab_end = ra - fascia
    for sg in (-1.0, 1.0):
        def top(a):
            return height - s * a

        bottom = [P(0.0, -rb, height - roof_t), P(sg * slab_end, -rb, top(slab_end) - roof_t),
                  P(sg * slab_end, rb, top(slab_end) - roof_t), P(0.0, rb, height - roof_t)]
        topq = [P(0.0, -rb, height), P(sg * slab_end, -rb, top(slab_end)),
                P(sg * slab_end, rb, top(slab_end)), P(0.0, rb, height)]
        m.hexa("roof", bottom, topq)
        if fascia > 0:
            drop = roof_t + 0.05
            fb = [P(sg * slab_end, -rb, top(slab_end) - drop), P(sg * ra, -rb, top(ra) - drop),
                  P(sg * ra, rb, top(ra) - drop), P(sg * slab_end, rb, top(slab_end) - drop)]
            ft = [P(sg * slab_end, -rb, top(slab_end)), P(sg * ra, -rb, top(ra)),
                  P(sg * ra, rb, top(ra)), P(sg * slab_end, rb, top(slab_end))]
            if m.lod:
                m.decal("trim", hexa_faces(fb, ft), 3)  # the face at sg * ra
            else:
                m.hexa("trim", fb, ft)
    if ridge_cap and not m.lod:
        w = 0.13
        cap = [(-w, height - s * w - 0.02), (w, height - s * w - 0.02), (w, height - s * w + 0.05),
               (0.0, height + 0.06), (-w, height - s * w + 0.05)]
        m.extrude("roof", [P(a, -rb - 0.01, z) for a, z in cap], P(0.0, 2 * rb + 0.02, 0.0))
    return s


def wall_slab(m, mat, face, center, w, z0, z1, proud, inset=0.03):
    """A window/door slab on a house wall. face: ('x', x_wall, sign) or ('y', y_wall, sign);
    center: coordinate along the wall; w: width; z0..z1; proud: how far it stands out.
    lod > 0: a decal on the slab's outer face."""
    axis, wall, sg = face
    lo_o, hi_o = sorted((wall - sg * inset, wall + sg * proud))
    if axis == "x":
        m.box_or_decal(mat, (lo_o, center - w / 2, z0), (hi_o, center + w / 2, z1), (axis, sg))
    else:
        m.box_or_decal(mat, (center - w / 2, lo_o, z0), (center + w / 2, hi_o, z1), (axis, sg))


# lod2 windows: per (wall, row), groups of windows (indices into that row's list) each drawn as
# ONE decal of the same total area (width: the group's window widths added up, centred on the
# mean of their centres, the row's height); a window in no group is dropped. Rows are merged
# where the gaps are about a window width (house_1); house_2 (19 windows, 12 triangles left for
# them) keeps one band per storey and wall where it can and drops its front's lone downstairs
# window and its gable ends' upstairs windows.
LOD2_WINDOWS = {
    "house_1": {("front", 0): [(0,), (1, 2)], ("back", 0): [(0, 1, 2, 3)],
                ("left", 0): [(0,), (1,)], ("right", 0): [(0,), (1,)]},
    "house_2": {("front", 0): [(1, 2)], ("front", 1): [(0, 1, 2, 3)],
                ("back", 0): [(0, 1, 2)], ("back", 1): [(0, 1, 2)],
                ("left", 0): [(0, 1)], ("right", 0): [(0, 1)]},
}


def house_windows(storeys, ri):
    """Window centres along the wall of row ri: front (y), back (y), gable ends (x)."""
    fy = [-3.5, 1.3, 3.5] if ri == 0 else [-3.5, -0.9, 1.3, 3.5]  # beside/above the door
    by = [-3.6, -1.2, 1.2, 3.6] if storeys == 1 else [-3.3, 0.0, 3.3]
    sx = [-2.2, 2.2] if ri == 0 else [0.0]
    return fy, by, sx


def make_house(name, storeys, lod=0):
    """lod 2: walls, roof sheets, the lod1 chimney, the door and merged window decals, the
    step and house_2's belt course as sheets at mid-height (no trim, no corner boards)."""
    m = Mesh(name, budget(name, "house", lod), paint=(0.86, 0.82, 0.70), lod=lod)
    L, W = 10.0, 11.0
    H = 5.2 if storeys == 1 else 8.0
    wall_h = 2.9 if storeys == 1 else 5.6
    wx, wy = 4.6, 5.2          # walls (inset so the eaves touch +-L/2, gable overhang in y)
    rx, ry = L / 2, 5.5
    s = gable_building(m, "y", wx, wy, rx, ry, wall_h, H, 0.2)
    front, back = ("x", -wx, -1.0), ("x", wx, 1.0)
    left, right = ("y", wy, 1.0), ("y", -wy, -1.0)
    # front door, its frame and a step (door faces the street, -x)
    door_y = -0.9
    step = ((-rx, door_y - 0.85, 0.0), (-wx + 0.01, door_y + 0.85, 0.18))
    if lod < 2:
        wall_slab(m, "trim", front, door_y, 1.3, 0.15, 2.35, 0.03)
    wall_slab(m, "door", front, door_y, 1.0, 0.18, 2.25, 0.06)
    if lod < 2:
        m.box("trim", *step)
    else:
        m.box_sheet("trim", step[0], step[1], ("z", 1), 0.5)
    rows = [(0.9, 2.2)] if storeys == 1 else [(0.95, 2.25), (3.75, 5.0)]
    win_w = 1.2
    for ri, (z0, z1) in enumerate(rows):
        fy, by, sx = house_windows(storeys, ri)
        if lod >= 2:
            for wall, face, cs in (("front", front, fy), ("back", back, by), ("left", left, sx),
                                   ("right", right, sx)):
                for group in LOD2_WINDOWS[name].get((wall, ri), []):
                    c = sum(cs[i] for i in group) / len(group)
                    wall_slab(m, "window", face, c, win_w * len(group), z0, z1, 0.045)
            continue
        for y in fy:
            if storeys == 1:  # one-storey: trimmed front windows
                wall_slab(m, "trim", front, y, win_w + 0.2, z0 - 0.12, z1 + 0.1, 0.025)
            wall_slab(m, "window", front, y, win_w, z0, z1, 0.045)
        for y in by:
            wall_slab(m, "window", back, y, win_w, z0, z1, 0.045)
        for x in sx:
            wall_slab(m, "window", left, x, win_w, z0, z1, 0.045)
            wall_slab(m, "window", right, x, win_w, z0, z1, 0.045)
    belt = ((-wx - 0.04, -wy - 0.04, 2.75), (wx + 0.04, wy + 0.04, 2.95))
    if storeys == 1 and lod < 2:  # corner boards
        for sx_ in (-1, 1):
            for sy_ in (-1, 1):
                x0, x1 = sorted((sx_ * (wx + 0.05), sx_ * (wx - 0.18)))
                y0, y1 = sorted((sy_ * (wy + 0.05), sy_ * (wy - 0.18)))
                m.box("trim", (x0, y0, 0.0), (x1, y1, wall_h - 0.02))
    elif storeys != 1 and lod < 2:  # belt course between the storeys
        m.box("trim", *belt)
    elif storeys != 1:  # (lod2: its mid-plane; its top and bottom run through the whole house)
        m.box_sheet("trim", belt[0], belt[1], ("z", 1), 0.5)
    # chimney on the back slope, through the ridge height, with a cap
    cx0, cx1, cy0, cy1 = 1.3, 2.0, 3.0, 3.8
    z_in = H - s * cx1 - 0.6
    top = H + 0.3
    if lod:  # chimney and cap as one box halfway between them (sides +0.03, top +0.04)
        m.box("chimney", (cx0 - 0.03, cy0 - 0.03, z_in), (cx1 + 0.03, cy1 + 0.03, top + 0.04))
    else:
        m.box("chimney", (cx0, cy0, z_in), (cx1, cy1, top))
        m.box("chimney", (cx0 - 0.06, cy0 - 0.06, top), (cx1 + 0.06, cy1 + 0.06, top + 0.08))
    return m


def make_garage(name, doors, lod=0):
    """lod 2: walls, roof sheets, the lod1 door, garage door and window decals, no trim."""
    m = Mesh(name, budget(name, "garage", lod), paint=(0.86, 0.82, 0.70), lod=lod)
    L = 6.7
    W = 3.9 if doors == 1 else 6.6
    H, wall_h = 3.1, 2.6
    wx, wy = L / 2 - 0.15, W / 2 - 0.15
    gable_building(m, "x", wy, wx, W / 2, L / 2, wall_h, H, 0.15, fascia=0.04)
    front = ("x", -wx, -1.0)
    door_w = 2.7 if doors == 1 else 2.5
    centres = [0.0] if doors == 1 else [-1.45, 1.45]
    gap, dz, nslab = 0.035, 2.2, 4
    sh = (dz - gap * (nslab - 1)) / nslab
    for yc in centres:
        if lod < 2:
            wall_slab(m, "trim", front, yc, door_w + 0.16, 0.0, dz + 0.1, 0.03)
        if lod:  # one decal over the panels (the 3.5 cm gaps between them are sub-pixel)
            wall_slab(m, "garage_door", front, yc, door_w, 0.01, dz, 0.07)
            continue
        for k in range(nslab):
            z0 = k * (sh + gap)
            wall_slab(m, "garage_door", front, yc, door_w, z0 + (0.01 if k == 0 else 0.0),
                      z0 + sh, 0.07)
    # side door near the back and a window on the +y wall, a window on the back wall
    if lod < 2:
        wall_slab(m, "trim", ("y", wy, 1.0), 1.9, 1.05, 0.0, 2.15, 0.03)
    wall_slab(m, "door", ("y", wy, 1.0), 1.9, 0.9, 0.01, 2.05, 0.06)
    wall_slab(m, "window", ("y", wy, 1.0), -0.8, 1.0, 1.1, 1.9, 0.045)
    wall_slab(m, "window", ("x", wx, 1.0), 0.0, 1.0, 1.1, 1.9, 0.045)
    return m


# ----------------------------------------------------------------------------------------------
# Fences: runs along x, every part spans the whole length (the renderer stretches x to 3-30 m)
# except the two end posts.
# ----------------------------------------------------------------------------------------------
def make_fence_wood(lod=0):
    """lod 1: one box (board panel, rails, trim board and posts are all paint), from the boards'
    face to halfway between the boards' back and the posts' back, from halfway up the gap under
    the boards."""
    m = Mesh("fence_wood", budget("fence_wood", "fence", lod), paint=(0.56, 0.40, 0.25), lod=lod)
    hl, H = 5.0, 1.8
    if lod:
        m.box("paint", (-hl, -0.06, 0.025), (hl, 0.5 * (-0.035 + 0.06), H))
        return m
    m.box("paint", (-hl, -0.06, 0.05), (hl, -0.035, H))              # board panel
    for z0 in (0.30, 1.38):                                          # two back rails
        m.box("paint", (-hl, -0.036, z0), (hl, 0.035, z0 + 0.10))
    m.box("paint", (-hl, -0.065 + 0.005, H - 0.06), (hl, -0.02, H - 0.01))  # top trim board
    for sg in (-1, 1):                                               # end posts
        x0, x1 = sorted((sg * hl, sg * (hl - 0.1)))
        m.box("paint", (x0, -0.036, 0.0), (x1, 0.06, H - 0.05))
    return m


def make_fence_vinyl(lod=0):
    """lod 1: a paint box for panel, posts and bottom rail (halfway between the panel's and the
    posts' thickness, from halfway up the bottom rail's gap) and a trim box for the cap rail
    and post caps (the cap rail's width, up to halfway between their tops)."""
    m = Mesh("fence_vinyl", budget("fence_vinyl", "fence", lod), paint=(0.95, 0.95, 0.93),
             lod=lod)
    hl, H = 5.0, 1.8
    if lod:
        hw = 0.5 * (0.02 + 0.055)
        m.box("paint", (-hl, -hw, 0.02), (hl, hw, 1.64))
        m.box("trim", (-hl, -0.045, 1.62), (hl, 0.045, 0.5 * (1.72 + H)))
        return m
    m.box("paint", (-hl, -0.02, 0.08), (hl, 0.02, 1.64))             # privacy panel
    m.box("trim", (-hl, -0.035, 0.04), (hl, 0.035, 0.14))             # bottom rail
    m.box("trim", (-hl, -0.045, 1.62), (hl, 0.045, 1.72))             # cap rail
    for sg in (-1, 1):
        x0, x1 = sorted((sg * hl, sg * (hl - 0.07)))
        m.box("paint", (x0, -0.055, 0.0), (x1, 0.055, 1.75))         # end post
        m.box("trim", (x0, -0.06, 1.75), (x1, 0.06, H))               # post cap
    return m


def make_fence_chain_link(lod=0):
    """lod 1: a paint box for the mesh panel, wire and posts (halfway between the panel's and
    the posts' thickness, from just under the wire) and a frame box for the top rail (up to
    the posts' top)."""
    m = Mesh("fence_chain_link", budget("fence_chain_link", "fence", lod),
             paint=(0.36, 0.37, 0.38), lod=lod)
    hl, H = 5.0, 1.5
    if lod:
        hw = 0.5 * (0.006 + 0.06)
        m.box("paint", (-hl, -hw, 0.015), (hl, hw, H - 0.07))
        m.box("frame", (-hl, -hw, H - 0.07), (hl, hw, H))
        return m
    m.box("paint", (-hl, -0.006, 0.04), (hl, 0.006, H - 0.06))        # mesh panel
    m.box("frame", (-hl, -0.025, H - 0.07), (hl, 0.025, H - 0.02))    # top rail
    m.box("frame", (-hl, -0.01, 0.03), (hl, 0.01, 0.06))              # bottom tension wire
    for sg in (-1, 1):
        x0, x1 = sorted((sg * hl, sg * (hl - 0.06)))
        m.box("frame", (x0, -0.06, 0.0), (x1, 0.06, H))              # end posts
    return m


# ----------------------------------------------------------------------------------------------
# Trees
# ----------------------------------------------------------------------------------------------
def make_tree_deciduous(lod=0):
    """lod 1: square trunk, triangular branches, icosahedra. lod 2: a triangular pyramid trunk
    (lod2_trunk), each branch one triangle (a sheet through its axis, facing up), the canopy
    an octahedron or bipyramid per icosphere (LOD2_CANOPY)."""
    m = Mesh("tree_deciduous", budget("tree_deciduous", "tree", lod), lod=lod)
    D, H = 5.0, 9.0
    r_tr = 0.06 * D / math.cos(math.pi / 8)   # octagon across flats = 12% of the width
    if lod >= 2:
        lod2_trunk(m, 0.45 * H * LOD2_TRUNK[1], r_tr * LOD2_TRUNK[0])
    elif lod:  # square trunk with the octagon's corner radius
        m.frustum("trunk", (0, 0, 0), (0, 0, 0.45 * H), r_tr, r_tr * 0.8, 4, phase=math.pi / 4)
    else:
        m.frustum("trunk", (0, 0, 0), (0, 0, 0.45 * H), r_tr, r_tr * 0.8, 8, phase=math.pi / 8)
    for ang, z0, z1, reach in ((20.0, 2.3, 3.9, 1.3), (145.0, 2.7, 4.1, 1.2),
                               (260.0, 2.5, 3.7, 1.25)):
        a = math.radians(ang)
        d = (math.cos(a), math.sin(a), 0.0)
        tip = (reach * d[0], reach * d[1], z1)
        if lod >= 2:
            side = (-d[1] * 0.11, d[0] * 0.11, 0.0)
            base = (0.0, 0.0, z0)
            up = unit(cross(sub(tip, base), side))
            m.sheet("trunk", [sub(base, side), add(base, side), tip],
                    sub(lerp(base, tip, 0.5), mul(up, 0.1)))
        elif lod:  # triangular, with the square beam's corner radius
            m.frustum("trunk", (0.0, 0.0, z0), tip, 0.11 * math.sqrt(2.0), 0.06 * math.sqrt(2.0), 3,
                      u_hint=(-d[1], d[0], 0.0))
        else:
            m.beam("trunk", (0.0, 0.0, z0), tip, (-d[1], d[0], 0.0), 0.11, 0.11, 0.06, 0.06)
    # canopy: 4 overlapping icospheres; their union spans exactly +-D/2 in x and y,
    # from 35% to 100% of the height
    h = D / 2
    blobs = [((-0.85, 0.10, 6.9), (h - 0.85, 1.65, 2.1)),    # crown: min x, top
             ((1.05, 0.30, 5.4), (h - 1.05, 1.45, 1.9)),     # max x
             ((-0.15, 1.10, 5.25), (1.40, h - 1.10, 1.85)),  # max y
             ((0.25, -1.05, 5.0), (1.45, h - 1.05, 1.85))]   # min y, bottom (3.15 = 35%)
    for (c, r), shape in zip(blobs, LOD2_CANOPY):
        m.ellipsoid("foliage", c, r, shape)
    return m


def lod2_trunk(m, height, r):
    """A triangular pyramid standing on the ground, base corner radius r, as three side sheets
    facing out (its base would lie on the ground, never seen)."""
    base = [(r * math.cos(math.pi / 2 + 2 * math.pi * k / 3),
             r * math.sin(math.pi / 2 + 2 * math.pi * k / 3), 0.0) for k in range(3)]
    for k in range(3):
        m.sheet("trunk", [base[k], base[(k + 1) % 3], (0.0, 0.0, height)], (0.0, 0.0, height / 3))


def make_tree_pine(lod=0):
    """lod 1, 2: fewer trunk and cone sides (LOD_PINE: sides, phase and radius scale); lod 2:
    the trunk a triangular pyramid (lod2_trunk)."""
    m = Mesh("tree_pine", budget("tree_pine", "tree", lod), lod=lod)
    m.kd_override["foliage"] = (0.13, 0.31, 0.16)
    D, H = 4.0, 10.0
    r = D / 2
    if lod:
        trunk, cones = LOD_PINE[lod]
        if trunk is None:
            lod2_trunk(m, 0.45 * H * LOD2_TRUNK[1], 0.22 * LOD2_TRUNK[0])
        else:
            n, ph, sc = trunk
            m.frustum("trunk", (0, 0, 0), (0, 0, 0.45 * H), 0.22 * sc, 0.15 * sc, n, phase=ph)
    else:
        m.frustum("trunk", (0, 0, 0), (0, 0, 0.45 * H), 0.22, 0.15, 8, phase=math.pi / 8)
    # three stacked 12-sided cones; the bottom one has vertices on the axes (extent +-D/2)
    for k, (zb, zt, rr, ph) in enumerate(((0.15 * H, 0.62 * H, r, 0.0),
                                          (0.38 * H, 0.82 * H, 0.78 * r, math.pi / 12),
                                          (0.60 * H, H, 0.55 * r, 0.0))):
        if lod:
            n, ph, sc = cones[k]
            m.cone("foliage", (0, 0, zb), (0, 0, zt), rr * sc, n, phase=ph)
        else:
            m.cone("foliage", (0, 0, zb), (0, 0, zt), rr, 12, phase=ph)
    return m


# ----------------------------------------------------------------------------------------------
# Cars. Body: a convex side profile (x, z) extruded across the width; cabin: a tapered
# hexahedron; glass slabs on the cabin faces; 10-sided wheels touching z = 0.
# ----------------------------------------------------------------------------------------------
def lod2_body(spec):
    """The lod2 car body profile: a quadrilateral. Its front and rear faces are
    LOD2_BUMPER_INSET inside the bumpers' outer faces (unless the body ends before that: the
    pickup's cab); their tops lie on the hood line (profile points 3-4) and the deck line (4-5)
    extended, so the nose and tail chamfers and the cowl (point 4) are cut straight."""
    body, L = spec["body"], spec["L"]
    zb = min(z for _, z in body)
    xf = min(max(x for x, _ in body), L / 2 - LOD2_BUMPER_INSET)
    xr = max(min(x for x, _ in body), -L / 2 + LOD2_BUMPER_INSET)

    def line_z(a, b, x):
        return a[1] + (b[1] - a[1]) * (x - a[0]) / (b[0] - a[0])

    return [(xr, zb), (xf, zb), (xf, line_z(body[3], body[4], xf)),
            (xr, line_z(body[4], body[5], xr))]


def make_car(name, spec, lod=0):
    """lod 2: the body a quadrilateral prism (lod2_body), the cabin with glass sides and a paint
    roof, each wheel a square sheet on both tyre faces; no glass slabs, bumpers, lights,
    mirrors (unless LOD2_MIRRORS: a sheet on each one's mid-plane) or roof rails."""
    m = Mesh(name, budget(name, "car", lod), paint=(0.72, 0.12, 0.10), lod=lod)
    L, W = spec["L"], spec["W"]
    hb = W / 2 - 0.05            # body half-width (mirrors reach W/2)
    if lod >= 2:
        return make_car_lod2(m, spec, hb)
    body = spec["body"]
    m.extrude("paint", [(x, -hb, z) for x, z in body], (0.0, 2 * hb, 0.0))
    for x0, x1, z0, z1 in spec.get("extra_body", []):
        m.box("paint", (x0, -hb, z0), (x1, hb, z1))
    # cabin
    (xr0, xf0, z0, hw0), (xr1, xf1, z1, hw1) = spec["cabin"]
    cb = [(xr0, -hw0, z0), (xf0, -hw0, z0), (xf0, hw0, z0), (xr0, hw0, z0)]
    ct = [(xr1, -hw1, z1), (xf1, -hw1, z1), (xf1, hw1, z1), (xr1, hw1, z1)]
    m.hexa("paint", cb, ct)
    cc = centroid(cb + ct)
    belt = spec["belt"]
    v0 = (belt + 0.04 - z0) / (z1 - z0)
    v1 = 1.0 - 0.06 / (z1 - z0)
    tg_o, tg_i = 0.012, 0.012
    # windscreen, rear window
    A, B, C, D = (xf0, -hw0, z0), (xf0, hw0, z0), (xf1, hw1, z1), (xf1, -hw1, z1)
    m.slab("glass", sub_quad(A, B, C, D, 0.06, 0.94, v0, v1), cc, tg_o, tg_i)
    A, B, C, D = (xr0, hw0, z0), (xr0, -hw0, z0), (xr1, -hw1, z1), (xr1, hw1, z1)
    rv0 = spec.get("rear_v0", v0)
    m.slab("glass", sub_quad(A, B, C, D, 0.08, 0.92, rv0, v1), cc, tg_o, tg_i)
    # side windows (u from the rear pillar to the front pillar)
    for sg in (-1.0, 1.0):
        A, B = (xr0, sg * hw0, z0), (xf0, sg * hw0, z0)
        C, D = (xf1, sg * hw1, z1), (xr1, sg * hw1, z1)
        for u0, u1 in spec["side_windows"]:
            m.slab("glass", sub_quad(A, B, C, D, u0, u1, v0, v1), cc, tg_o, tg_i)
    # wheels: 10-sided (lod > 0: 6-sided, same radius: with a vertex at the bottom the hexagon's
    # lower edges are 0.1286 r from the decagon's next vertex whatever its size), a vertex at the
    # bottom (z = 0)
    r, tw = spec["wheel_r"], 0.23
    yo = W / 2 - 0.03
    for xw in spec["wheel_x"]:
        for sg in (-1.0, 1.0):
            m.frustum("tire", (xw, sg * (yo - tw), r), (xw, sg * yo, r), r, r, 6 if lod else 10,
                      u_hint=(1, 0, 0), v_hint=(0, 0, 1), phase=-math.pi / 2)
    # bumpers (they define the length), lights
    bz0, bz1 = spec["bumper_z"]
    bw = hb + 0.01
    m.box("bumper", (L / 2 - 0.2, -bw, bz0), (L / 2, bw, bz1))
    m.box("bumper", (-L / 2, -bw, bz0), (-L / 2 + 0.2, bw, bz1))
    xf_face, hz0, hz1 = spec["head"]
    xr_face, tz0, tz1 = spec["tail"]
    ty_in = spec.get("tail_y_in", 0.50)
    for sg in (-1.0, 1.0):
        y0, y1 = sorted((sg * 0.48, sg * (hb - 0.07)))
        m.box_or_decal("light_front", (xf_face - 0.06, y0, hz0), (xf_face + 0.015, y1, hz1),
                       ("x", 1))
        y0, y1 = sorted((sg * ty_in, sg * (hb - 0.03)))
        m.box_or_decal("light_rear", (xr_face - 0.015, y0, tz0), (xr_face + 0.06, y1, tz1),
                       ("x", -1))
    # mirrors (they define the width)
    mx, mz = spec["mirror"]
    for sg in (-1.0, 1.0):
        y0, y1 = sorted((sg * (hw0 - 0.06), sg * W / 2))
        m.box("paint", (mx - 0.07, y0, mz), (mx + 0.07, y1, mz + 0.13))
    for x0, x1, y0, y1, z0_, z1_, mat in spec.get("extras", []) if not lod else []:
        m.box(mat, (x0, y0, z0_), (x1, y1, z1_))  # (the SUV's roof rails: 4-5 cm, not in lod1)
    return m


def make_car_lod2(m, spec, hb):
    """make_car's lod 2 (see there); hb: the body's half-width."""
    L, W = spec["L"], spec["W"]
    body = lod2_body(spec)
    m.extrude("paint", [(x, -hb, z) for x, z in body], (0.0, 2 * hb, 0.0))
    for x0, x1, z0, z1 in spec.get("extra_body", []):
        m.box("paint", (max(x0, -L / 2 + LOD2_BUMPER_INSET), -hb, z0),
              (min(x1, L / 2 - LOD2_BUMPER_INSET), hb, z1))
    # cabin: glass sides, paint roof; its bottom lowered to LOD2_CABIN_SINK below the body's
    # (straight) top under it
    (xr0, xf0, z0, hw0), (xr1, xf1, z1, hw1) = spec["cabin"]
    (_, _), (_, _), (xf, zf), (xr, zr) = body
    zc = min(z0, min(zf + (zr - zf) * (x - xf) / (xr - xf) for x in (xr0, xf0)) - LOD2_CABIN_SINK)
    cb = [(xr0, -hw0, zc), (xf0, -hw0, zc), (xf0, hw0, zc), (xr0, hw0, zc)]
    ct = [(xr1, -hw1, z1), (xf1, -hw1, z1), (xf1, hw1, z1), (xr1, hw1, z1)]
    m.solid_mats(["paint", "paint", "glass", "glass", "glass", "glass"], hexa_faces(cb, ct))
    # wheels: a square sheet on each tyre face, facing away from the tyre's centre
    r, tw = spec["wheel_r"], 0.23
    yo = W / 2 - 0.03
    a = LOD2_WHEEL * r
    for xw in spec["wheel_x"]:
        for sg in (-1.0, 1.0):
            c = (xw, sg * (yo - tw / 2), r)
            for y in (sg * yo, sg * (yo - tw)):
                m.sheet("tire", [(xw - a, y, r - a), (xw + a, y, r - a), (xw + a, y, r + a),
                                 (xw - a, y, r + a)], c)
    if m.base in LOD2_MIRRORS:
        mx, mz = spec["mirror"]
        for sg in (-1.0, 1.0):
            y0, y1 = sorted((sg * (hw0 - 0.06), sg * W / 2))
            m.box_sheet("paint", (mx - 0.07, y0, mz), (mx + 0.07, y1, mz + 0.13), ("y", sg), 0.5)
    return m


CARS = {
    "car_sedan": dict(
        L=4.9, W=1.85,
        body=[(-2.41, 0.25), (2.41, 0.25), (2.41, 0.62), (2.30, 0.78), (0.95, 0.93),
              (-2.25, 0.98), (-2.41, 0.88)],
        cabin=((-1.50, 0.95, 0.90, 0.84), (-0.80, 0.22, 1.45, 0.68)), belt=0.95,
        side_windows=[(0.10, 0.47), (0.52, 0.93)],
        wheel_r=0.33, wheel_x=(1.47, -1.38), bumper_z=(0.22, 0.48),
        head=(2.41, 0.52, 0.64), tail=(-2.41, 0.70, 0.84), mirror=(0.72, 0.95)),
    "car_suv": dict(
        L=4.85, W=1.93,
        body=[(-2.39, 0.32), (2.39, 0.32), (2.39, 0.80), (2.22, 0.99), (1.05, 1.08),
              (-2.32, 1.10), (-2.39, 1.03)],
        cabin=((-2.30, 1.05, 1.04, 0.88), (-2.18, 0.12, 1.71, 0.78)), belt=1.09,
        side_windows=[(0.04, 0.31), (0.35, 0.63), (0.67, 0.94)],
        wheel_r=0.37, wheel_x=(1.45, -1.40), bumper_z=(0.28, 0.58),
        head=(2.39, 0.70, 0.84), tail=(-2.39, 0.80, 1.05), tail_y_in=0.62, mirror=(0.82, 1.10),
        extras=[(-1.90, 0.0, 0.60, 0.66, 1.70, 1.75, "bumper"),
                (-1.90, 0.0, -0.66, -0.60, 1.70, 1.75, "bumper")]),
    "car_pickup": dict(
        L=5.9, W=2.05,
        body=[(-0.74, 0.45), (2.91, 0.45), (2.91, 0.95), (2.78, 1.13), (1.35, 1.22),
              (-0.74, 1.22)],
        extra_body=[(-2.91, -0.73, 0.45, 0.85)],           # chassis under the bed (bed floor)
        cabin=((-0.72, 1.35, 1.18, 0.95), (-0.68, 0.50, 1.95, 0.85)), belt=1.22,
        side_windows=[(0.06, 0.47), (0.52, 0.93)],
        wheel_r=0.40, wheel_x=(1.85, -1.80), bumper_z=(0.40, 0.66),
        head=(2.91, 0.80, 0.94), tail=(-2.91, 0.90, 1.18), tail_y_in=0.875,
        mirror=(1.05, 1.26)),
    "car_hatchback": dict(
        L=4.2, W=1.76,
        body=[(-2.06, 0.22), (2.06, 0.22), (2.06, 0.58), (1.93, 0.76), (0.85, 0.92),
              (-1.95, 0.97), (-2.06, 0.90)],
        cabin=((-2.00, 0.85, 0.88, 0.80), (-1.68, -0.08, 1.49, 0.65)), belt=0.95,
        side_windows=[(0.14, 0.50), (0.55, 0.93)],
        wheel_r=0.31, wheel_x=(1.30, -1.27), bumper_z=(0.19, 0.44),
        head=(2.06, 0.50, 0.62), tail=(-2.06, 0.72, 0.88), mirror=(0.64, 0.96)),
    "car_van": dict(
        L=5.16, W=1.99,
        body=[(-2.54, 0.28), (2.54, 0.28), (2.54, 0.66), (2.38, 0.86), (1.45, 1.01),
              (-2.45, 1.06), (-2.54, 0.98)],
        cabin=((-2.50, 1.45, 0.98, 0.93), (-2.38, 0.42, 1.76, 0.84)), belt=1.04,
        side_windows=[(0.04, 0.33), (0.37, 0.65), (0.69, 0.94)],
        wheel_r=0.36, wheel_x=(1.55, -1.52), bumper_z=(0.25, 0.52),
        head=(2.54, 0.56, 0.70), tail=(-2.54, 0.76, 1.00), tail_y_in=0.66,
        mirror=(1.22, 1.06)),
}


def make_pickup_bed(m):
    """Open bed of the pickup: side walls and tailgate on the chassis (bed floor z = 0.85).
    lod 2: each wall a sheet on its mid-plane, facing out of the bed."""
    hb = 2.05 / 2 - 0.05
    for sg in (-1.0, 1.0):
        y0, y1 = sorted((sg * (hb - 0.09), sg * hb))
        if m.lod >= 2:
            m.box_sheet("paint", (-2.91, y0, 0.84), (-0.70, y1, 1.24), ("y", sg), 0.5)
        else:
            m.box("paint", (-2.91, y0, 0.84), (-0.70, y1, 1.24))
    if m.lod >= 2:
        m.box_sheet("paint", (-2.91, -hb + 0.08, 0.84), (-2.82, hb - 0.08, 1.21), ("x", -1), 0.5)
    else:
        m.box("paint", (-2.91, -hb + 0.08, 0.84), (-2.82, hb - 0.08, 1.21))


# ----------------------------------------------------------------------------------------------
# Pedestrian: walking stance facing +x (left leg forward, right arm forward), real metres,
# 0.5 x 0.5 x 1.75 in design so normalization hardly distorts it.
# ----------------------------------------------------------------------------------------------
def make_pedestrian():
    m = Mesh("pedestrian", 300, paint=(0.25, 0.45, 0.75))
    # shoes (heel-to-toe spans x = -0.25 .. 0.25)
    m.box("shoe", (-0.005, 0.04, 0.0), (0.25, 0.14, 0.09))          # left, forward
    m.box("shoe", (-0.25, -0.14, 0.0), (0.005, -0.04, 0.09))        # right, back
    # legs hip -> ankle
    m.beam("pants", (0.02, 0.09, 0.95), (0.075, 0.09, 0.07), (0, 1, 0), 0.075, 0.08, 0.055, 0.055)
    m.beam("pants", (-0.02, -0.09, 0.95), (-0.175, -0.09, 0.07), (0, 1, 0), 0.075, 0.08,
           0.055, 0.055)
    m.box("pants", (-0.095, -0.165, 0.86), (0.095, 0.165, 1.02))    # pelvis
    # torso (tapered), neck, head and hair
    m.hexa("paint", [(-0.10, -0.16, 0.98), (0.10, -0.16, 0.98), (0.10, 0.16, 0.98),
                     (-0.10, 0.16, 0.98)],
           [(-0.11, -0.205, 1.46), (0.11, -0.205, 1.46), (0.11, 0.205, 1.46),
            (-0.11, 0.205, 1.46)])
    m.box("skin", (-0.045, -0.045, 1.42), (0.045, 0.045, 1.54))
    m.ellipsoid("skin", (0.012, 0.0, 1.62), (0.095, 0.082, 0.115))
    m.ellipsoid("hair", (-0.012, 0.0, 1.648), (0.098, 0.088, 0.102))
    # arms shoulder -> wrist, swinging opposite to the legs, and hands
    for sg, wx in ((1.0, -0.085), (-1.0, 0.095)):
        sh = (0.0, sg * 0.20, 1.42)
        wr = (wx, sg * 0.214, 0.86)   # arm outer edge at |y| = 0.25
        m.beam("paint", sh, wr, (0, 1, 0), 0.045, 0.05, 0.036, 0.036)
        d = unit(sub(wr, sh))
        hand_end = add(wr, mul(d, 0.11))
        m.beam("skin", sub(wr, mul(d, 0.01)), hand_end, (0, 1, 0), 0.022, 0.04, 0.018, 0.034)
    return m


# ----------------------------------------------------------------------------------------------
# Sentinel UAV (metres, base_link FLU, origin at the centre of mass)
# ----------------------------------------------------------------------------------------------
def make_sentinel():
    m = Mesh("sentinel", 1500, normalized=False, paint=(0.16, 0.16, 0.17))
    a = 0.106066
    # central body: tapered box 0.12 x 0.08 x 0.05 and a battery/cover plate on top
    m.hexa("frame", [(-0.06, -0.04, -0.025), (0.06, -0.04, -0.025), (0.06, 0.04, -0.025),
                     (-0.06, 0.04, -0.025)],
           [(-0.055, -0.036, 0.025), (0.055, -0.036, 0.025), (0.055, 0.036, 0.025),
            (-0.055, 0.036, 0.025)])
    m.box("frame", (-0.045, -0.028, 0.025), (0.035, 0.028, 0.033))
    for sx in (-1.0, 1.0):
        for sy in (-1.0, 1.0):
            hub = (sx * a, sy * a, 0.03)
            d = unit((sx, sy, 0.0))
            side = (-d[1], d[0], 0.0)
            # arm from inside the body to under the motor
            m.beam("arm", (d[0] * 0.03, d[1] * 0.03, 0.008), (sx * a, sy * a, 0.008), side,
                   0.009, 0.007)
            # motor (bell) on the arm, hub height 0.03
            m.frustum("motor", (hub[0], hub[1], 0.015), (hub[0], hub[1], 0.040), 0.014, 0.013,
                      10)
            # prop disc at z = 0.045, radius 0.065, 8 sides (vertices on the x and y axes)
            m.frustum("prop", (hub[0], hub[1], 0.0435), (hub[0], hub[1], 0.0465), 0.065, 0.065,
                      8)
            # landing leg under the arm
            lx, ly = d[0] * 0.085, d[1] * 0.085
            m.box("frame", (lx - 0.004, ly - 0.004, -0.052), (lx + 0.004, ly + 0.004, 0.002))
    # front camera at (0.12, 0, -0.03) on a bracket, lens looking forward
    m.box("frame", (0.05, -0.012, -0.036), (0.108, 0.012, -0.022))
    m.box("camera", (0.105, -0.02, -0.042), (0.13, 0.02, -0.018))
    m.frustum("camera", (0.129, 0.0, -0.03), (0.14, 0.0, -0.03), 0.009, 0.008, 8,
              u_hint=(0, 1, 0), phase=math.pi / 8)
    # down camera at (0, 0, -0.06), lens looking down
    m.box("camera", (-0.016, -0.016, -0.05), (0.016, 0.016, -0.024))
    m.frustum("camera", (0.0, 0.0, -0.049), (0.0, 0.0, -0.06), 0.009, 0.008, 8,
              phase=math.pi / 8)
    return m


# ----------------------------------------------------------------------------------------------
def make_car_named(name, lod):
    m = make_car(name, CARS[name], lod)
    if name == "car_pickup":
        make_pickup_bed(m)
    return m


# (class mesh, builder(lod), its coarse levels), in the order of the files and of lod.json
CLASS_MESHES = [
    ("house_1", lambda lod: make_house("house_1", 1, lod), (1, 2)),
    ("house_2", lambda lod: make_house("house_2", 2, lod), (1, 2)),
    ("garage_1", lambda lod: make_garage("garage_1", 1, lod), (1, 2)),
    ("garage_2", lambda lod: make_garage("garage_2", 2, lod), (1, 2)),
    ("fence_wood", make_fence_wood, (1,)),
    ("fence_vinyl", make_fence_vinyl, (1,)),
    ("fence_chain_link", make_fence_chain_link, (1,)),
    ("tree_deciduous", make_tree_deciduous, (1, 2)),
    ("tree_pine", make_tree_pine, (1, 2)),
] + [(name, lambda lod, name=name: make_car_named(name, lod), (1, 2)) for name in CARS] + [
    ("pedestrian", lambda lod: make_pedestrian(), ()),
    ("sentinel", lambda lod: make_sentinel(), ()),
]


def build_all():
    """The fine meshes, then the lod1 meshes, then the lod2 meshes (each coarse mesh normalized
    with its fine mesh's design bounds)."""
    fine = [build(0) for _, build, _ in CLASS_MESHES]
    coarse = []
    for lod in (1, 2):
        for f, (_, build, levels) in zip(fine, CLASS_MESHES):
            if lod in levels:
                m = build(lod)
                m.bounds_from = f
                coarse.append(m)
    return fine + coarse


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


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    outdir = os.path.join(os.path.dirname(here), "models", "meshes")
    check_only = False
    i = 0
    while i < len(argv):
        if argv[i] == "--check":
            check_only = True
        elif argv[i] == "--out" and i + 1 < len(argv):
            outdir = argv[i + 1]
            i += 1
        else:
            print(__doc__)
            return 2
        i += 1
    if check_only:
        # the files must be what this script writes now (so the in-memory part checks apply)
        import tempfile
        meshes = build_all()
        stale = []
        with tempfile.TemporaryDirectory() as tmp:
            for m in meshes:
                m.write(tmp)
            table = lod_table(meshes)
            with open(os.path.join(tmp, LOD_FILE), "w", newline="\n") as f:
                f.write(lod_json(table))
            for fn in [m.name + ext for m in meshes for ext in (".obj", ".mtl")] + [LOD_FILE]:
                old = os.path.join(outdir, fn)
                with open(os.path.join(tmp, fn), "rb") as f:
                    want = f.read()
                have = None
                if os.path.exists(old):
                    with open(old, "rb") as f:
                        have = f.read()
                if have != want:
                    stale.append(fn)
        ok = run_checks(outdir, meshes)
        ok = report_levels(table) and ok
        for fn in stale:
            print("STALE: %s differs from what the script generates (regenerate)" % fn)
        return 0 if ok and not stale else 1
    os.makedirs(outdir, exist_ok=True)
    meshes = build_all()
    for m in meshes:
        m.write(outdir)
    table = lod_table(meshes)
    with open(os.path.join(outdir, LOD_FILE), "w", newline="\n") as f:
        f.write(lod_json(table))
    print_lod_table(table)
    print()
    ok = run_checks(outdir, meshes)
    return 0 if report_levels(table) and ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
