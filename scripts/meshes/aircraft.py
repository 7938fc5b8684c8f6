"""The other aircraft of avoid scenarios: a small fixed-wing airplane and a quadrotor."""

from .mesh import Mesh
from .pedestrian_uav import make_sentinel


# ----------------------------------------------------------------------------------------------
# Fixed wing: a 1.8 m long, 2.4 m span single-engine tractor airplane with a high wing,
# nose towards +x. Designed in metres, normalized to the unit box like every class mesh.
# ----------------------------------------------------------------------------------------------
def make_fixed_wing():
    m = Mesh("aircraft_fixed_wing", 400, paint=(0.92, 0.92, 0.90))
    # fuselage: an icosphere stretched along x, and the cockpit canopy on top, forward
    m.ellipsoid("paint", (0.0, 0.0, 0.22), (0.85, 0.10, 0.10))
    m.ellipsoid("glass", (0.32, 0.0, 0.30), (0.20, 0.06, 0.05))
    # high wing, each half tapered from the root chord to the tip
    for sy in (-1.0, 1.0):
        plan = [(-0.14, 0.0), (0.16, 0.0), (0.10, sy * 1.2), (-0.08, sy * 1.2)]
        m.hexa("paint", [(x, y, 0.30) for x, y in plan], [(x, y, 0.33) for x, y in plan])
    # horizontal tail and vertical fin
    m.box("paint", (-0.85, -0.40, 0.24), (-0.66, 0.40, 0.26))
    m.box("paint", (-0.86, -0.015, 0.26), (-0.68, 0.015, 0.45))
    # propeller disc and spinner at the nose
    m.frustum("prop", (0.84, 0.0, 0.22), (0.86, 0.0, 0.22), 0.13, 0.13, 8, u_hint=(0, 1, 0))
    m.cone("motor", (0.86, 0.0, 0.22), (0.93, 0.0, 0.22), 0.04, 8, u_hint=(0, 1, 0))
    # fixed landing gear: two main legs and the nose leg with their wheels
    for y in (-0.22, 0.22):
        m.box("frame", (-0.02, y - 0.01, 0.04), (0.02, y + 0.01, 0.14))
        m.box("tire", (-0.05, y - 0.02, 0.0), (0.05, y + 0.02, 0.08))
    m.box("frame", (0.58, -0.01, 0.04), (0.62, 0.01, 0.14))
    m.box("tire", (0.56, -0.02, 0.0), (0.64, 0.02, 0.07))
    return m


# ----------------------------------------------------------------------------------------------
# Quadrotor: the sentinel's geometry as a class mesh (normalized to the aircraft's box).
# ----------------------------------------------------------------------------------------------
def make_quadrotor():
    return make_sentinel("aircraft_quadrotor", normalized=True)
