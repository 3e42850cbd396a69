"""``xval import`` of MJCF models written by hand (tests/sim_models/own/user_models.py):
the description MuJoCo's compiler gives, its kinematics at the model's configuration
against the closed forms, and the one-line refusals."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from analytic.errors import DescriptionError
from analytic.kinematics import Linkage
from analytic.toml_io import mechanism_from_dict
from sim_models.own import import_model, imported_toml

from . import user_models as um

pytest.importorskip("mujoco")

#: Body rates and accelerations against the closed forms, relative to the peak over the
#: bodies: the issue's 1e-12 (both sides are double-precision closed forms of a
#: well-conditioned loop; the importer's geometry is MuJoCo's, exact to its float64
#: kinematics).
RATE_TOL = 1e-12
#: Masses and inertias against the capsule's closed form: MuJoCo computes the same
#: composition in double precision (a few ulps).
MASS_TOL = 1e-12
W_IN = 10.0  # rad/s, the input rate


def _write(tmp_path, text: str, name: str = "model.xml") -> str:
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def _rates(mech, w_in: float = W_IN) -> dict[str, tuple[float, float]]:
    lk = Linkage(mech.with_driver(velocity=w_in, acceleration=0.0))
    kin = lk.kinematics()
    return {b.name: (float(kin.omega[0, lk.body_index(b.name)]),
                     float(kin.alpha[0, lk.body_index(b.name)]))
            for b in mech.moving_bodies}


def _check_rates(got: dict, want: dict) -> float:
    peak_w = max(abs(w) for w, _ in want.values())
    peak_a = max(abs(a) for _, a in want.values())
    worst = 0.0
    for name, (w, a) in want.items():
        worst = max(worst, abs(got[name][0] - w) / peak_w, abs(got[name][1] - a) / peak_a)
    assert worst <= RATE_TOL, (got, want)
    return worst


@pytest.mark.parametrize("closure", ["anchor", "sites"])
def test_four_bar_xz_plane(tmp_path, closure):
    imp = import_model(_write(tmp_path, um.four_bar_xml(closure)))
    mech = imp.mechanism
    assert [b.name for b in mech.moving_bodies] == ["crank", "coupler", "rocker"]
    assert [j.name for j in mech.joints] == ["O2", "A", "O4", "close"]
    assert mech.driver.joint == "O2" and mech.driver.value == 0.0  # qpos0
    np.testing.assert_allclose(imp.plane.n, [0, -1, 0], atol=1e-15)
    assert mech.gravity == pytest.approx((0.0, -9.81), abs=1e-15)
    for name, length in (("crank", um.A_LEN), ("coupler", um.B_LEN), ("rocker", um.C_LEN)):
        m, i = um.capsule_mass_inertia(length)
        b = mech.body(name)
        assert b.mass == pytest.approx(m, rel=MASS_TOL)
        assert b.inertia == pytest.approx(i, rel=MASS_TOL)
    w3, w4, al3, al4 = um.four_bar_rates(W_IN)
    _check_rates(_rates(mech), {"crank": (W_IN, 0.0), "coupler": (w3, al3),
                                "rocker": (w4, al4)})
    text = imported_toml(imp)
    assert f"equality connect 'close' ({'anchor' if closure == 'anchor' else 'sites'}" in text
    import tomllib
    again = mechanism_from_dict(tomllib.loads(text), "again")  # the file reads back
    _check_rates(_rates(again), _rates(mech))


def test_slider_crank(tmp_path):
    imp = import_model(_write(tmp_path, um.slider_crank_xml()))
    mech = imp.mechanism
    assert mech.driver.joint == "crank_pin"
    w3, al3, v, acc = um.slider_crank_rates(W_IN)
    _check_rates(_rates(mech), {"crank": (W_IN, 0.0), "rod": (w3, al3),
                                "piston": (0.0, 0.0)})
    lk = Linkage(mech.with_driver(velocity=W_IN))
    kin = lk.kinematics()
    s, sd, sdd = (float(x[0]) for x in kin.slider("slide"))
    assert s == pytest.approx(0.0, abs=1e-15)  # the model's qpos of the slide at qpos0
    assert sd == pytest.approx(v, abs=RATE_TOL * abs(v))
    assert sdd == pytest.approx(acc, abs=RATE_TOL * abs(acc))


def test_five_bar_refused(tmp_path):
    with pytest.raises(DescriptionError, match=r"2 degrees of freedom: joints \['L0', 'R0'\]"):
        import_model(_write(tmp_path, um.FIVE_BAR_XML))


def test_tilted_hinge_refused(tmp_path):
    with pytest.raises(DescriptionError, match=r"joint 'O4': hinge axis is tilted by 0\.001 "):
        import_model(_write(tmp_path, um.four_bar_xml(tilt=1e-3)))


def test_site_loop_2mm_open_refused(tmp_path):
    with pytest.raises(DescriptionError, match=r"connect 'close' .*open by 2 mm"):
        import_model(_write(tmp_path, um.four_bar_xml("sites", gap=0.002)))


def test_anchor_beyond_coupler_read_as_mujoco(tmp_path):
    """The anchor 2 mm beyond the coupler's end: MuJoCo pins the rocker where that point
    lies at qpos0; the reference's rates, put into MuJoCo's joint velocities, leave its
    own constraint's velocity (efc_vel of the connect rows) at rounding."""
    import mujoco
    path = _write(tmp_path, um.four_bar_xml(anchor_beyond=0.002))
    imp = import_model(path)
    rates = _rates(imp.mechanism)
    m = mujoco.MjModel.from_xml_path(path)
    d = mujoco.MjData(m)
    # MuJoCo's joint velocities: O2 the crank's rate, A the coupler's relative to the
    # crank, O4 the rocker's (all hinge axes along the plane's normal)
    d.qvel[:] = [rates["crank"][0], rates["coupler"][0] - rates["crank"][0],
                 rates["rocker"][0]]
    mujoco.mj_forward(m, d)
    rows = d.efc_type == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    assert rows.sum() == 3
    scale = W_IN * um.A_LEN  # the crank tip's speed, m/s
    assert np.abs(d.efc_vel[rows]).max() <= 1e-12 * scale
    # and the geometry differs from the 2 mm-shorter closure: not the textbook rates
    w3, _, _, _ = um.four_bar_rates(W_IN)
    assert abs(rates["coupler"][0] - w3) > 1e-6 * W_IN


def test_major_simulator_four_bar(tmp_path):
    imp = import_model(_write(tmp_path, um.major_four_bar_xml()), driver="crank_pin")
    mech = imp.mechanism
    for b in mech.moving_bodies:
        assert b.mass == 20.0 and b.inertia == pytest.approx(20 * 16 / 12, rel=1e-13)
    t2 = math.atan(math.sqrt(15.0))
    w3, w4, al3, al4 = um.loop_rates(4.0, 4.0, 4.0, t2, math.pi, math.pi - t2, W_IN)
    _check_rates(_rates(mech), {"crank": (W_IN, 0.0), "coupler": (w3, al3),
                                "rocker": (w4, al4)})


def test_driver_and_keyframe_refusals(tmp_path):
    path = _write(tmp_path, um.major_four_bar_xml())
    with pytest.raises(DescriptionError, match="no actuated joint: name the input"):
        import_model(path)
    with pytest.raises(DescriptionError, match="--driver 'nope': no such"):
        import_model(path, driver="nope")
    with pytest.raises(DescriptionError, match="no keyframe 'k'"):
        import_model(path, driver="crank_pin", keyframe="k")


PENDULUM_ELEMENTS = """<mujoco model="elements">
  <compiler angle="degree"/>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="arm">
      <joint name="pivot" axis="0 -1 0" damping="0.3" stiffness="2" springref="30"
             armature="0.01" frictionloss="0.1" limited="true" range="-170 170"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.02" mass="1"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="torque" joint="pivot" gear="2"/>
    <position name="servo" joint="pivot" kp="5"/>
  </actuator>
  <keyframe>
    <key name="up" qpos="0.5" qvel="1.5" ctrl="0.25 0"/>
  </keyframe>
</mujoco>
"""


def test_elements_keyframe_and_not_modelled(tmp_path):
    """Joint damping, stiffness about springref, a constant-effort motor (gear x ctrl of
    the keyframe) and the armature of a ground hinge (added to the body's inertia: its
    kinetic energy is a (w - 0)^2 / 2) are carried; friction loss, the limit and the
    position actuator are listed as not modelled."""
    imp = import_model(_write(tmp_path, PENDULUM_ELEMENTS), driver="pivot", keyframe="up")
    mech, fm = imp.mechanism, imp.mechanism.motion
    assert mech.driver.value == 0.5 and fm.value == 0.5 and fm.rate == 1.5
    assert [(d.joint, d.coefficient) for d in fm.dampers] == [("pivot", 0.3)]
    (sp,) = fm.springs
    assert sp.stiffness == 2.0 and sp.free_value == pytest.approx(math.radians(30), rel=1e-15)
    (mo,) = fm.motors
    assert mo.effort == pytest.approx(2 * 0.25, rel=1e-15)
    m_rod, length, r = 1.0, 0.5, 0.02
    # MuJoCo's capsule of mass 1 kg: cylinder + hemispheres, as in the test above
    _, i_unit = um.capsule_mass_inertia(length, r, rho=1.0)
    m_unit, _ = um.capsule_mass_inertia(length, r, rho=1.0)
    i_com = i_unit * m_rod / m_unit
    assert mech.body("arm").inertia == pytest.approx(i_com + 0.01, rel=1e-12)
    text = " ".join(imp.not_modelled)
    assert "friction loss on joints ['pivot']" in text and "limits on joints ['pivot']" in text
    assert "actuator 'servo'" in text


@pytest.mark.parametrize("xml, words", [
    ("""<mujoco><worldbody><body name="b"><joint name="j" type="ball"/>
        <geom size="0.1"/></body></worldbody></mujoco>""", "joint 'j' is a ball joint"),
    ("""<mujoco><worldbody><body name="b"><joint name="j1" axis="0 1 0"/>
        <joint name="j2" axis="0 1 0"/><geom size="0.1"/></body></worldbody></mujoco>""",
     "body 'b' has 2 joints"),
    ("""<mujoco><worldbody><body name="a"><joint name="ja" axis="0 1 0"/><geom size="0.1"/>
        </body><body name="b" pos="1 0 0"><joint name="jb" axis="0 1 0"/><geom size="0.1"/>
        </body></worldbody><equality><weld name="glue" body1="a" body2="b"/></equality>
        </mujoco>""", "equality 'glue' is a weld constraint"),
])
def test_what_the_description_cannot_hold_is_refused(tmp_path, xml, words):
    with pytest.raises(DescriptionError, match=re.escape(words)):
        import_model(_write(tmp_path, xml), driver="j" if "ball" in xml else None)


@pytest.mark.parametrize("plane", ["xy", "xz"])
def test_urdf_four_bar_closed_on_the_command_line(tmp_path, plane):
    """A URDF four-bar (read by MuJoCo's URDF reader) closed by --close, in the XY plane
    and in the XZ plane (gravity in its plane): the rates and accelerations at 10 rad/s
    against the closed form; left open it is refused, naming its degrees of freedom and
    how to close it."""
    from sim_models.own import Close
    path = _write(tmp_path, um.four_bar_urdf(plane), "four_bar.urdf")
    close = Close("coupler", (um.B_LEN, 0.0, 0.0), "rocker", (um.C_LEN, 0.0, 0.0))
    imp = import_model(path, driver="O2", closes=(close,))
    w3, w4, al3, al4 = um.four_bar_rates(W_IN)
    _check_rates(_rates(imp.mechanism), {"crank": (W_IN, 0.0), "coupler": (w3, al3),
                                         "rocker": (w4, al4)})
    assert imp.mechanism.body("coupler").inertia == pytest.approx(0.6 * 0.3**2 / 12,
                                                                   rel=1e-12)
    with pytest.raises(DescriptionError, match=r"3 degrees of freedom: .* --close LINK_A"):
        import_model(path, driver="O2")


def _loop_rates(pts: dict, loops, w_in: float):
    """Body rates and accelerations of a closed planar linkage, solved independently of the
    importer by numpy linear algebra on its loop vectors: each loop is a list of
    ``(body, sign, from point, to point)`` whose signed vectors sum to zero; a vector r
    fixed in a body turning at w has r' = w J r and r'' = al J r - w^2 r (J: +90 deg).
    The input body ``crank`` turns at ``w_in`` with no acceleration."""
    def vec(a, b):
        return np.subtract(pts[b], pts[a])

    def jr(r):
        return np.array([-r[1], r[0]])

    unknown = sorted({b for lp in loops for b, *_ in lp} - {"crank"})
    col = {b: k for k, b in enumerate(unknown)}
    m, rhs_v = np.zeros((2 * len(loops), len(unknown))), np.zeros(2 * len(loops))
    for i, lp in enumerate(loops):
        for b, s, a, e in lp:
            r = s * vec(a, e)
            if b == "crank":
                rhs_v[2 * i:2 * i + 2] -= w_in * jr(r)
            else:
                m[2 * i:2 * i + 2, col[b]] += jr(r)
    w = dict(zip(unknown, np.linalg.solve(m, rhs_v), strict=True)) | {"crank": w_in}
    rhs_a = np.zeros(2 * len(loops))
    for i, lp in enumerate(loops):
        for b, s, a, e in lp:
            rhs_a[2 * i:2 * i + 2] += w[b] ** 2 * s * vec(a, e)
    al = dict(zip(unknown, np.linalg.solve(m, rhs_a), strict=True)) | {"crank": 0.0}
    return {b: (float(w[b]), float(al[b])) for b in w}


def test_watt_six_bar_two_loops(tmp_path):
    """A Watt six-bar (two connect closures, one by anchor, one by sites): every body's rate
    and angular acceleration at qpos0 at 10 rad/s against the loop equations solved in this
    test; the ternary rocker's mass and inertia against its two capsules composed here."""
    imp = import_model(_write(tmp_path, um.six_bar_xml()))
    mech = imp.mechanism
    assert [j.name for j in mech.joints] == ["O2", "A", "O4", "C", "O6", "B", "D"]
    assert mech.driver.joint == "O2" and mech.driver.value == 0.0
    p = um.six_bar_pose()
    loops = [[("crank", 1, "O2", "A"), ("coupler", 1, "A", "B"), ("rocker", -1, "O4", "B")],
             [("rocker", 1, "O4", "C"), ("link5", 1, "C", "D"), ("link6", -1, "O6", "D")]]
    want = _loop_rates(p, loops, W_IN)
    assert set(want) == {b.name for b in mech.moving_bodies}
    worst = _check_rates(_rates(mech), want)
    print(f"six-bar: worst rate/acceleration error {worst:.3g} of peak")
    # the ternary rocker: two capsules O4-B and O4-C, each about its own centre plus m d^2
    parts = []
    for end in ("B", "C"):
        r = np.subtract(p[end], p["O4"])
        mc, ic = um.capsule_mass_inertia(float(np.hypot(*r)))
        parts.append((mc, ic, np.add(p["O4"], r / 2)))
    mass = sum(x[0] for x in parts)
    com = sum(x[0] * x[2] for x in parts) / mass
    inertia = sum(ic + mc * float(np.sum((c - com) ** 2)) for mc, ic, c in parts)
    rocker = mech.body("rocker")
    assert rocker.mass == pytest.approx(mass, rel=MASS_TOL)
    assert rocker.inertia == pytest.approx(inertia, rel=MASS_TOL)
    import tomllib
    again = mechanism_from_dict(tomllib.loads(imported_toml(imp)), "again")
    _check_rates(_rates(again), want)
