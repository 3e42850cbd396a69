"""The fused kernel (analytic.fused) against the numpy path, and the streamed sweep.

The numpy path is the reference: every quantity of every built-in case over its sweep
must agree to :data:`AGREEMENT` of its peak.  Peaks are taken per family of
quantities (all points' accelerations, all joint forces, ...), because a single
series can be round-off alone (a fixed pivot's velocity, a slider's zero moment), and
its own peak is then no scale at all.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from analytic import AssemblyError, Linkage, SingularConfigurationError, case_names, load_case
from analytic.fused import FusedKernel, kernel_for
from analytic.kernels.smallmat import complex_multiply_reproduced
from analytic.positions import size_of
from analytic.stream import sweep_csv
from analytic.sweep import input_values

#: The two paths run the same operations in the same order: complex products as numpy's
#: array multiply rounds them (``smallmat.cmul_fused`` on an FMA machine), ``|z|`` as
#: numpy's SIMD absolute value, libm's cos, sin and atan2 on both sides.  Poses and rates
#: then agree bit for bit on eight of the ten built-in cases, also at the samples next
#: to hibbeler-16-30's limit position where the Jacobian's condition number (~600)
#: amplifies a one-ulp difference in a pose to ~1e-13 of peak (it did, at 1.5e-13,
#: before the complex products were matched).  What remains is the summation order of
#: BLAS (loop sums) and LAPACK's LU for the six-bar's 4x4 system: 5e-15 of peak
#: measured.  The issue asks 1e-13 of peak, with no allowance for conditioning (on a
#: machine whose numpy complex multiply neither helper reproduces, which the probe
#: ``complex_multiply_reproduced`` reports, the kappa allowance below applies instead).
AGREEMENT = 1e-13
#: Random linkages (not the built-in cases) may sit closer to a limit than any sweep
#: sample here: there a one-ulp difference in a sum becomes kappa eps of peak, and the
#: paths must agree to RATE_ROUNDING kappa eps.
RATE_ROUNDING = 4.0
EPS = np.finfo(float).eps
RATE_FAMILIES = {"velocity", "acceleration", "omega", "alpha", "qd", "qdd", "force",
                 "effort", "power", "moment"}
DATA = Path(__file__).parent / "data"
POINTS = 721


def _rel(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / max(float(np.max(np.abs(b))), 1e-300))


def _families(lk, kin, frc):
    """Every output, grouped into families that share a scale."""
    pos, vel, acc = [], [], []
    for body in lk.mech.bodies:
        for pn in body.points:
            p, v, a = kin.point_c(body.name, pn)
            pos.append(p)
            vel.append(v)
            acc.append(a)
    fam = {"position": np.stack(pos, 1), "velocity": np.stack(vel, 1),
           "acceleration": np.stack(acc, 1), "theta": kin.theta, "omega": kin.omega,
           "alpha": kin.alpha, "q": kin.q, "qd": kin.qd, "qdd": kin.qdd,
           "origin": kin.zO, "E": kin.E, "determinant": kin.determinant,
           "jacobian": kin.jacobian}
    for name, tr in kin.transmission.items():
        fam["transmission " + name] = tr
    if frc is not None:
        f = [frc.joint_force[k] for k in sorted(frc.joint_force)] + \
            [frc.normal[k] for k in sorted(frc.normal)]
        fam["force"] = np.concatenate([np.reshape(x, (len(x), -1)) for x in f], axis=1)
        fam["effort"] = frc.effort
        fam["power"] = np.stack([frc.power, frc.kinetic_rate, frc.load_power,
                                 frc.power_residual], 1)
        if frc.moment:
            fam["moment"] = np.stack([frc.moment[k] for k in sorted(frc.moment)], 1)
    return fam


def _compare(lk, kin, frc, kin0, frc0, conditioned: bool = False):
    """Each family's largest difference over what is allowed at that sample (<= 1 passes):
    AGREEMENT of the family's peak, or (``conditioned``) for rates RATE_ROUNDING kappa
    eps where larger."""
    a, b = _families(lk, kin, frc), _families(lk, kin0, frc0)
    kappa = np.where(np.isfinite(kin0.condition), kin0.condition, 1e300)
    errs = {}
    for k in b:
        peak = float(np.max(np.abs(b[k])))
        if k == "moment":  # a couple's scale: the largest joint force times the size
            peak = max(peak, float(np.max(np.abs(b["force"]))) * size_of(lk.topo))
        d = np.abs(np.asarray(a[k]) - np.asarray(b[k])).reshape(len(kappa), -1).max(axis=1)
        allowed = np.full(len(kappa), AGREEMENT)
        if conditioned and k in RATE_FAMILIES:
            allowed = np.maximum(allowed, RATE_ROUNDING * EPS * kappa)
        errs[k] = float(np.max(d / (max(peak, 1e-300) * allowed)))
    return errs


def _numpy_kinematics(lk, x):
    """The numpy path, whatever Linkage dispatches to."""
    import os
    old = os.environ.get("XVAL_FUSED")
    os.environ["XVAL_FUSED"] = "0"
    try:
        kin = lk.kinematics(x, on_singular="flag")
        frc = lk.forces(kin) if lk.mech.has_mass else None
    finally:
        if old is None:
            del os.environ["XVAL_FUSED"]
        else:
            os.environ["XVAL_FUSED"] = old
    return kin, frc


@pytest.mark.parametrize("case", case_names())
def test_fused_equals_numpy_on_every_case(case):
    lk = Linkage(load_case(case))
    x = input_values(lk, POINTS)[0]
    kin0, frc0 = _numpy_kinematics(lk, x)
    fk = FusedKernel(lk)
    kin, frc = fk.solve(x, on_singular="flag", forces=lk.mech.has_mass)
    # (on a machine whose numpy multiplies complex numbers in a way neither helper
    # reproduces, the paths are not the same arithmetic: kappa eps is allowed there)
    errs = _compare(lk, kin, frc, kin0, frc0, conditioned=not complex_multiply_reproduced())
    worst = max(errs, key=errs.get)
    assert errs[worst] <= 1.0, (worst, errs[worst])
    # the compact state and the forces-only pass are the same numbers
    st = fk.state(x, level=3 if lk.mech.has_mass else 2)
    np.testing.assert_array_equal(st.q, kin.q)
    np.testing.assert_array_equal(st.qdd, kin.qdd)
    if frc is not None:
        np.testing.assert_array_equal(fk.forces(kin).effort, frc.effort)
        np.testing.assert_array_equal(st.scalars[:, 0], frc.effort)
    E, O = fk.poses(x)
    np.testing.assert_array_equal(E, kin.E)
    np.testing.assert_array_equal(O, kin.zO)
    P = fk.joint_positions(x)
    for j, pj in kin.joint_point.items():
        np.testing.assert_array_equal(P[:, j], pj)


@settings(max_examples=25, deadline=None)
@given(crank=st.floats(0.05, 0.3), coupler=st.floats(0.2, 0.6), rocker=st.floats(0.1, 0.5))
def test_fused_equals_numpy_on_random_four_bars(crank, coupler, rocker):
    """Random four-bars (Grashof or not) over their feasible range, up to its limits: the
    same numbers, to AGREEMENT of peak or, at samples next to a limit, RATE_ROUNDING
    kappa eps (one structure: one compiled kernel for all examples)."""
    from tests.conftest import four_bar
    mech = four_bar(0.4, crank, coupler, rocker)
    try:
        lk = Linkage(mech)
    except AssemblyError:
        assume(False)
    x = input_values(lk, POINTS)[0]
    kin0, frc0 = _numpy_kinematics(lk, x)
    kin, frc = FusedKernel(lk).solve(x, on_singular="flag", forces=lk.mech.has_mass)
    if complex_multiply_reproduced():  # poses: the same operations
        np.testing.assert_array_equal(kin.E, kin0.E)
        np.testing.assert_array_equal(kin.zO, kin0.zO)
    errs = _compare(lk, kin, frc, kin0, frc0, conditioned=True)
    worst = max(errs, key=errs.get)
    assert errs[worst] <= 1.0, (worst, errs[worst])


def test_signs_per_configuration():
    """Branch signs are an input per configuration: mixed rows give, row by row, what
    each sign combination gives alone (what branch continuation past a change point
    needs)."""
    lk = Linkage(load_case("six-bar"))
    fk = FusedKernel(lk)
    x = np.radians(np.arange(0.0, 360.0, 5.0))
    held = np.array([lk.positions.signs], float)
    other = held.copy()
    other[0, 1] *= -1
    pick = (np.arange(len(x)) % 3) == 0
    signs = np.where(pick[:, None], other, held)
    out = fk.alloc(len(x), 1, full=True)
    fk.run(x, np.ones(1), np.zeros(1), signs, out, 1)
    for s, m in ((held, ~pick), (other, pick)):
        o = fk.alloc(len(x), 1, full=True)
        fk.run(x, np.ones(1), np.zeros(1), s, o, 1)
        np.testing.assert_array_equal(out["E"][m], o["E"][m])
        np.testing.assert_array_equal(out["zO"][m], o["zO"][m])


def test_errors_as_the_numpy_path():
    """An input where the loops cannot close, and a singular position, raise the same
    typed errors with the same message."""
    lk = Linkage(load_case("hibbeler-16-30"))
    fk = FusedKernel(lk)
    lo, hi = lk.feasible_ranges()[0]
    x = np.array([0.5 * (lo + hi), hi + 0.1 * (hi - lo)])
    with pytest.raises(AssemblyError) as e0:
        _numpy_kinematics(lk, x)
    with pytest.raises(AssemblyError) as e1:
        fk.kinematics(x)
    assert str(e1.value) == str(e0.value)
    # at the limit position (singular or nearly) Linkage leaves the singular treatment to
    # the numpy path: the front door gives the same outcome with the kernel on or off
    at = np.concatenate([np.linspace(lo, hi, 20000), [hi]])
    import os
    got = {}
    for mode in ("always", "0"):
        os.environ["XVAL_FUSED"] = mode
        try:
            got[mode] = _outcome(lambda: lk.kinematics(at))
        finally:
            del os.environ["XVAL_FUSED"]
    assert got["always"] == got["0"]


def _outcome(f):
    """The typed error and message ``f`` raises, or ``None``."""
    try:
        f()
    except (AssemblyError, SingularConfigurationError) as e:
        return type(e).__name__, str(e)
    return None


def test_newton_path_has_no_kernel():
    lk = Linkage(load_case(DATA / "stephenson-point-hints.toml"))
    assert lk.topo.plan is None and kernel_for(lk, True) is None


def test_compiled_once_per_structure():
    """Mechanisms of one structure share the compiled kernel (geometry is a parameter)."""
    a = FusedKernel(Linkage(load_case("seed-four-bar")))
    from tests.conftest import four_bar
    b = FusedKernel(Linkage(four_bar(0.5, 0.12, 0.35, 0.3)))
    assert a.fn is b.fn and not np.array_equal(a.pf, b.pf)


@pytest.mark.parametrize("case", ["seed-four-bar", "quick-return", "hibbeler-16-30"])
def test_streamed_sweep_is_the_sweep(case):
    """The CSV written block by block holds the in-memory sweep's table, and the events
    and summary are the same."""
    lk = Linkage(load_case(case))
    r0 = lk.sweep(1000)
    buf = io.StringIO()
    r1 = sweep_csv(lk, 1000, buf, block=97)
    buf.seek(0)
    f1 = pd.read_csv(buf)
    f0 = pd.read_csv(io.StringIO(r0.frame.to_csv(index=False)))
    assert list(f1.columns) == list(f0.columns) and len(f1) == len(f0)
    family = {"y": "x", "vy": "vx", "ay": "ax", "fy": "fx", "normal": "fx",
              "power_residual": "power"}
    rates = {"vx", "ax", "omega", "alpha", "fx", "moment", "torque", "force", "power", "v", "a"}
    kinds = {}
    for col in f0.columns:  # columns of one kind share a scale
        kind = col.rsplit(".", 1)[-1]
        kinds.setdefault(family.get(kind, kind), []).append(col)
    for kind, cols in kinds.items():
        ref = f0[cols].to_numpy()
        scale = np.max(np.abs(ref))
        if kind == "moment":  # a couple's scale: the largest joint force times the size
            scale = max(scale, np.max(np.abs(f0[kinds["fx"]].to_numpy())) * size_of(lk.topo))
        allowed = np.full(len(f0), AGREEMENT)
        if kind in rates and not complex_multiply_reproduced():  # see the test above
            allowed = np.maximum(allowed, RATE_ROUNDING * EPS
                                 * f0["jacobian_condition"].to_numpy())
        d = np.abs(f1[cols].to_numpy() - ref).max(axis=1)
        assert np.all(d <= allowed * scale), kind
    pd.testing.assert_frame_equal(r1.events, r0.events)
    assert r1.summary.lines() == r0.summary.lines()
    if r0.forces is not None:
        assert r1.forces.power_balance_error() == pytest.approx(
            r0.forces.power_balance_error(), abs=1e-12)


@pytest.mark.parametrize("case", ["seed-four-bar", "six-bar", "quick-return"])
def test_compact_kinematics_defers_the_same_numbers(case, monkeypatch):
    """``Linkage.kinematics`` through the kernel holds ``q, q', q''`` only; the forces
    pass does not need the rest; the deferred arrays, asked for, are the full pass's
    bit for bit (and the numpy path's to AGREEMENT)."""
    from analytic.kinematics import DEFERRED, CompactKinematics
    monkeypatch.setenv("XVAL_FUSED", "always")
    lk = Linkage(load_case(case))
    x = input_values(lk, POINTS)[0]
    kin = lk.kinematics(x)
    assert isinstance(kin, CompactKinematics)
    frc = lk.forces(kin) if lk.mech.has_mass else None
    assert not set(DEFERRED) & set(kin.__dict__)  # nothing deferred was computed
    full, frc_full = FusedKernel(lk).solve(x, on_singular="flag", forces=lk.mech.has_mass)
    for k in ("q", "qd", "qdd", "theta", "omega", "alpha", "E", "zO", "zv", "za", "jacobian",
              "determinant"):
        np.testing.assert_array_equal(getattr(kin, k), getattr(full, k), err_msg=k)
    assert set(DEFERRED) <= set(kin.__dict__)
    if frc is not None:
        np.testing.assert_array_equal(frc.effort, frc_full.effort)
    kin0, frc0 = _numpy_kinematics(lk, x)
    errs = _compare(lk, kin, frc, kin0, frc0)
    assert max(errs.values()) <= 1.0, errs
    with pytest.raises(AttributeError):
        kin.no_such_array  # noqa: B018 - the error, not a fill


@pytest.mark.parametrize("case", ["seed-four-bar", "six-bar"])
def test_forces_of_kinematics_is_one_pass(case, monkeypatch):
    """``lk.forces(lk.kinematics(x))``, the call a user makes: from its second call on,
    the kinematics pass writes the forces too (one kernel pass for both), the same
    forces as a forces-only pass; once a result's forces go unused, kinematics alone
    is one pass of kinematics again (issue 23, item 2)."""
    monkeypatch.setenv("XVAL_FUSED", "always")
    lk = Linkage(load_case(case))
    x = input_values(lk, POINTS)[0]
    fk = kernel_for(lk)
    levels = []
    run = fk.run

    def counted(*a, **k):
        levels.append(a[5] if len(a) > 5 else k.get("level", 3))
        return run(*a, **k)
    monkeypatch.setattr(fk, "run", counted)
    frc1 = lk.forces(lk.kinematics(x))  # first call: kinematics, then a forces pass
    assert levels == [2, 3]
    levels.clear()
    kin2 = lk.kinematics(x)
    frc2 = lk.forces(kin2)
    assert levels == [3]  # one pass for both
    for a, b in ((frc1.effort, frc2.effort), (frc1.power, frc2.power)):
        np.testing.assert_allclose(b, a, rtol=0, atol=AGREEMENT * np.max(np.abs(a)))
    for jn, F in frc1.joint_force.items():
        np.testing.assert_allclose(frc2.joint_force[jn], F, rtol=0,
                                   atol=AGREEMENT * np.max(np.abs(F)))
    levels.clear()
    lk.kinematics(x)  # forces written, never read: the guess stops
    lk.kinematics(x)
    assert levels == [3, 2]


def test_a_linkage_with_its_kernel_pickles(monkeypatch):
    """A Linkage whose fused kernel is loaded pickles (an engine run carries its Linkage
    back from the report's worker processes; the kernel holds a compiled module, which
    cannot be pickled): the copy has no kernel, finds it again on first use, and gives
    the same numbers as the original's kernel."""
    import pickle
    monkeypatch.setenv("XVAL_FUSED", "always")
    lk = Linkage(load_case("seed-four-bar"))
    x = input_values(lk, POINTS)[0]
    kin, frc = lk.solve(x)
    assert lk.fused_kernel is not None
    back = pickle.loads(pickle.dumps(lk))
    assert back.fused_kernel is None and back.mech == lk.mech
    kin2, frc2 = back.solve(x)
    np.testing.assert_allclose(kin2.alpha, kin.alpha, rtol=0,
                               atol=AGREEMENT * np.max(np.abs(kin.alpha)))
    np.testing.assert_allclose(frc2.effort, frc.effort, rtol=0,
                               atol=AGREEMENT * np.max(np.abs(frc.effort)))
