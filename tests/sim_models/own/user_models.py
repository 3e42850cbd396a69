"""MJCF models written by hand the way users write them (never through our builders),
with their closed-form kinematics.

The four-bar: ground pins O2 = (0, 0, 0) and O4 = (0.4, 0, 0) in the world XZ plane,
crank a = 0.1 m at 60 deg above +x, coupler b = 0.3 m, rocker c = 0.25 m, open branch
(B above the ground line), gravity -z.  Hinge axes (0, -1, 0): a positive rotation turns
+x towards +z, so every angle below is counter-clockwise in the view with x right and
z up, the plane the importer chooses (e2 against gravity = +z, e1 = e2 x n = +x).
"""

from __future__ import annotations

import math

A_LEN, B_LEN, C_LEN, D_LEN = 0.1, 0.3, 0.25, 0.4
THETA2 = math.radians(60.0)
RADIUS = 0.01        # capsule radius, m
DENSITY = 2700.0     # kg/m^3 (aluminium)


def four_bar_pose(theta2: float = THETA2):
    """(A, B, theta3, theta4): the crank tip, the coupler-rocker pin (x, z) and the
    coupler and rocker angles, open branch, from the circle intersection."""
    ax, az = A_LEN * math.cos(theta2), A_LEN * math.sin(theta2)
    dx, dz = D_LEN - ax, -az            # A -> O4
    e = math.hypot(dx, dz)
    # B on the circle of radius b about A and c about O4: the side with B above
    along = (B_LEN**2 - C_LEN**2 + e**2) / (2 * e)
    h = math.sqrt(B_LEN**2 - along**2)
    ux, uz = dx / e, dz / e
    bx, bz = ax + along * ux - h * uz, az + along * uz + h * ux
    return (ax, az), (bx, bz), math.atan2(bz - az, bx - ax), math.atan2(bz, bx - D_LEN)


def four_bar_rates(w2: float, al2: float = 0.0, theta2: float = THETA2):
    """(w3, w4, al3, al4) of the test four-bar at ``theta2``."""
    _, _, t3, t4 = four_bar_pose(theta2)
    return loop_rates(A_LEN, B_LEN, C_LEN, theta2, t3, t4, w2, al2)


def loop_rates(a, b, c, t2, t3, t4, w2, al2=0.0):
    """(w3, w4, al3, al4) of any four-bar: the loop a e2 + b e3 - c e4 - d = 0 (d fixed)
    differentiated once and twice, solved by Cramer's rule (the textbook closed form)."""
    w3 = a * w2 * math.sin(t4 - t2) / (b * math.sin(t3 - t4))
    w4 = a * w2 * math.sin(t3 - t2) / (c * math.sin(t3 - t4))
    # second derivative: b al3 i e3 - c al4 i e4 = rhs (complex), rhs from the squares
    rhs = (-(a * al2 * 1j - a * w2**2) * complex(math.cos(t2), math.sin(t2))
           + b * w3**2 * complex(math.cos(t3), math.sin(t3))
           - c * w4**2 * complex(math.cos(t4), math.sin(t4)))
    # columns: b i e3 and -c i e4 as (re, im)
    m11, m21 = -b * math.sin(t3), b * math.cos(t3)
    m12, m22 = c * math.sin(t4), -c * math.cos(t4)
    det = m11 * m22 - m12 * m21
    al3 = (rhs.real * m22 - m12 * rhs.imag) / det
    al4 = (m11 * rhs.imag - m21 * rhs.real) / det
    return w3, w4, al3, al4


def capsule_mass_inertia(length: float, r: float = RADIUS, rho: float = DENSITY):
    """Mass (kg) and inertia (kg m^2) about the axis through the centre perpendicular to a
    capsule of cylinder length ``length``: the cylinder plus two hemispheres (their centres
    3r/8 from the flat faces), the textbook composition."""
    mc = rho * math.pi * r**2 * length
    ms = rho * 4.0 / 3.0 * math.pi * r**3
    i_cyl = mc * (r**2 / 4 + length**2 / 12)
    i_hemis = ms * (2 * r**2 / 5 + length**2 / 4 + 3 * length * r / 8)
    return mc + ms, i_cyl + i_hemis


def _f(x: float) -> str:
    return repr(float(x))


def four_bar_xml(closure: str = "anchor", tilt: float = 0.0, gap: float = 0.0,
                 anchor_beyond: float = 0.0, stiff: bool = False) -> str:
    """The four-bar as a user writes it: a default class for the links, inertia from
    capsule geoms with a density, bodies placed at the assembled pose.  ``closure``:
    "anchor" (connect by an anchor in the coupler's frame) or "sites" (connect site1/
    site2); ``tilt`` tilts the rocker's hinge axis (rad) about x; ``gap`` moves the
    rocker's site this far along the rocker, beyond B (m); ``anchor_beyond`` puts the
    connect's anchor this far beyond the coupler's end along the coupler (m); ``stiff``
    gives the connect a near-hard solref 0.002 s and solimp 0.9999 (else MuJoCo's
    defaults, 0.02 s and 0.9-0.95)."""
    (ax, az), (bx, bz), t3, _ = four_bar_pose()
    cbx, cbz = bx - ax, bz - az
    ext = 1 + anchor_beyond / B_LEN
    rbx, rbz = bx - D_LEN, bz
    sg = 1 + gap / C_LEN
    rocker_axis = f"{_f(math.sin(tilt))} {_f(-math.cos(tilt))} 0"
    soft = 'solref="0.002 1" solimp="0.9999 0.9999 0.001" ' if stiff else ""
    if closure == "anchor":
        eq = (f'<connect name="close" {soft}body1="coupler" body2="rocker" '
              f'anchor="{_f(cbx * ext)} 0 {_f(cbz * ext)}"/>')
    else:
        eq = f'<connect name="close" {soft}site1="coupler_B" site2="rocker_B"/>'
    return f"""<mujoco model="user-four-bar">
  <compiler angle="degree" inertiafromgeom="true"/>
  <option gravity="0 0 -9.81" timestep="0.0005" integrator="RK4"/>
  <default>
    <default class="link">
      <joint type="hinge" axis="0 -1 0" damping="0"/>
      <geom type="capsule" size="{RADIUS}" density="{DENSITY}" contype="0" conaffinity="0"/>
      <site size="0.005"/>
    </default>
  </default>
  <worldbody>
    <geom type="plane" size="1 1 0.1" pos="0 0 -0.5"/>
    <body name="crank" childclass="link">
      <joint name="O2"/>
      <geom fromto="0 0 0 {_f(ax)} 0 {_f(az)}"/>
      <body name="coupler" pos="{_f(ax)} 0 {_f(az)}">
        <joint name="A"/>
        <geom fromto="0 0 0 {_f(cbx)} 0 {_f(cbz)}"/>
        <site name="coupler_B" pos="{_f(cbx)} 0 {_f(cbz)}"/>
      </body>
    </body>
    <body name="rocker" pos="{D_LEN} 0 0" childclass="link">
      <joint name="O4" axis="{rocker_axis}"/>
      <geom fromto="0 0 0 {_f(rbx)} 0 {_f(rbz)}"/>
      <site name="rocker_B" pos="{_f(rbx * sg)} 0 {_f(rbz * sg)}"/>
    </body>
  </worldbody>
  <equality>
    {eq}
  </equality>
  <actuator>
    <motor name="drive" joint="O2" gear="1"/>
  </actuator>
</mujoco>
"""


# --- the slider-crank: crank r = 0.1 m at 60 deg, rod l = 0.3 m, slider on the x axis ---
R_CRANK, L_ROD = 0.1, 0.3


def slider_crank_pose(theta: float = THETA2):
    """(A, x_slider, theta3): crank tip, slider position on x, rod angle."""
    ax, az = R_CRANK * math.cos(theta), R_CRANK * math.sin(theta)
    t3 = -math.asin(R_CRANK * math.sin(theta) / L_ROD)
    return (ax, az), ax + L_ROD * math.cos(t3), t3


def slider_crank_rates(w: float, theta: float = THETA2):
    """(w3, al3, v, a): rod rate and acceleration, slider velocity and acceleration at a
    constant crank rate: r sin(t) + l sin(t3) = 0 differentiated twice."""
    _, _, t3 = slider_crank_pose(theta)
    r, l = R_CRANK, L_ROD
    w3 = -r * w * math.cos(theta) / (l * math.cos(t3))
    al3 = (r * w**2 * math.sin(theta) + l * w3**2 * math.sin(t3)) / (l * math.cos(t3))
    v = -r * w * math.sin(theta) - l * w3 * math.sin(t3)
    acc = -r * w**2 * math.cos(theta) - l * al3 * math.sin(t3) - l * w3**2 * math.cos(t3)
    return w3, al3, v, acc


def slider_crank_xml() -> str:
    """A slider-crank: the piston on a slide joint along x, the rod's end pinned to it by
    a connect; hinge axes (0, -1, 0) in the XZ plane, gravity -z."""
    (ax, az), xs, t3 = slider_crank_pose()
    rx, rz = xs - ax, -az
    return f"""<mujoco model="user-slider-crank">
  <compiler angle="radian"/>
  <option gravity="0 0 -9.81" timestep="0.0005" integrator="RK4"/>
  <default>
    <joint axis="0 -1 0"/>
    <geom type="capsule" size="0.01" density="7800" contype="0" conaffinity="0"/>
  </default>
  <worldbody>
    <body name="crank">
      <joint name="crank_pin"/>
      <geom fromto="0 0 0 {_f(ax)} 0 {_f(az)}"/>
      <body name="rod" pos="{_f(ax)} 0 {_f(az)}">
        <joint name="wrist"/>
        <geom fromto="0 0 0 {_f(rx)} 0 {_f(rz)}"/>
      </body>
    </body>
    <body name="piston" pos="{_f(xs)} 0 0">
      <joint name="slide" type="slide" axis="1 0 0"/>
      <geom type="box" size="0.02 0.02 0.015" density="7800"/>
    </body>
  </worldbody>
  <equality>
    <connect name="gudgeon" body1="rod" body2="piston" anchor="{_f(rx)} 0 {_f(rz)}"/>
  </equality>
  <actuator>
    <motor joint="crank_pin"/>
  </actuator>
</mujoco>
"""


FIVE_BAR_XML = """<mujoco model="user-five-bar">
  <default><joint axis="0 -1 0"/><geom type="capsule" size="0.01" density="1000"/></default>
  <worldbody>
    <body name="left">
      <joint name="L0"/>
      <geom fromto="0 0 0 0 0 0.2"/>
      <body name="left_arm" pos="0 0 0.2">
        <joint name="L1"/>
        <geom fromto="0 0 0 0.15 0 0.1"/>
      </body>
    </body>
    <body name="right" pos="0.3 0 0">
      <joint name="R0"/>
      <geom fromto="0 0 0 0 0 0.2"/>
      <body name="right_arm" pos="0 0 0.2">
        <joint name="R1"/>
        <geom fromto="0 0 0 -0.15 0 0.1"/>
      </body>
    </body>
  </worldbody>
  <equality>
    <connect name="tip" body1="left_arm" body2="right_arm" anchor="0.15 0 0.1"/>
  </equality>
  <actuator><motor joint="L0"/></actuator>
</mujoco>
"""


def major_four_bar_xml(crank_rate: float = 1.0) -> str:
    """The four-bar of a major simulator's documented example (the SDF four-bar of
    Gazebo's tutorials / Drake's four_bar example): three links of 4 m and 20 kg, ground
    pins 2 m apart, the crank at atan(sqrt 15) above the ground line, so the coupler is
    horizontal and the mechanism an isosceles trapezoid; uniform rods (inertia m L^2/12 +
    a thin section), gravity -z.  At rest this symmetric pose is an equilibrium, so the
    keyframe "moving" releases it with the crank at ``crank_rate`` (rad/s) and the other
    joints at the rates the loop allows (closed form :func:`loop_rates`)."""
    t = math.atan(math.sqrt(15.0))
    w3, w4, _, _ = loop_rates(4.0, 4.0, 4.0, t, math.pi, math.pi - t, crank_rate)
    qvel = f"{_f(crank_rate)} {_f(w3 - crank_rate)} {_f(w4)}"
    ax, az = 4 * math.cos(t), 4 * math.sin(t)    # (1, sqrt 15)
    return f"""<mujoco model="major-four-bar">
  <option gravity="0 0 -9.81" timestep="0.001" integrator="RK4"/>
  <default>
    <joint axis="0 -1 0"/>
    <geom type="capsule" size="0.05" contype="0" conaffinity="0"/>
  </default>
  <worldbody>
    <body name="crank">
      <joint name="crank_pin"/>
      <inertial pos="{_f(ax / 2)} 0 {_f(az / 2)}" mass="20"
                diaginertia="26.6666666666667 26.6666666666667 0.01" quat="{_quat_y(t)}"/>
      <geom fromto="0 0 0 {_f(ax)} 0 {_f(az)}"/>
      <body name="coupler" pos="{_f(ax)} 0 {_f(az)}">
        <joint name="coupler_pin"/>
        <inertial pos="-2 0 0" mass="20" diaginertia="0.01 26.6666666666667 26.6666666666667"/>
        <geom fromto="0 0 0 -4 0 0"/>
      </body>
    </body>
    <body name="rocker" pos="-2 0 0">
      <joint name="rocker_pin"/>
      <inertial pos="{_f(-ax / 2)} 0 {_f(az / 2)}" mass="20"
                diaginertia="26.6666666666667 26.6666666666667 0.01"
                quat="{_quat_y(math.pi - t)}"/>
      <geom fromto="0 0 0 {_f(-ax)} 0 {_f(az)}"/>
    </body>
  </worldbody>
  <equality>
    <connect name="loop" body1="coupler" body2="rocker" anchor="-4 0 0"/>
  </equality>
  <keyframe>
    <key name="moving" qpos="0 0 0" qvel="{qvel}"/>
  </keyframe>
</mujoco>
"""


def _quat_y(angle_xz: float) -> str:
    """The quaternion turning a frame's z axis onto the in-plane direction at angle
    ``angle_xz`` from +x towards +z (a rod's long axis for diaginertia Ixx = Iyy > Izz)."""
    # z -> (cos t, 0, sin t): a rotation about y by (pi/2 - t)
    h = (math.pi / 2 - angle_xz) / 2
    return f"{_f(math.cos(h))} 0 {_f(math.sin(h))} 0"


def chain_four_bar_xml() -> str:
    """The four-bar as one chain world-crank-coupler-rocker, its loop closed at the
    ground pin O4 by a connect to the world (``body2`` left out), near-hard."""
    (ax, az), (bx, bz), _, _ = four_bar_pose()
    return f"""<mujoco model="chain-four-bar">
  <option gravity="0 0 -9.81" timestep="0.0005" integrator="RK4"/>
  <default>
    <joint axis="0 -1 0"/>
    <geom type="capsule" size="{RADIUS}" density="{DENSITY}" contype="0" conaffinity="0"/>
  </default>
  <worldbody>
    <body name="crank">
      <joint name="O2"/>
      <geom fromto="0 0 0 {_f(ax)} 0 {_f(az)}"/>
      <body name="coupler" pos="{_f(ax)} 0 {_f(az)}">
        <joint name="A"/>
        <geom fromto="0 0 0 {_f(bx - ax)} 0 {_f(bz - az)}"/>
        <body name="rocker" pos="{_f(bx - ax)} 0 {_f(bz - az)}">
          <joint name="B"/>
          <geom fromto="0 0 0 {_f(D_LEN - bx)} 0 {_f(-bz)}"/>
        </body>
      </body>
    </body>
  </worldbody>
  <equality>
    <connect name="O4" body1="rocker" anchor="{_f(D_LEN - bx)} 0 {_f(-bz)}"
             solref="0.002 1" solimp="0.9999 0.9999 0.001"/>
  </equality>
  <actuator><motor joint="O2"/></actuator>
</mujoco>
"""


def four_bar_urdf(plane: str = "xy") -> str:
    """The test four-bar as a URDF (the XY plane, joint axes +z, link frames along each
    link, inertia of uniform rods of 0.2 / 0.6 / 0.5 kg), an open tree: its loop is
    closed on the command line by ``--close coupler:0.3,0,0=rocker:0.25,0,0``.
    ``plane="xz"``: the same in the XZ plane (joint axes -y, each joint's origin turned
    about -y, i.e. ``rpy = (0, -angle, 0)``), so gravity -z acts in its plane."""
    _, _, t3, t4 = four_bar_pose()
    xz = plane == "xz"

    def link(name: str, length: float, mass: float) -> str:
        i = mass * length**2 / 12
        return (f'<link name="{name}"><inertial><origin xyz="{_f(length / 2)} 0 0"/>'
                f'<mass value="{mass}"/><inertia ixx="1e-9" iyy="{_f(i)}" izz="{_f(i)}" '
                'ixy="0" ixz="0" iyz="0"/></inertial></link>')

    def joint(name, parent, child, xyz, yaw) -> str:
        rpy, axis = (f"0 {_f(-yaw)} 0", "0 -1 0") if xz else (f"0 0 {_f(yaw)}", "0 0 1")
        return (f'<joint name="{name}" type="continuous"><parent link="{parent}"/>'
                f'<child link="{child}"/><origin xyz="{xyz}" rpy="{rpy}"/>'
                f'<axis xyz="{axis}"/></joint>')

    return "\n".join([
        '<robot name="urdf-four-bar">', '<link name="base"/>',
        link("crank", A_LEN, 0.2), link("coupler", B_LEN, 0.6), link("rocker", C_LEN, 0.5),
        joint("O2", "base", "crank", "0 0 0", THETA2),
        joint("A", "crank", "coupler", f"{A_LEN} 0 0", t3 - THETA2),
        joint("O4", "base", "rocker", f"{D_LEN} 0 0", t4), "</robot>", ""])


# --- a Watt six-bar (two four-bars in series, two loops): the four-bar above, its rocker
# a ternary link O4-B-C driving a second four-bar O4-C-D-O6 (link5 C-D, link6 O6-D) ---
O6 = (0.75, 0.25)                 # ground pin of link6 (x, z), m
R4C, DELTA4 = 0.2, math.radians(-30.0)  # O4->C on the rocker: 0.2 m at -30 deg from O4->B
L5, L6 = 0.35, 0.3


def _circles(p, r1, q, r2):
    """The intersection of the circles (p, r1) and (q, r2) to the left of p -> q."""
    dx, dz = q[0] - p[0], q[1] - p[1]
    e = math.hypot(dx, dz)
    along = (r1**2 - r2**2 + e**2) / (2 * e)
    h = math.sqrt(r1**2 - along**2)
    ux, uz = dx / e, dz / e
    return (p[0] + along * ux - h * uz, p[1] + along * uz + h * ux)


def six_bar_pose(theta2: float = THETA2):
    """The joint points (x, z) O2, A, B, O4, C, D, O6 of the six-bar at ``theta2``, from
    circle intersections (B above the ground line, D left of C -> O6)."""
    (ax, az), (bx, bz), _, t4 = four_bar_pose(theta2)
    c = (D_LEN + R4C * math.cos(t4 + DELTA4), R4C * math.sin(t4 + DELTA4))
    d = _circles(c, L5, O6, L6)
    return {"O2": (0.0, 0.0), "A": (ax, az), "B": (bx, bz), "O4": (D_LEN, 0.0), "C": c,
            "D": d, "O6": O6}


def six_bar_xml(stiff: bool = True) -> str:
    """The six-bar as a user writes it: crank and coupler a chain from the world, the
    ternary rocker (geoms to B and to C) with link5 its child at C, link6 on the ground at
    O6; the loops closed by a connect at B (anchor, in the coupler's frame) and one at D
    (two sites).  Capsules with a density, the XZ plane, gravity -z.  ``stiff``: the
    connects near-hard (solref 0.002 s, solimp 0.9999)."""
    p = six_bar_pose()
    soft = 'solref="0.002 1" solimp="0.9999 0.9999 0.001" ' if stiff else ""

    def rel(a: str, b: str) -> str:  # point b in a frame at point a (no rotation), "x 0 z"
        return f"{_f(p[b][0] - p[a][0])} 0 {_f(p[b][1] - p[a][1])}"

    return f"""<mujoco model="user-watt-six-bar">
  <option gravity="0 0 -9.81" timestep="0.0005" integrator="RK4"/>
  <default>
    <joint axis="0 -1 0"/>
    <geom type="capsule" size="{RADIUS}" density="{DENSITY}" contype="0" conaffinity="0"/>
  </default>
  <worldbody>
    <body name="crank">
      <joint name="O2"/>
      <geom fromto="0 0 0 {rel('O2', 'A')}"/>
      <body name="coupler" pos="{rel('O2', 'A')}">
        <joint name="A"/>
        <geom fromto="0 0 0 {rel('A', 'B')}"/>
      </body>
    </body>
    <body name="rocker" pos="{rel('O2', 'O4')}">
      <joint name="O4"/>
      <geom fromto="0 0 0 {rel('O4', 'B')}"/>
      <geom fromto="0 0 0 {rel('O4', 'C')}"/>
      <body name="link5" pos="{rel('O4', 'C')}">
        <joint name="C"/>
        <geom fromto="0 0 0 {rel('C', 'D')}"/>
        <site name="link5_D" pos="{rel('C', 'D')}"/>
      </body>
    </body>
    <body name="link6" pos="{rel('O2', 'O6')}">
      <joint name="O6"/>
      <geom fromto="0 0 0 {rel('O6', 'D')}"/>
      <site name="link6_D" pos="{rel('O6', 'D')}"/>
    </body>
  </worldbody>
  <equality>
    <connect name="B" {soft}body1="coupler" body2="rocker" anchor="{rel('A', 'B')}"/>
    <connect name="D" {soft}site1="link5_D" site2="link6_D"/>
  </equality>
  <actuator><motor joint="O2"/></actuator>
</mujoco>
"""
