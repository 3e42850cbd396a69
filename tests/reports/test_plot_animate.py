"""``xval plot`` and ``xval animate``: what is drawn is the analytic solution (checked
against closed forms and finite differences computed here), engine poses are drawn where
the engine put them, outputs and errors are one line.

Expected positions come from the slider-crank's and the four-bar's geometry by hand
(law of cosines / Pythagoras), never from the code under test.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from PIL import Image

from analytic import Linkage, load_case
from reports.cli import plot as plot_cmd
from reports.cli.xval import main
from reports.figures import animation, poses

from .cli_run import run

#: Positions drawn from the analytic solution agree with a closed form to round-off.
POSE_TOL = 1e-9
#: MuJoCo's poses at the recommended settings agree with the analytic ones to ~1e-8 of
#: the size (README, Engines); a displacement of 0.05 rad is 1e5 times that.
ENGINE_POSE_TOL = 1e-5
#: The finite difference of the plotted angle over 1 deg steps: error ~ h^2/6 * omega'''.
FD_REL = 2e-3


def slider_crank_pose(theta: float) -> dict[str, np.ndarray]:
    """seed-slider-crank (crank 0.1 m, rod 0.2 m, line through the crank pivot along
    x) by hand: joint positions at crank angle ``theta``."""
    r, l_ = 0.1, 0.2
    B = np.array([r * math.cos(theta), r * math.sin(theta)])
    C = np.array([B[0] + math.sqrt(l_ ** 2 - B[1] ** 2), 0.0])
    return {"A": np.zeros(2), "B": B, "C": C, "slide": C}


# ============================================================================ plot
def test_plot_png_shows_the_analytic_cycle(tmp_path):
    out = tmp_path / "x.png"
    code, text = run("plot", "seed-four-bar", "--out", str(out))
    assert code == 0 and "wrote" in text and "units: lengths m" in text
    assert Image.open(out).format == "PNG"
    figs, err, runs, _ = plot_cmd.case_figures(load_case("seed-four-bar"),
                                               ["angle", "omega"], [], {})
    assert err is None and not runs
    ang, om = figs
    by = {c.label: c for c in ang.curves}
    assert np.ptp(ang.curves[0].x) == pytest.approx(359.0, abs=1.01)  # a full turn, deg
    # omega = d(angle)/dt with dt = d(input)/15 rad/s: central differences of the
    # plotted angle against the plotted omega
    # (at the whole degrees: the line also holds points between them)
    for c in om.curves:
        x, th = by[c.label].x, by[c.label].y
        k = np.abs(x - np.round(x)) < 1e-9
        x, first = np.unique(np.round(x[k]), return_index=True)
        th, w = th[k][first], c.y[k][first]
        assert len(x) >= 300
        dth = (th[2:] - th[:-2]) / (x[2:] - x[:-2]) * 15.0  # deg/deg * rad/s
        np.testing.assert_allclose(dth, w[1:-1], atol=FD_REL * np.abs(w).max())
    crank = next(c for c in om.curves if c.label == "crank")
    assert np.all(crank.y == 15.0)


def test_plot_units_convert_the_same_figures():
    mech = load_case("seed-four-bar")
    (om,), _, _, _ = plot_cmd.case_figures(mech, ["omega"], [], {})
    from reports.figures.display_units import DisplayUnits, convert_figure
    c = convert_figure(om, DisplayUnits.parse("mm,rad,rpm"))
    assert c.ylabel == "omega (rpm)" and c.xlabel == "input angle (rad)"
    np.testing.assert_allclose(c.curves[1].y, om.curves[1].y * 60 / (2 * math.pi), rtol=1e-15)
    np.testing.assert_allclose(c.curves[1].x, np.radians(om.curves[1].x), rtol=1e-15)


@pytest.mark.parametrize("ext,magic", [(".svg", b"<?xml"), (".pdf", b"%PDF")])
def test_plot_format_by_extension(tmp_path, ext, magic):
    out = tmp_path / f"x{ext}"
    assert run("plot", "seed-slider-crank", "--what", "slider,torque,transmission",
               "--out", str(out))[0] == 0
    assert out.read_bytes()[:5].startswith(magic[:4])


def test_plot_bad_inputs_are_one_line(tmp_path, capsys, monkeypatch):
    assert main(["plot", "seed-four-bar", "--out", str(tmp_path / "x.jpg")]) == 2
    assert "must end in .png, .svg, .pdf" in capsys.readouterr().err
    assert main(["plot", "seed-four-bar", "--what", "speed"]) == 2
    assert "'speed' is not a quantity" in capsys.readouterr().err
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("sys.platform", "linux")
    assert main(["plot", "seed-four-bar", "--show"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no display" in err


def test_plot_with_engine_has_markers_and_errors(tmp_path):
    pytest.importorskip("mujoco")
    out = tmp_path / "e.png"
    code, text = run("plot", "seed-four-bar", "--engine", "mujoco", "--what", "alpha",
                     "--out", str(out))
    assert code == 0 and "with mujoco" in text
    figs, err, runs, _ = plot_cmd.case_figures(load_case("seed-four-bar"), ["alpha"],
                                               ["mujoco"], _settings("mujoco"))
    (alpha,) = figs
    rocker = next(c for c in alpha.curves if c.label == "rocker")
    x, y, judged = rocker.markers["mujoco"]
    # each marker sits on the analytic line at its input (the verdict's reference)
    line_at = np.interp(x, rocker.x, rocker.y)
    assert np.max(np.abs(y - line_at)[judged]) < 1e-3 * np.abs(rocker.y).max()
    assert err is not None and err.panels["mujoco"]["worst"][1] < err.tolerance


def _settings(engine):
    from reports.comparison.runs import settings_for
    return settings_for([engine])


# ============================================================================ animate
def test_animate_gif_frames_and_first_pose(tmp_path):
    out = tmp_path / "x.gif"
    code, text = run("animate", "seed-slider-crank", "--out", str(out))
    assert code == 0 and "72 frames" in text
    gif = Image.open(out)
    assert gif.n_frames >= 36
    # the frames' data: frame 0 is the assembled reference pose (crank at 30 deg)
    mech = load_case("seed-slider-crank")
    fr = poses.analytic_frames(Linkage(mech))
    expect = slider_crank_pose(math.radians(30.0))
    got = animation.joint_positions(mech, fr.analytic, 0)
    for j, p in expect.items():
        np.testing.assert_allclose(got[j], p, atol=POSE_TOL)
    # every frame is on the closed form at its own input
    for i in range(0, fr.n, 7):
        for j, p in slider_crank_pose(fr.values[i]).items():
            np.testing.assert_allclose(animation.joint_positions(mech, fr.analytic, i)[j], p,
                                       atol=POSE_TOL)
    # the pixels: the joint C's ring (black edge) where C is in frame 0 of the file
    an = animation.build_animation(fr, f"{mech.name}: analytic")
    an.fig.canvas.draw()
    px = an.ax.transData.transform(expect["C"])
    H = an.fig.canvas.get_width_height()[1]
    gif.seek(0)
    f0 = np.asarray(gif.convert("RGB"))
    assert f0.shape[0] == H
    assert _ring_is_dark(f0, px)
    gif.seek(36)  # half a turn later C is elsewhere: the check can fail
    assert not _ring_is_dark(np.asarray(gif.convert("RGB")), px)


def _ring_is_dark(img: np.ndarray, px) -> bool:
    """A joint marker (white disc, black edge ~3.3 px radius at 80 dpi) at display point
    ``px``: dark pixels on the ring in at least 3 of 4 directions, a light centre."""
    H = img.shape[0]
    cx, cy = px[0], H - px[1]
    hits = 0
    for ang in (0, 90, 180, 270):
        dark = False
        for r in np.arange(2.0, 5.0, 0.5):
            x = int(round(cx + r * math.cos(math.radians(ang))))
            y = int(round(cy - r * math.sin(math.radians(ang))))
            dark |= bool(np.all(img[y, x] < 90))
        hits += dark
    centre = img[int(round(cy)), int(round(cx))]
    return hits >= 3 and bool(np.all(centre > 150))


def test_animate_follows_the_prescribed_motion():
    """hibbeler-16-30's collar starts at 0 m at 2 m/s and speeds up at 1 m/s^2: the
    frames are s = 2 t + t^2 / 2 (by hand), the box shows the rate 2 + t reached there
    (not the nominal 2 m/s), and the motion stops short of the limit position, as the
    engines' runs do."""
    lk = Linkage(load_case("hibbeler-16-30"))
    fr = poses.analytic_frames(lk, 72)
    t = fr.times
    assert t[0] == 0.0 and np.all(np.diff(t) > 0) and fr.n == 72
    np.testing.assert_allclose(fr.values, 2.0 * t + 0.5 * t * t, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(fr.rates, 2.0 + t, rtol=1e-12)
    lo, hi = lk.feasible_ranges()[0]
    assert fr.values.max() < hi
    text = animation.info_text(fr, 60, fr.convention)
    assert f"{2.0 + t[60]:.4g} m/s" in text and f"t = {t[60]:.4f} s" in text, text
    assert f"{2.0 * t[60] + 0.5 * t[60] ** 2:.6g} m" in text, text
    # a crank that accelerates: hibbeler-16-121 from 90 deg at 3 rad/s, 2 rad/s^2
    lk = Linkage(load_case("hibbeler-16-121"))
    fr = poses.analytic_frames(lk, 36)
    w0, a = 3.0, 2.0
    T = (-w0 + math.sqrt(w0 * w0 + 2 * a * 2 * math.pi)) / a  # one turn, by hand
    np.testing.assert_allclose(fr.times[-1], T * 35 / 36, rtol=1e-12)
    np.testing.assert_allclose(fr.rates, w0 + a * fr.times, rtol=1e-12)


@pytest.mark.parametrize("engine", ["mujoco", "exudyn"])
def test_animate_engine_pose_at_every_frame(engine, tmp_path):
    """The engine is sampled at the frames' times: a pose at every frame (mujoco once
    had none at 58 of 72 frames of hibbeler-16-30; Exudyn, in absolute coordinates, none
    at all), each on the analytic pose to the engine's accuracy."""
    pytest.importorskip(engine)
    from sim_models import compile_linkage
    mech = load_case("hibbeler-16-30")
    tree = compile_linkage(mech)
    fr = poses.analytic_frames(tree.linkage, 36, tree=tree)
    r = poses.engine_run(mech, tree, engine, 36, times=fr.times)
    assert r.ok, r.reason
    p = poses.engine_poses(r, tree, fr.values, False, times=fr.times)
    assert np.all(np.isfinite(p.theta)) and np.all(np.isfinite(p.origin))
    for i in (0, 17, 35):
        a = animation.joint_positions(mech, fr.analytic, i)
        e = animation.joint_positions(mech, p, i)
        for j in a:
            assert np.linalg.norm(a[j] - e[j]) < ENGINE_POSE_TOL, (i, j)
    code, text = run("animate", "hibbeler-16-30", "--engine", engine, "--frames", "36",
                     "--out", str(tmp_path / "a.gif"))
    assert code == 0 and "no pose" not in text and "not drawn" not in text, text


def test_engine_pose_displaced_is_drawn_displaced():
    pytest.importorskip("mujoco")
    from sim_models import compile_linkage
    mech = load_case("seed-four-bar")
    tree = compile_linkage(mech)
    fr = poses.analytic_frames(tree.linkage, 36)
    r = poses.engine_run(mech, tree, "mujoco", 36)
    assert r.ok
    honest = poses.engine_poses(r, tree, fr.values, True)
    assert np.all(np.isfinite(honest.theta))
    # the rocker's tree coordinate turned by delta at every sample, on purpose
    delta = 0.05
    k = next(i for i, tj in enumerate(tree.joints) if tj.name == "O4")
    q = r.q.copy()
    q[:, k] += tree.joints[k].sigma * delta
    moved = poses.engine_poses(dataclasses.replace(r, q=q), tree, fr.values, True)
    O4 = np.array([0.4, 0.0])
    fr.engines[:] = [honest, moved]
    an = animation.build_animation(fr)
    for i in (0, 11, 23):
        an.draw(i)
        lines = [a for a in an.dynamic if getattr(a, "get_linestyle", lambda: "")() == "--"]
        # body lines of each engine, in body order: crank, coupler, rocker
        h_rocker = np.column_stack(lines[2].get_data())
        m_rocker = np.column_stack(lines[5].get_data())
        a_B = animation.joint_positions(mech, fr.analytic, i)["B"]
        # honest engine: on the analytic rocker
        assert np.min(np.linalg.norm(h_rocker - a_B, axis=1)) < ENGINE_POSE_TOL
        # displaced engine: the analytic B turned by delta about O4, by hand
        c, s = math.cos(delta), math.sin(delta)
        b = a_B - O4
        want = O4 + np.array([c * b[0] - s * b[1], s * b[0] + c * b[1]])
        assert np.min(np.linalg.norm(m_rocker - want, axis=1)) < ENGINE_POSE_TOL
        assert np.min(np.linalg.norm(m_rocker - a_B, axis=1)) > 0.5 * delta * 0.1
    import matplotlib.pyplot as plt
    plt.close(an.fig)


@pytest.mark.slow
def test_animate_html_is_self_contained(tmp_path):
    out = tmp_path / "x.html"
    assert run("animate", "seed-four-bar", "--out", str(out), "--frames", "36",
               "--forces")[0] == 0
    html = out.read_text()
    assert "data:image/png;base64" in html and "<script" in html
    assert "src=\"http" not in html and "href=\"http" not in html


def test_animate_mp4_or_a_clear_line(tmp_path, capsys):
    from matplotlib import animation
    out = tmp_path / "x.mp4"
    code = main(["animate", "seed-four-bar", "--out", str(out), "--frames", "36"])
    if animation.writers.is_available("ffmpeg"):
        assert code == 0 and out.stat().st_size > 0
    else:
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1 and "needs ffmpeg" in err


def test_animate_forces_need_masses(tmp_path, capsys):
    assert main(["animate", "hibbeler-16-30", "--forces", "--out",
                 str(tmp_path / "x.gif")]) == 2
    assert "no masses" in capsys.readouterr().err


def test_plot_show_with_an_unreachable_display_writes_then_says_so(tmp_path, capsys,
                                                                   monkeypatch):
    monkeypatch.setenv("DISPLAY", ":97")  # no X server there
    monkeypatch.setattr("sys.platform", "linux")
    out = tmp_path / "s.png"
    assert main(["plot", "seed-four-bar", "--what", "angle", "--show", "--out",
                 str(out)]) == 2
    err = capsys.readouterr().err
    assert out.is_file() and err.count("\n") == 1 and "written to" in err
