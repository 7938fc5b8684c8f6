"""The Mesh: closed convex parts (or decals and sheets), normalization, OBJ/MTL output."""

import math
import os

from .parameters import ICO_LOD_SCALE, KD, LOD_FILE, budget
from .geometry import (BOX_FACE, add, basis, box_faces, centroid, cross, dot, fmt, hexa_faces,
                       icosahedron, icosphere1, mul, outward_fan, rnd, sub, unit, unit_polyhedron)


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
