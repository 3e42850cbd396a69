"""Which path a call takes (analytic.fused.dispatch), one specialisation per kernel, and
the background compile."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from analytic import Linkage, fused, load_case
from analytic.kernels import cache
from analytic.kinematics import CompactKinematics, Kinematics
from tests.conftest import four_bar

#: a background compile of the four-bar's kernel takes 8-11 s alone; on a loaded 2-core
#: machine (other compiles, test workers) several times that
BACKGROUND_WAIT_S = 240.0


def test_forces_pass_reuses_the_kinematics_specialisation(monkeypatch):
    """``forces`` hands the kernel read-only rates (a slice of a broadcast view); the
    kernel is compiled (or loaded) for one set of argument types, whatever the front
    door passes, and COMPILE_LOG records that one."""
    monkeypatch.setenv("XVAL_FUSED", "always")
    lk = Linkage(load_case("seed-four-bar"))
    x = np.linspace(0.0, 2 * math.pi, 50)
    fk = fused.kernel_for(lk)
    frc = lk.forces(lk.kinematics(x))
    fk.solve(np.broadcast_to(0.5, (7,)), np.broadcast_to(3.0, (7,)), forces=True)
    fk.state(x[::2], level=3)
    fk.joint_positions(x.astype(np.float32))
    lk.forces(lk.kinematics(x, velocity=np.broadcast_to(15.0, x.shape)))
    assert len(fk.fn.overloads) == 1
    # one entry when this test brought the kernel in; none when an earlier test of this
    # worker did (the free motion's compiled loop takes the kernel from the same cache)
    assert len(fused.COMPILE_LOG.get(fk.name, [])) <= 1
    assert np.all(np.isfinite(frc.effort))


def test_loaded_kernel_serves_every_size(monkeypatch):
    """Once the kernel is in the process, a call of any size takes it (the numpy path
    only for a structure whose kernel is not here)."""
    monkeypatch.delenv("XVAL_FUSED", raising=False)
    lk = Linkage(load_case("seed-four-bar"))
    fused.kernel_for(lk).state(np.zeros(2), level=3)  # compiled or loaded here
    for n in (1, 36, 3600):
        assert isinstance(lk.kinematics(np.linspace(0.0, 1.0, n)), CompactKinematics), n
    # another linkage of the same structure shares it
    other = Linkage(four_bar(0.5, 0.12, 0.35, 0.3))
    assert isinstance(other.kinematics(np.zeros(3)), CompactKinematics)


def test_unloaded_kernel_waits_until_loading_pays(monkeypatch, tmp_path):
    """A structure whose kernel is neither here nor cached runs on numpy (and, with
    background compiles off, compiles nothing); one cached on disk is loaded once the
    numpy path's estimated cost reaches the load's."""
    monkeypatch.delenv("XVAL_FUSED", raising=False)
    monkeypatch.setenv("XVAL_KERNEL_CACHE", str(tmp_path))
    monkeypatch.setenv("XVAL_BACKGROUND_COMPILE", "0")
    monkeypatch.setattr(fused, "_MODULES", {})
    monkeypatch.setattr(cache, "_MODULES", fused._MODULES)  # the same dict, emptied
    monkeypatch.setattr(fused, "_SPENT", {})
    lk = Linkage(four_bar(0.5, 0.12, 0.35, 0.3))
    for _ in range(3):
        assert fused.dispatch(lk, 3600) is None
    assert not list(tmp_path.glob("*.py"))  # nothing compiled, nothing written
    fk = fused.kernel_for(lk)
    # as if compiled on disk: the loading rule (numba imported by now)
    monkeypatch.setattr(fused, "on_disk", lambda name: True)
    calls = math.ceil(fused.LOAD_IMPORTED_S / (fused.NUMPY_CALL_S + fused.NUMPY_POINT_S * 36))
    got = [fused.dispatch(lk, 36) for _ in range(calls + 1)]
    assert got[0] is None and got[-1] is fk
    assert fused.dispatch(lk, 10 ** 6) is fk  # a large call loads at once


@pytest.mark.slow
def test_background_compile_marks_the_kernel_ready(monkeypatch, tmp_path):
    """The first call of an uncached structure answers on numpy and leaves a background
    process compiling the kernel into the cache, which marks it ready."""
    monkeypatch.delenv("XVAL_FUSED", raising=False)
    monkeypatch.setenv("XVAL_KERNEL_CACHE", str(tmp_path / "k"))
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "n"))
    monkeypatch.delenv("XVAL_BACKGROUND_COMPILE", raising=False)
    monkeypatch.setattr(fused, "_MODULES", {})
    monkeypatch.setattr(cache, "_MODULES", fused._MODULES)  # the same dict, emptied
    from analytic.kernels import background
    monkeypatch.setattr(background, "_STARTED", {})
    lk = Linkage(four_bar(0.45, 0.1, 0.35, 0.3))
    kin = lk.kinematics(np.linspace(0.0, 1.0, 10))
    assert type(kin) is Kinematics  # the numpy path answered
    name = fused.kernel_for(lk).name
    t0 = time.monotonic()
    while not fused.on_disk(name) and time.monotonic() - t0 < BACKGROUND_WAIT_S:
        time.sleep(0.5)
    assert fused.on_disk(name)
    assert str(tmp_path / "n") in (tmp_path / "k" / f"{name}.ready").read_text()
    assert not list((tmp_path / "k").glob("*.compiling"))


@pytest.mark.parametrize("case", ["seed-four-bar", "six-bar", "seed-slider-crank"])
def test_solve_is_one_pass(case, monkeypatch):
    """``Linkage.solve`` (kinematics, forces and joint points) runs the kernel once and
    gives the numbers of ``forces(kinematics(x))`` and the full pass's joint points,
    bit for bit (the same operations in the same kernel)."""
    monkeypatch.setenv("XVAL_FUSED", "always")
    lk = Linkage(load_case(case))
    x = lk.mech.driver.value + np.linspace(0.0, 0.5, 64)
    fk = fused.kernel_for(lk)
    kin0 = lk.kinematics(x)
    frc0 = lk.forces(kin0)
    jp0 = kin0.joint_point
    passes = []
    run = fk.run
    monkeypatch.setattr(fk, "run", lambda *a, **k: passes.append(1) or run(*a, **k))
    kin, frc = lk.solve(x, joints=True)
    assert lk.forces(kin) is frc
    assert len(passes) == 1
    for k in ("q", "qd", "qdd"):
        np.testing.assert_array_equal(getattr(kin, k), getattr(kin0, k))
    np.testing.assert_array_equal(frc.effort, frc0.effort)
    for j, f in frc0.joint_force.items():
        np.testing.assert_array_equal(frc.joint_force[j], f)
    for j, p in jp0.items():
        np.testing.assert_array_equal(kin.joint_point[j], p)
    assert len(passes) == 1


def test_solve_on_the_numpy_path(monkeypatch):
    """Without the kernel, ``solve`` is ``forces(kinematics(x))``."""
    monkeypatch.setenv("XVAL_FUSED", "0")
    lk = Linkage(load_case("seed-four-bar"))
    x = np.linspace(0.0, 1.0, 9)
    kin, frc = lk.solve(x, joints=True)
    np.testing.assert_array_equal(frc.effort, lk.forces(lk.kinematics(x)).effort)
    assert set(kin.joint_point) == set(range(len(lk.mech.joints)))


@pytest.mark.parametrize("mode", ["always", "0"])
def test_solve_without_masses_is_the_typed_error(mode, monkeypatch):
    """``solve`` of a description without masses raises MissingMassError on either
    path (no traceback from the kernel's wrapping)."""
    from analytic import MissingMassError
    monkeypatch.setenv("XVAL_FUSED", mode)
    lk = Linkage(four_bar(0.4, 0.1, 0.3, 0.25, masses=None))
    with pytest.raises(MissingMassError):
        lk.solve(np.linspace(0.0, 1.0, 5))
    assert lk.kinematics(np.linspace(0.0, 1.0, 5)).n == 5


def test_a_very_large_structure_compiles_nothing(monkeypatch, tmp_path):
    """IFToMM A02 at N = 8 (4210 lines of kernel source; N = 40 makes about 58,000, whose
    background compile held 9.7 GB and 17 min of CPU): no background process is started
    and no kernel compiled for calls of any size; the numpy path answers.
    ``XVAL_FUSED=always`` still asks for it."""
    import tomllib

    from analytic.free_motion.iftomm import n_four_bar_toml
    from analytic.kernels import background
    from analytic.toml_io import mechanism_from_dict
    monkeypatch.delenv("XVAL_FUSED", raising=False)
    monkeypatch.delenv("XVAL_BACKGROUND_COMPILE", raising=False)
    monkeypatch.setenv("XVAL_KERNEL_CACHE", str(tmp_path))
    monkeypatch.setattr(fused, "_MODULES", {})

    def refuse(fk):
        raise AssertionError(f"a background compile of {fk.name} was started")
    monkeypatch.setattr(background, "start", refuse)
    lk = Linkage(mechanism_from_dict(tomllib.loads(n_four_bar_toml(8)), "A02 N=8"))
    fk = fused.kernel_for(lk)
    assert fk.too_large and fk.source.source.count("\n") > fused.MAX_KERNEL_LINES
    for n in (3, 1 << 20):
        assert fused.dispatch(lk, n) is None
    assert type(lk.kinematics(np.linspace(1.5, 1.6, 5))) is Kinematics
    assert fk._fn is None  # never compiled nor loaded
    monkeypatch.setenv("XVAL_FUSED", "always")
    assert fused.dispatch(lk, 3) is fk
