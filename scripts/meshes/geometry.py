"""Vector helpers and the convex solids (boxes, prisms, icospheres, polyhedra) the meshes use."""

import math

from .parameters import FMT


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
