"""Cars (sedan, SUV, pickup, hatchback, van) and their coarse levels."""

import math

from .parameters import LOD2_BUMPER_INSET, LOD2_CABIN_SINK, LOD2_MIRRORS, LOD2_WHEEL, budget
from .geometry import centroid, hexa_faces, sub_quad
from .mesh import Mesh


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
