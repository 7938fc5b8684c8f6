"""The pedestrian and the sentinel UAV meshes."""

import math

from .geometry import add, mul, sub, unit
from .mesh import Mesh


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
def make_sentinel(name="sentinel", normalized=False):
    """The sentinel in metres (normalized=False), or the same parts as a class mesh."""
    m = Mesh(name, 1500, normalized=normalized, paint=(0.16, 0.16, 0.17))
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
