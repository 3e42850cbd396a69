"""``xval plot`` and ``xval animate`` of free motion: the files are written, every drawn
point is the trajectory's sample at its time (the figure's line data against
``simulate(...).at(times)``), the samples agree with an independent integration of the
pendulum written here, the turning points sit at the closed-form half period, and
options that do not apply are one line, status 2, with nothing written.

Independent sources: IFToMM A01 (a 1 kg point mass at 1 m, released from the horizontal)
obeys ``(I + m l^2) th'' = -m g l cos th``, integrated here by SciPy's Radau (not the
code under test's DOP853 nor its equation of motion), and its period is
``4 K(sin^2(a/2)) sqrt((I + m l^2) / (m g l))`` with amplitude a = 90 deg.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from PIL import Image
from scipy.integrate import solve_ivp
from scipy.special import ellipk

from analytic import load_case
from analytic.cases import case_path
from analytic.free_motion import simulate
from reports.figures import free_plots
from reports.figures.animation import body_outlines, world
from reports.figures.poses import free_frames

from .cli_run import run

#: The pendulum's constants (analytic/cases/free/iftomm-a01-pendulum.toml).
M, L, G, I_G = 1.0, 1.0, 9.81, 1e-12
#: The plotted line is the trajectory's sample: the same computation, so equal to round-off.
SAME = 1e-12
#: The code's DOP853 at rtol 1e-13 against the test's Radau at rtol 1e-12 over a few
#: seconds: both ~1e-10 rad; 1e-8 rad leaves a margin and still catches any sample drawn
#: at another time (0.025 s off moves the angle by ~0.1 rad).
INDEPENDENT = 1e-8
#: Turning points are located by root-finding to ~1e-13 s on a trajectory good to
#: ~1e-11; the closed-form half period is exact.
TURN_TIME = 1e-8
DURATION, SAMPLES = 2.5, 101


def pendulum_angle(t: np.ndarray) -> np.ndarray:
    """The A01 angle (rad, from +x, counter-clockwise) at times ``t`` by Radau."""
    J = I_G + M * L * L

    def f(_, y):
        return [y[1], -M * G * L * math.cos(y[0]) / J]
    sol = solve_ivp(f, (0.0, float(t[-1])), [0.0, 0.0], method="Radau", rtol=1e-12,
                    atol=1e-14, t_eval=t)
    return sol.y[0]


def half_period() -> float:
    return 2.0 * ellipk(math.sin(math.pi / 4) ** 2) * math.sqrt((I_G + M * L * L) / (M * G * L))


@pytest.fixture(scope="module")
def traj():
    return simulate(load_case("iftomm-a01-pendulum"), DURATION)


@pytest.fixture
def drawn(monkeypatch):
    """The figures ``free_plots.draw_free`` returns, kept for inspection."""
    figs = []
    real = free_plots.draw_free

    def keep(*a, **k):
        figs.append(real(*a, **k))
        return figs[-1]
    monkeypatch.setattr(free_plots, "draw_free", keep)
    return figs


def lines_of(ax, label: str):
    (ln,) = [ln for ln in ax.get_lines() if ln.get_label() == label]
    return np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float)


# ============================================================================ plot
def test_plot_draws_the_trajectory_samples(tmp_path, traj, drawn):
    out = tmp_path / "a01.png"
    code, text = run("plot", "iftomm-a01-pendulum", "--duration", str(DURATION),
                     "--samples", str(SAMPLES), "--out", str(out))
    assert code == 0 and f"wrote {out} (free motion" in text, text
    assert Image.open(out).format == "PNG"
    (fig,) = drawn
    ax_coord, ax_energy, ax_res, ax_events = fig.axes
    t = np.linspace(0.0, DURATION, SAMPLES)
    smp = traj.at(t, forces=False)
    x, y = lines_of(ax_coord, "O")
    assert np.array_equal(x, t)
    assert np.max(np.abs(y - np.degrees(smp.x[:, 0]))) <= SAME * 180
    assert np.max(np.abs(np.radians(y) - pendulum_angle(t))) <= INDEPENDENT
    _, ke = lines_of(ax_energy, "kinetic T")
    _, pe = lines_of(ax_energy, "potential V (gravity, springs)")
    _, tot = lines_of(ax_energy, "total T + V")
    assert np.array_equal(ke, smp.kinetic) and np.array_equal(pe, smp.potential)
    assert np.array_equal(tot, smp.kinetic + smp.potential)
    # kinetic energy by hand: (I + m l^2) th'^2 / 2 with th' the drawn line's own rate
    assert np.allclose(ke, 0.5 * (I_G + M * L * L) * smp.xd[:, 0] ** 2, rtol=0, atol=1e-12)
    (_, res), = [lines_of(ax_res, ln.get_label()) for ln in ax_res.get_lines()
                 if ln.get_label().startswith("r = ")]
    assert np.array_equal(res, smp.energy_residual) and np.max(np.abs(res)) < 1e-9
    # events: two turning points, at the closed-form half periods, as lines and strip
    turns = [e.t for e in traj.events if e.kind == "turn"]
    assert np.allclose(turns, [half_period(), 2 * half_period()], rtol=0, atol=TURN_TIME)
    vlines = sorted(ln.get_xdata()[0] for ln in ax_coord.get_lines()
                    if ln.get_linestyle() == "--")  # the event lines (axvline)
    assert np.allclose(vlines, turns, rtol=0, atol=1e-12)
    strip = np.concatenate([ln.get_xdata() for ln in ax_events.get_lines()])
    assert np.allclose(np.sort(strip), turns, rtol=0, atol=1e-12)
    assert "turning point (motion reverses) (2)" in [tl.get_text() for tl in
                                                     ax_events.get_yticklabels()]


def test_plot_units_and_quantities(tmp_path, traj, drawn):
    out = tmp_path / "a01.svg"
    code, _ = run("plot", "iftomm-a01-pendulum", "--duration", str(DURATION), "--samples",
                  "11", "--units", "rad,rpm", "--what", "rate,coordinate", "--out", str(out))
    assert code == 0 and out.read_bytes().lstrip().startswith(b"<?xml")
    (fig,) = drawn
    ax_rate, ax_coord, _ = fig.axes
    smp = traj.at(np.linspace(0.0, DURATION, 11), forces=False)
    assert ax_rate.get_ylabel() == "joint angular rate (rpm)"
    assert np.allclose(lines_of(ax_rate, "O")[1], smp.xd[:, 0] * 60 / (2 * math.pi),
                       rtol=SAME, atol=0)
    assert ax_coord.get_ylabel() == "joint angle (rad)"
    assert np.array_equal(lines_of(ax_coord, "O")[1], smp.x[:, 0])


def test_plot_slider_and_motor(tmp_path, drawn):
    """A prismatic joint gets its own panel in the length unit; a motor its effort."""
    f = tmp_path / "sc.toml"
    f.write_text(case_path("seed-slider-crank").read_text()
                 + '\n[motion]\njoint = "A"\nvalue = 30.0\nrate = 20.0\nduration = 0.05\n'
                 'samples = 21\n\n[[motors]]\njoint = "A"\ntable = [[0.0, 0.0], [0.05, 2.0]]\n')
    code, text = run("plot", str(f), "--units", "mm", "--what", "coordinate,torque",
                     "--out", str(tmp_path / "sc.png"))
    assert code == 0, text
    (fig,) = drawn
    ax_ang, ax_s, ax_m, _ = fig.axes
    assert ax_s.get_ylabel() == "slider displacement (mm)"
    traj = simulate(load_case(str(f)))
    t = np.linspace(0.0, 0.05, 21)
    smp = traj.at(t, forces=False)
    k = smp.joints.index("slide")
    assert np.allclose(lines_of(ax_s, "slide")[1], 1000 * smp.x[:, k], rtol=SAME, atol=0)
    # the slider by hand from the crank angle drawn (crank 0.1 m, rod 0.2 m, no offset)
    th = np.radians(lines_of(ax_ang, "A")[1])
    s = 0.1 * np.cos(th) + np.sqrt(0.2 ** 2 - (0.1 * np.sin(th)) ** 2)
    assert np.allclose(lines_of(ax_s, "slide")[1], 1000 * s, rtol=0, atol=1e-9)
    assert np.allclose(lines_of(ax_m, "motor at A")[1], np.interp(t, [0, 0.05], [0, 2]),
                       rtol=0, atol=1e-15)


def test_default_name_is_safe(tmp_path, monkeypatch):
    f = tmp_path / "in.toml"
    f.write_text(case_path("iftomm-a01-pendulum").read_text().replace(
        'name = "iftomm-a01-pendulum"', 'name = "../../evil name"'))
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    code, text = run("plot", str(f), "--duration", "0.3", "--samples", "5")
    assert code == 0, text
    assert [p.name for p in work.iterdir()] == ["evil_name-free-plot.png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.toml", "work"]


def test_many_events_only_in_the_strip(tmp_path, drawn, monkeypatch):
    monkeypatch.setattr(free_plots, "MAX_EVENT_LINES", 1)
    code, text = run("plot", "iftomm-a01-pendulum", "--duration", str(DURATION),
                     "--samples", "6", "--out", str(tmp_path / "x.png"))
    assert code == 0
    assert "note: 2 events: marked in the event strip only" in text
    # 6 samples 0.5 s apart cannot follow swings 1.18 s apart
    assert "they cannot follow each swing" in text
    (fig,) = drawn
    assert all(ln.get_linestyle() != "--" for ln in fig.axes[0].get_lines())


def test_driven_plots_the_prescribed_cycle(tmp_path):
    code, text = run("plot", "iftomm-a01-pendulum", "--driven", "--what", "angle",
                     "--out", str(tmp_path / "d.png"))
    assert code == 0 and "free motion" not in text and "1 panels" in text, text


# ============================================================================ animate
def test_animate_free_frames_are_the_trajectory(tmp_path, traj):
    out = tmp_path / "a01.gif"
    code, text = run("animate", "iftomm-a01-pendulum", "--duration", str(DURATION),
                     "--frames", "36", "--out", str(out))
    assert code == 0 and "free motion, 36 frames" in text, text
    assert Image.open(out).n_frames == 36
    fr = free_frames(traj, 36)
    t = np.linspace(0.0, DURATION, 36)
    assert np.array_equal(fr.times, t)
    th = pendulum_angle(t)
    b = [bd.name for bd in fr.mech.bodies].index("link")
    for i in range(fr.n):
        p1 = world(fr.analytic.theta[i, b], fr.analytic.origin[i, b], np.array([1.0, 0.0]))
        assert np.allclose(p1, [math.cos(th[i]), math.sin(th[i])], rtol=0, atol=INDEPENDENT)
    assert np.allclose(body_outlines(fr.mech, fr.analytic, 0)["link"], [[0, 0], [1, 0]],
                       atol=1e-15)  # the release pose
    from reports.figures.animation import info_text
    assert info_text(fr, 35, None).endswith(f"t = {DURATION:g} s of {DURATION:g} s   "
                                            "frame 36/36")


@pytest.mark.slow
def test_animate_free_html_with_forces(tmp_path):
    out = tmp_path / "a.html"
    code, text = run("animate", "iftomm-a01-pendulum", "--duration", "0.5", "--forces",
                     "--out", str(out))
    assert code == 0 and "free motion" in text, text
    html = out.read_text()
    assert "<script" in html and "font-awesome" not in html


def test_animate_forces_are_the_pin_reaction(traj):
    """The arrows' forces: the ground's pin force on the link, m (a_G - g), by hand from
    the independent angle, its rate and th'' = -g cos(th) / l."""
    fr = free_frames(traj, 36, forces=True)
    t = fr.times
    J = I_G + M * L * L
    sol = solve_ivp(lambda _, y: [y[1], -M * G * L * math.cos(y[0]) / J], (0.0, t[-1]),
                    [0.0, 0.0], method="Radau", rtol=1e-12, atol=1e-14, t_eval=t)
    th, w = sol.y
    a = -M * G * L * np.cos(th) / J
    aG = L * np.stack([-w ** 2 * np.cos(th) - a * np.sin(th),
                       -w ** 2 * np.sin(th) + a * np.cos(th)], axis=1)
    F = M * (aG - np.array([0.0, -G]))
    assert np.max(np.abs(fr.forces["O"] - F)) <= 1e-6  # N, of ~30 N at the bottom


def test_show_without_display_writes_then_says_so(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("sys.platform", "linux")
    out = tmp_path / "s.png"
    code, _ = run("plot", "iftomm-a01-pendulum", "--duration", "0.3", "--samples", "4",
                  "--show", "--out", str(out))
    err = capsys.readouterr().err
    assert code == 2 and out.is_file() and err.count("\n") == 1 and "no display" in err


# ============================================================================ bad options
BAD = [
    (["plot", "iftomm-a01-pendulum", "--engine", "mujoco"],
     r"option --engine: .*free motion.*--driven"),
    (["plot", "iftomm-a01-pendulum", "--revolutions", "3"], r"option --revolutions: .*--driven"),
    (["plot", "iftomm-a01-pendulum", "--what", "angle"],
     r"option --what: 'angle' is not a quantity of a free-motion plot"),
    (["plot", "iftomm-a01-pendulum", "--samples", "1"],
     r"argument --samples: 1 is out of range: the accepted range is 2 to 1000000"),
    (["plot", "iftomm-a01-pendulum", "--duration", "0"],
     r"argument --duration: 0 is out of range"),
    (["plot", "iftomm-a01-pendulum", "--free", "--driven"],
     r"argument --driven: not allowed with argument --free"),
    # a built-in case without [motion] is released as xval simulate releases it (issue 30);
    # one that cannot be is refused with simulate's line
    (["plot", "hibbeler-16-30", "--free"], r"cannot be released under gravity"),
    (["plot", "seed-four-bar", "--duration", "2"], r"option --duration is for free motion"),
    (["plot", "seed-four-bar", "--samples", "5000"],
     r"argument --samples: 5000 is out of range: .*2 to 3600"),
    (["animate", "iftomm-a01-pendulum", "--engine", "mujoco", "--out", "{d}/a.gif"],
     r"option --engine: .*free motion.*--driven"),
    (["animate", "hibbeler-16-30", "--free", "--out", "{d}/a.gif"],
     r"cannot be released under gravity"),
    (["animate", "seed-four-bar", "--duration", "2", "--out", "{d}/a.gif"],
     r"option --duration is for free motion"),
    (["animate", "iftomm-a01-pendulum", "--duration", "nan", "--out", "{d}/a.gif"],
     r"argument --duration: nan is not a finite number"),
]


@pytest.mark.parametrize("argv, message", BAD, ids=[" ".join(b[0][:3]) for b in BAD])
def test_bad_options_one_line(tmp_path, monkeypatch, capsys, argv, message):
    import re
    monkeypatch.chdir(tmp_path)
    code, out = run(*[a.replace("{d}", str(tmp_path)) for a in argv])
    err = capsys.readouterr().err
    assert code == 2, (out, err)
    assert err.startswith("xval: error: ") and err.count("\n") == 1, err
    assert re.search(message, err), err
    assert list(tmp_path.iterdir()) == []  # nothing written
