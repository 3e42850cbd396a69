"""Every figure of REFERENCE S1-S4 (the seed notes' worked examples) from the built-in cases.

Expected values are REFERENCE.md's "exact" column, which was computed independently
from closed forms; each is checked to half a unit in its last printed digit (at
least 5 significant figures).  Where the notes' own printed number differs, the
comment says why and the exact value is what is checked.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from analytic import Linkage, load_case

INCH = 0.0254


def printed(text: str) -> tuple[float, float]:
    """A printed figure and its rounding half-width (half a unit in its last digit)."""
    decimals = len(text.split(".")[1]) if "." in text else 0
    return float(text), 0.5 * 10.0 ** -decimals


def check(actual: float, text: str, scale: float = 1.0) -> None:
    """``actual`` (SI) equals the printed figure ``text`` in units of ``scale``."""
    value, half = printed(text)
    assert abs(actual / scale - value) <= half * (1 + 1e-9), (actual / scale, text)


def wrap_deg(rad: float) -> float:
    return 180.0 - (180.0 - math.degrees(rad)) % 360.0


@pytest.fixture(scope="module")
def s1():
    lk = Linkage(load_case("seed-slider-crank"))
    kin = lk.kinematics()
    return lk, kin, lk.forces(kin)


def _b(lk, name):
    return lk.body_index(name)


# --- S1: slider-crank kinematics (notes week 4) ------------------------------
# The notes' figures (theta3 = -14.47, AC = 28.0 cm, alpha3 = 8259) carry their
# rounded intermediates (theta3 rounded to 345.5 deg before alpha3 was computed).
def test_s1_theta3(s1):
    lk, kin, _ = s1
    check(wrap_deg(kin.theta[0, _b(lk, "rod")]), "-14.4775")


def test_s1_slider_distance(s1):
    _, kin, _ = s1
    check(kin.slider("slide")[0][0], "28.0252", 0.01)


def test_s1_omega3(s1):
    lk, kin, _ = s1
    check(kin.omega[0, _b(lk, "rod")], "-89.4427")


def test_s1_slider_velocity(s1):
    _, kin, _ = s1
    check(kin.slider("slide")[1][0], "-14.4721")


def test_s1_alpha3(s1):
    lk, kin, _ = s1
    check(kin.alpha[0, _b(lk, "rod")], "8262.36")


def test_s1_slider_acceleration(s1):
    _, kin, _ = s1
    check(kin.slider("slide")[2][0], "-4600.18")


# --- S2: kinetostatics (notes week 8), g = 0 ----------------------------------
# The notes' force figures (R_B = 16160 N, F_C = 3359 N) come from lever arms
# measured on a drawing and from typos (a_B written with 0.2 m, I3*alpha3 with
# 0.2); the exact values below are what the equations give.
def test_s2_a_g3(s1):
    _, kin, _ = s1
    check(np.hypot(*kin.point("rod", "G3")[2][0]), "4154.29")


def test_s2_motor_torque(s1):
    _, _, frc = s1
    check(frc.effort[0], "476.56")


def test_s2_motor_power(s1):
    _, _, frc = s1
    check(frc.power[0], "95.31", 1e3)


@pytest.mark.parametrize("joint", ["A", "B"])
def test_s2_crank_pin_forces(s1, joint):
    _, _, frc = s1
    check(np.hypot(*frc.joint_force[joint][0]), "15720.5")


def test_s2_rod_slider_force(s1):
    _, _, frc = s1
    check(np.hypot(*frc.joint_force["C"][0]), "3280.3")


def test_s2_slider_normal_force(s1):
    _, _, frc = s1
    check(abs(frc.normal["slide"][0]), "363.3")


def test_s2_torque_with_gravity():
    from dataclasses import replace
    mech = replace(load_case("seed-slider-crank"), gravity=(0.0, -9.81))
    lk = Linkage(mech)
    check(lk.forces(lk.kinematics()).effort[0], "477.83")


# --- S3: relative-acceleration examples (Hibbeler ch. 16) --------------------
def test_s3_1_two_inclines():
    lk = Linkage(load_case("hibbeler-two-inclines"))
    kin = lk.kinematics()
    bar = _b(lk, "bar")
    check(kin.omega[0, bar], "0.28284")
    check(kin.slider("slideB")[2][0], "1.8686")
    # REFERENCE prints alpha "exact 0.34400", which is the 3-figure textbook answer
    # padded with zeros.  The closed form of this instant (bar horizontal, L = 10 m,
    # lines at -45/+45 deg): x: a_B/sqrt2 = a_A/sqrt2 - L w^2,
    # y: a_B/sqrt2 = -a_A/sqrt2 + L alpha  ->  alpha = (2 a_A/sqrt2 - L w^2) / L.
    w = 2 * math.sqrt(2) / 10
    alpha = (2 * 3 / math.sqrt(2) - 10 * w * w) / 10
    assert kin.alpha[0, bar] == pytest.approx(alpha, rel=1e-12)
    check(kin.alpha[0, bar], "0.344")


def test_s3_2_hibbeler_16_121():
    lk = Linkage(load_case("hibbeler-16-121"))
    kin = lk.kinematics()
    rod = _b(lk, "rod")
    check(kin.omega[0, rod], "1.125")
    check(abs(kin.slider("slide")[1][0]), "9.375", INCH)
    check(kin.alpha[0, rod], "-3.00")
    check(abs(kin.slider("slide")[2][0]), "54.65", INCH)


def test_s3_3_hibbeler_16_30():
    # Exact by hand: v_B = v_C + w_CB k x (0.2, -0.2) = w_AB k x (0, -0.2) gives
    # w_CB = w_AB = 10; the same with accelerations gives 19 + 0.2 alpha_CB = 20 and
    # 1 - 20 = 0.2 alpha_AB, i.e. alpha_CB = 5 and alpha_AB = -95 exactly.
    lk = Linkage(load_case("hibbeler-16-30"))
    kin = lk.kinematics()
    exact = {("omega", "linkAB"): 10.0, ("omega", "linkCB"): 10.0,
             ("alpha", "linkCB"): 5.0, ("alpha", "linkAB"): -95.0}
    for (what, body), value in exact.items():
        assert getattr(kin, what)[0, _b(lk, body)] == pytest.approx(value, rel=1e-12)


def test_s3_4_hibbeler_16_31():
    # The notes' a_C = -13.6 rounds intermediates; the exact value is -13.54.
    lk = Linkage(load_case("hibbeler-16-31"))
    kin = lk.kinematics()
    rod = _b(lk, "rod")
    check(kin.omega[0, rod], "2.425")
    check(kin.alpha[0, rod], "27.68")
    check(kin.slider("slide")[2][0], "-13.54")


# --- S4: four-bar (machine dynamics week 6) -----------------------------------
@pytest.fixture(scope="module")
def s4():
    lk = Linkage(load_case("seed-four-bar"))
    kin = lk.kinematics()
    return lk, kin, lk.forces(kin)


def test_s4_angles(s4):
    lk, kin, _ = s4
    check(wrap_deg(kin.theta[0, _b(lk, "coupler")]), "29.379")
    # the notes' r4 points from the coupler pin back to O4: rocker angle + 180 deg
    check(math.degrees(kin.theta[0, _b(lk, "rocker")]) % 360 + 180, "290.753")


def test_s4_omegas(s4):
    lk, kin, _ = s4
    check(kin.omega[0, _b(lk, "coupler")], "-3.9164")
    check(kin.omega[0, _b(lk, "rocker")], "3.0911")


def test_s4_alphas(s4):
    # SolidWorks Motion in the notes: 2421.706 and 5471.96 deg/s^2 (42.266, 95.503 rad/s^2)
    lk, kin, _ = s4
    check(kin.alpha[0, _b(lk, "coupler")], "42.2670")
    check(kin.alpha[0, _b(lk, "rocker")], "95.5036")


def test_s4_forces_engine_notes(s4):
    """The uniform-rod masses of ENGINE_NOTES.md; its reference was checked there
    against T2 omega2 = dKE/dt."""
    _, _, frc = s4
    check(frc.effort[0], "0.67334")
    for joint, (fx, fy) in {"O2": ("-14.775", "-12.124"), "A": ("-13.650", "-10.175"),
                            "B": ("3.8305", "1.1213"), "O4": ("-1.5396", "-1.5521")}.items():
        check(frc.joint_force[joint][0, 0], fx)
        check(frc.joint_force[joint][0, 1], fy)
