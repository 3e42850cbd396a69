"""Source of the fused kernel of one mechanism *structure*.

The generated function evaluates, for each input value in turn and without array
temporaries, the same operations as the numpy path: the dyad plan of
:class:`analytic.positions.ClosedForm`, the loop unknowns and their unwrapping
(:func:`analytic.positions.q_from_poses`), the loop Jacobian and ``gamma``
(:class:`analytic.loops.LoopEquations`), the rates (``solve_rates``), the tree walk
(``Linkage._propagate``) and the kinetostatics (:func:`analytic.kinetostatics.solve_forces`),
written out as scalar complex arithmetic in the same order of operations, so that
the two paths agree to rounding.

Only the structure is in the source (which dyads, which bodies and joints, which
joints are prismatic, the spanning tree and its subtrees, which bodies carry loads);
every number of the geometry, masses, loads and gravity is read from two parameter
arrays.  Mechanisms of one structure (every random four-bar of a property test)
therefore share one compiled kernel.
"""

from __future__ import annotations

import cmath
import functools
import math

import numpy as np

from ..mechanism import Revolute
from ..planar import cplx
from ..positions import rrr_disc_factor
from ..tolerances import SINGULAR_CONDITION, TOGGLE_SNAP

#: inputs per chunk of the position stages (their scratch: ~50 bytes per body and
#: input, in L1/L2; a larger chunk measured no faster)
CHUNK = 128
#: layout of the per-call status outputs (``stat`` int64, ``statf`` float64)
STAT_INFEASIBLE, STAT_WORST, STAT_NSUSPECT = 0, 1, 2
FORCE_SCALARS = ("effort", "power", "kinetic_rate", "load_power", "power_residual")


class _Src:
    """Lines of Python with indentation, plus the parameter tables."""

    def __init__(self):
        self.lines: list[str] = []
        self.pf: list[float] = []
        self.pc: list[complex] = []
        self._n = 0

    def emit(self, s: str, ind: int = 2):
        self.lines.append("    " * ind + s)

    def f(self, x: float) -> str:
        """A real parameter: its local name (loaded once before the loop)."""
        self.pf.append(float(x))
        return f"pf{len(self.pf) - 1}"

    def c(self, z: complex) -> str:
        self.pc.append(complex(z))
        return f"pc{len(self.pc) - 1}"

    def tmp(self, stem: str = "t") -> str:
        self._n += 1
        return f"{stem}_{self._n}"


class KernelSource:
    """Generate the kernel source and its parameters for a :class:`Linkage`.

    Attributes
    ----------
    source : str
        Python source of ``kernel(...)`` (see :data:`SIGNATURE`).
    pf, pc : np.ndarray
        The real and complex parameters of this mechanism.
    n_branch, n_dyad_trans, n_prismatic, n_loads : int
        Sizes the caller needs for the outputs.
    """

    def __init__(self, linkage, with_forces: bool):
        self.lk = linkage
        self.topo = linkage.topo
        self.mech = linkage.mech
        self.eqs = linkage.eqs
        self.with_forces = with_forces
        self.s = _Src()
        topo = self.topo
        self.B = len(topo.body_names)
        self.nq = topo.nq
        self.ng = topo.n_groups
        self.J = len(self.mech.joints)
        self.L = topo.n_loops
        self.k = topo.driven_var
        # the square system's size: the unknowns besides the driven variable, or (a
        # driver row over two group angles: a coupler joint driven) every unknown, the
        # driver's row added to the loops' (LoopEquations.split)
        self.n = self.nq - 1 if self.k is not None else self.nq
        self.n_branch = 0
        self.trans = []  # (joint name, e1 var, e2 var)
        # level 0: poses; 1: + angles and q; 2: + rates and tree walk; 3: + forces
        self._positions()
        self._unknowns()
        self._residual()
        self._store_poses()
        start = len(self.s.lines)
        self._jacobian()
        self._rates()
        self._propagate()
        self._store_rates()
        if with_forces:
            fstart = len(self.s.lines)
            self._forces()
            self._indent(fstart, "if level >= 3:")
        self._indent(start, "if level >= 2:")
        self.n_dyad_trans = len(self.trans)
        self.n_prismatic = len(topo.prismatic)
        self.source = self._assemble()

    # -- helpers ---------------------------------------------------------------
    def _indent(self, start: int, header: str):
        """Put the lines emitted since ``start`` under ``header``."""
        body = ["    " + ln for ln in self.s.lines[start:]]
        self.s.lines[start:] = ["        " + header] + body

    def _at(self, j, b) -> str:
        return self.s.c(cplx(self.topo.attach(j, b)))

    def _pt(self, b, j) -> str:
        """``O[b] + E[b] * attach(j, b)`` (world point of joint j on body b); on the
        ground (E = 1, O = 0) the attachment itself."""
        if b == self.topo.ground:
            return self._at(j, b)
        return f"(O{b} + cm(E{b}, {self._at(j, b)}))"

    def _unit(self, z: str, c: str) -> str:
        """``z / |z| * c`` as numpy computes it: ``|z|`` by :func:`cabs`, a complex divided
        by a real is multiplied by its reciprocal (Smith's division with a zero imaginary
        part), so the two paths agree to the last bit near limit positions, where the
        rates amplify any difference by the Jacobian's condition number."""
        t = self.s.tmp("iz")
        self.s.emit(f"{t} = 1.0 / cabs({z}.real, {z}.imag)")
        return f"cm(complex({z}.real * {t}, {z}.imag * {t}), {c})"

    def _place(self, b, th: str, e: str | None = None):
        e_ = e if e is not None else f"complex(math.cos(th{b}), math.sin(th{b}))"
        self.s.emit(f"th{b} = {th}")
        self.s.emit(f"E{b} = {e_}")

    # -- positions: ClosedForm.run ---------------------------------------------
    def _positions(self):
        """The dyad plan as stage loops over a chunk of :data:`CHUNK` inputs, each step
        (an RRR dyad: two) one loop that reads the poses placed before it from scratch
        arrays and writes its own.  One loop per configuration would chain ~250 cycles
        of dependent latency (cos, sin, three square roots, four divisions) that the
        processor cannot overlap across configurations; short loops of independent
        iterations it overlaps (the four-bar's positions: ~87 to ~60 ns).  The
        operations and their order are unchanged (the same bits).  The main loop then
        reloads every pose."""
        topo = self.topo
        self.stage_lines: list[str] = []
        self.placed: list[int] = []  # bodies placed by earlier stages (not the ground)
        self.persist: dict[str, int] = {}  # complex temporaries kept in ``sX``, by column
        for st in topo.plan:
            self._stage_open()
            getattr(self, "_step_" + st.kind)(st)
            self._stage_close(list(st.bodies))

    def _stage_open(self):
        """Start a stage: its lines are collected apart from the main loop's."""
        self._stage_start = len(self.s.lines)

    def _stage_close(self, bodies: list[int], keep: tuple[str, ...] = ()):
        """Close the stage opened last: wrap its lines in a loop over the chunk that
        loads the poses placed so far and the kept temporaries, and stores the poses
        of ``bodies``, the temporaries ``keep`` (for the next stage of the same step)
        and the transmission vectors (for the main loop)."""
        s, g = self.s, self.topo.ground
        body = s.lines[self._stage_start:]
        del s.lines[self._stage_start:]
        loads = self._load_lines()  # what earlier stages stored
        store = []
        for b in bodies:
            if b not in self.placed and b != g:
                store += [f"sE[c, {b}] = E{b}", f"sO[c, {b}] = O{b}", f"sT[c, {b}] = th{b}"]
        trans = tuple(v.lstrip("-") for _, *vs in self.trans for v in vs)
        for name in keep + trans:
            if name in keep or name not in self.persist:
                self.persist.setdefault(name, len(self.persist))
                store.append(f"sX[c, {self.persist[name]}] = {name}")
        self.stage_lines += (["        for i in range(s0, s1):"]
                             + ["            " + ln for ln in loads]
                             + ["    " + ln for ln in body]
                             + ["            " + ln for ln in store])
        for b in bodies:
            if b not in self.placed and b != g:
                self.placed.append(b)

    def _load_lines(self) -> list[str]:
        """Lines that load the input value, the branch row, the ground, the poses placed
        so far and the kept temporaries (a load a stage does not use is dead code:
        LLVM drops it)."""
        g = self.topo.ground
        lines = ["c = i - s0", "v = values[i]", "srow = i if signs.shape[0] > 1 else 0",
                 f"th{g} = 0.0", f"E{g} = 1.0 + 0.0j", f"O{g} = 0.0j"]
        for b in self.placed:
            lines += [f"E{b} = sE[c, {b}]", f"O{b} = sO[c, {b}]", f"th{b} = sT[c, {b}]"]
        lines += [f"{name} = sX[c, {k}]" for name, k in self.persist.items()]
        return lines

    def _disc(self, expr: str):
        s = self.s
        s.emit(f"dsc = {expr}")
        s.emit(f"if dsc < {-TOGGLE_SNAP!r} and bad_i < 0:")
        s.emit("bad_i = i", 3)

    def _sign(self) -> str:
        k = self.n_branch
        self.n_branch += 1
        return f"signs[srow, {k}]"

    def _step_driven_revolute(self, st):
        topo, joints, s = self.topo, self.mech.joints, self.s
        (x,), (j,) = st.bodies, st.joints
        k = topo.other(j, x)
        sgn = 1.0 if topo.body_names[x] == joints[j].body_b else -1.0
        self._place(x, f"th{k} + {sgn!r} * v")
        s.emit(f"O{x} = {self._pt(k, j)} - cm(E{x}, {self._at(j, x)})")

    def _step_driven_prismatic(self, st):
        topo, jt, s = self.topo, self.mech.joints[st.joints[0]], self.s
        (x,), (j,) = st.bodies, st.joints
        k = topo.other(j, x)
        ul = s.c(cmath.exp(1j * jt.direction))
        if topo.body_names[x] == jt.slider:
            self._place(x, f"th{k} + {s.f(jt.angle)}", f"cm(E{k}, {s.c(cmath.exp(1j * jt.angle))})")
            s.emit(f"PS = {self._pt(k, j)} + v * cm(E{k}, {ul})")
            s.emit(f"O{x} = PS - cm(E{x}, {self._at(j, x)})")
        else:
            self._place(x, f"th{k} - {s.f(jt.angle)}",
                        f"cm(E{k}, {s.c(cmath.exp(-1j * jt.angle))})")
            s.emit(f"Q = {self._pt(k, j)} - v * cm(E{x}, {ul})")
            s.emit(f"O{x} = Q - cm(E{x}, {self._at(j, x)})")

    def _step_RRR(self, st):
        topo, joints, s, at = self.topo, self.mech.joints, self.s, self._at
        x1, x2 = st.bodies
        j1, j2, j3 = st.joints
        k1, k3 = topo.other(j1, x1), topo.other(j3, x2)
        c1 = cplx(topo.attach(j2, x1)) - cplx(topo.attach(j1, x1))
        c2 = cplx(topo.attach(j3, x2)) - cplx(topo.attach(j2, x2))
        L1s, L2s = s.f(abs(c1) ** 2), s.f(abs(c2) ** 2)
        n1, n2 = s.c((c1 / abs(c1)).conjugate()), s.c((c2 / abs(c2)).conjugate())
        t = s.tmp("tr")
        s.emit(f"P1 = {self._pt(k1, j1)}")
        s.emit(f"P3 = {self._pt(k3, j3)}")
        s.emit("d = P3 - P1")
        s.emit("D2 = d.real * d.real + d.imag * d.imag")
        s.emit("D = math.sqrt(D2)")
        s.emit("Dsafe = D if D > 0 else 1.0")
        # exactly numpy's operations: h2 below cancels, amplifying any rounding in a
        s.emit(f"a = ({L1s} - {L2s} + D2) / (2 * Dsafe)")
        s.emit("iD = 1.0 / Dsafe")
        s.emit(f"h2 = {L1s} - a * a")
        s.emit(f"dsc = h2 * {s.f(rrr_disc_factor(c1, c2))} if D > 0 else -1.0")
        self._disc("dsc")
        s.emit(f"h = math.sqrt(max(h2, 0.0)) if dsc > {TOGGLE_SNAP!r} else 0.0")
        s.emit(f"w = cm(d, complex(a, {self._sign()} * h))")
        s.emit("P2 = P1 + complex(w.real * iD, w.imag * iD)")
        # a second stage: the intersection's chain and the links' directions
        self._stage_close([], keep=("P1", "P2", "P3"))
        self._stage_open()
        s.emit(f"{t}a = P2 - P1")
        s.emit(f"{t}b = P3 - P2")
        s.emit(f"E{x1} = {self._unit(f'{t}a', n1)}")
        s.emit(f"E{x2} = {self._unit(f'{t}b', n2)}")
        s.emit(f"th{x1} = math.atan2(E{x1}.imag, E{x1}.real) if level >= 1 else 0.0")
        s.emit(f"th{x2} = math.atan2(E{x2}.imag, E{x2}.real) if level >= 1 else 0.0")
        s.emit(f"O{x1} = P1 - cm(E{x1}, {at(j1, x1)})")
        s.emit(f"O{x2} = P2 - cm(E{x2}, {at(j2, x2)})")
        self.trans.append((joints[j2].name, f"-{t}a", f"{t}b"))

    def _step_driven_RRR(self, st):
        """:meth:`analytic.positions.ClosedForm._driven_rrr`: the virtual link ``c1``
        (the driver's two bodies) per input, then :meth:`_step_RRR`'s intersection."""
        topo, joints, s, at = self.topo, self.mech.joints, self.s, self._at
        u, w, v = st.bodies
        j1, j2, j3, jd = st.joints
        k1, k3 = topo.other(j1, u), topo.other(j3, w)
        sgn = 1.0 if topo.body_names[v] == joints[jd].body_b else -1.0
        cu = cplx(topo.attach(jd, u)) - cplx(topo.attach(j1, u))
        cv = cplx(topo.attach(j2, v)) - cplx(topo.attach(jd, v))
        c2 = cplx(topo.attach(j3, w)) - cplx(topo.attach(j2, w))
        L2 = abs(c2)
        t = s.tmp("tr")
        s.emit(f"P1 = {self._pt(k1, j1)}")
        s.emit(f"P3 = {self._pt(k3, j3)}")
        s.emit(f"rv = {sgn!r} * v")
        s.emit("R = complex(math.cos(rv), math.sin(rv))")
        s.emit(f"c1 = {s.c(cu)} + cm(R, {s.c(cv)})")
        s.emit("L1 = cabs(c1.real, c1.imag)")
        s.emit("L1s = L1 * L1")
        s.emit("d = P3 - P1")
        s.emit("D2 = d.real * d.real + d.imag * d.imag")
        s.emit("D = math.sqrt(D2)")
        s.emit("Dsafe = D if D > 0 else 1.0")
        s.emit("L1safe = L1 if L1 > 0 else 1.0")
        s.emit(f"a = (L1s - {s.f(L2 * L2)} + D2) / (2 * Dsafe)")
        s.emit("iD = 1.0 / Dsafe")
        s.emit("h2 = L1s - a * a")
        L2f = s.f(L2)
        s.emit(f"dsc = (h2 * (L1safe + {L2f}) / (L1safe * {L2f} * max(L1safe, {L2f})) "
               "if D > 0 and L1 > 0 else -1.0)")
        self._disc("dsc")
        s.emit(f"h = math.sqrt(max(h2, 0.0)) if dsc > {TOGGLE_SNAP!r} else 0.0")
        s.emit(f"w = cm(d, complex(a, {self._sign()} * h))")
        s.emit("P2 = P1 + complex(w.real * iD, w.imag * iD)")
        s.emit(f"{t}a = P2 - P1")
        s.emit(f"{t}b = P3 - P2")
        s.emit(f"E{u} = {self._unit(f'{t}a', 'complex(c1.real / L1safe, -c1.imag / L1safe)')}")
        s.emit(f"E{w} = {self._unit(f'{t}b', s.c((c2 / L2).conjugate()))}")
        s.emit(f"E{v} = cm(E{u}, R)")
        s.emit(f"th{u} = math.atan2(E{u}.imag, E{u}.real) if level >= 1 else 0.0")
        s.emit(f"th{w} = math.atan2(E{w}.imag, E{w}.real) if level >= 1 else 0.0")
        s.emit(f"th{v} = th{u} + rv")
        s.emit(f"O{u} = P1 - cm(E{u}, {at(j1, u)})")
        s.emit(f"O{w} = P2 - cm(E{w}, {at(j2, w)})")
        s.emit(f"O{v} = P2 - cm(E{v}, {at(j2, v)})")
        s.emit(f"{t}p = O{u} + cm(E{u}, {at(jd, u)}) - P2")
        self.trans.append((joints[j2].name, f"{t}p", f"{t}b"))

    def _step_RRP(self, st):
        topo, joints, s, at = self.topo, self.mech.joints, self.s, self._at
        x1, x2 = st.bodies
        j1, j2, j3 = st.joints
        jt = joints[j3]
        k1, k3 = topo.other(j1, x1), topo.other(j3, x2)
        c1 = cplx(topo.attach(j2, x1)) - cplx(topo.attach(j1, x1))
        L1s = s.f(abs(c1) ** 2)
        n1 = s.c((c1 / abs(c1)).conjugate())
        ul = s.c(cmath.exp(1j * jt.direction))
        t = s.tmp("tr")
        s.emit(f"P1 = {self._pt(k1, j1)}")
        if topo.body_names[x2] == jt.slider:
            self._place(x2, f"th{k3} + {s.f(jt.angle)}",
                        f"cm(E{k3}, {s.c(cmath.exp(1j * jt.angle))})")
            s.emit(f"u = cm(E{k3}, {ul})")
            s.emit("ud = u")
        else:
            self._place(x2, f"th{k3} - {s.f(jt.angle)}",
                        f"cm(E{k3}, {s.c(cmath.exp(-1j * jt.angle))})")
            s.emit(f"u = cm(E{x2}, {ul})")
            s.emit("ud = -u")
        dc = s.c(cplx(topo.attach(j2, x2)) - cplx(topo.attach(j3, x2)))
        s.emit(f"base = {self._pt(k3, j3)} + cm(E{x2}, {dc})")
        s.emit("e = base - P1")
        s.emit("eu = e.real * ud.real + e.imag * ud.imag")
        s.emit(f"h2 = eu * eu - (e.real * e.real + e.imag * e.imag) + {L1s}")
        self._disc(f"h2 / {L1s}")
        s.emit(f"tt = -eu + {self._sign()} * (math.sqrt(max(h2, 0.0)) "
               f"if h2 / {L1s} > {TOGGLE_SNAP!r} else 0.0)")
        s.emit("P2 = base + tt * ud")
        s.emit(f"{t}a = P2 - P1")
        s.emit(f"E{x1} = {self._unit(f'{t}a', n1)}")
        s.emit(f"th{x1} = math.atan2(E{x1}.imag, E{x1}.real) if level >= 1 else 0.0")
        s.emit(f"O{x1} = P1 - cm(E{x1}, {at(j1, x1)})")
        s.emit(f"O{x2} = P2 - cm(E{x2}, {at(j2, x2)})")
        s.emit(f"{t}b = 1j * u")
        self.trans.append((joints[j2].name, f"-{t}a", f"{t}b"))

    def _step_RPR(self, st):
        topo, joints, s = self.topo, self.mech.joints, self.s
        x1, x2 = st.bodies
        j1, j2, j3 = st.joints
        jt = joints[j2]
        g = x1 if topo.body_names[x1] == jt.guide else x2
        s_ = x2 if g == x1 else x1
        jg, js = (j1, j3) if g == x1 else (j3, j1)
        kg, ks = topo.other(jg, g), topo.other(js, s_)
        aG, aS = cplx(topo.attach(jg, g)), cplx(topo.attach(js, s_))
        nl = 1j * cmath.exp(1j * jt.direction)
        kconst = (nl.conjugate() * (cmath.exp(1j * jt.angle) * (cplx(topo.attach(j2, s_)) - aS)
                                    - (cplx(topo.attach(j2, g)) - aG))).real
        s.emit(f"PG = {self._pt(kg, jg)}")
        s.emit(f"PSr = {self._pt(ks, js)}")
        s.emit("d = PSr - PG")
        s.emit("D = cabs(d.real, d.imag)")
        s.emit("Dsafe = D if D > 0 else 1.0")
        s.emit(f"ratio = -{s.f(kconst)} / Dsafe")
        s.emit("dsc = 1.0 - ratio * ratio if D > 0 else -1.0")
        self._disc("dsc")
        s.emit("psi = math.atan2(d.imag, d.real)")
        s.emit(f"ac = math.acos(min(max(ratio, -1.0), 1.0)) if dsc > {TOGGLE_SNAP!r} else "
               f"(0.0 if ratio > 0 else {math.pi!r})")
        s.emit(f"thg = psi - {s.f(jt.direction + math.pi / 2)} + {self._sign()} * ac")
        self._place(g, "thg")
        self._place(s_, f"thg + {s.f(jt.angle)}", f"cm(E{g}, {s.c(cmath.exp(1j * jt.angle))})")
        s.emit(f"O{g} = PG - cm(E{g}, {s.c(aG)})")
        s.emit(f"O{s_} = PSr - cm(E{s_}, {s.c(aS)})")

    def _step_PRP(self, st):
        topo, joints, s = self.topo, self.mech.joints, self.s
        x1, x2 = st.bodies
        j1, j2, j3 = st.joints
        for n, (x, j) in enumerate(((x1, j1), (x2, j3))):
            jt = joints[j]
            k = topo.other(j, x)
            ul = s.c(cmath.exp(1j * jt.direction))
            if topo.body_names[x] == jt.slider:
                self._place(x, f"th{k} + {s.f(jt.angle)}",
                            f"cm(E{k}, {s.c(cmath.exp(1j * jt.angle))})")
                s.emit(f"dir{n} = cm(E{k}, {ul})")
            else:
                self._place(x, f"th{k} - {s.f(jt.angle)}",
                            f"cm(E{k}, {s.c(cmath.exp(-1j * jt.angle))})")
                s.emit(f"dir{n} = cm(E{x}, {ul})")
            dc = s.c(cplx(topo.attach(j2, x)) - cplx(topo.attach(j, x)))
            s.emit(f"base{n} = {self._pt(k, j)} + cm(E{x}, {dc})")
        s.emit("cr = dir0.real * dir1.imag - dir0.imag * dir1.real")
        self._disc("abs(cr) - 1e-12")
        s.emit("db = base1 - base0")
        s.emit("t1 = (db.real * dir1.imag - db.imag * dir1.real) / (cr if cr != 0 else 1.0)")
        s.emit("P2 = base0 + t1 * dir0")
        s.emit(f"O{x1} = P2 - cm(E{x1}, {self._at(j2, x1)})")
        s.emit(f"O{x2} = P2 - cm(E{x2}, {self._at(j2, x2)})")

    # -- unknowns: q_from_poses, unwrapped as over one batch --------------------
    def _unknowns(self):
        topo, s, joints = self.topo, self.s, self.mech.joints
        s.emit("if level >= 1:")
        for g, b in enumerate(topo.group_leader):
            s.emit(f"raw{g} = th{b} - {s.f(topo.offset[b])}", 3)
            s.emit("if has_prev:", 3)
            s.emit(f"turn{g} += np.rint((raw{g} - prev{g}) * {0.5 / math.pi!r})", 4)
            s.emit(f"prev{g} = raw{g}", 3)
            s.emit(f"q{g} = raw{g} - {2 * math.pi!r} * turn{g}", 3)
        s.emit("has_prev = True", 3)
        for b, g in enumerate(topo.group_of):
            if g >= 0:
                s.emit(f"th{b} = q{g} + {s.f(topo.offset[b])}", 3)
        s.emit("else:")
        for g in range(topo.n_groups):
            s.emit(f"q{g} = 0.0", 3)
        for j, i in topo.slider_index.items():
            jt = joints[j]
            gb, sb = topo.body_names.index(jt.guide), topo.body_names.index(jt.slider)
            c = topo.n_groups + i
            s.emit(f"dPQ = O{sb} + cm(E{sb}, {self._at(j, sb)}) - O{gb} - cm(E{gb}, "
                   f"{self._at(j, gb)})")
            s.emit(f"uu = cm(E{gb}, {s.c(cmath.exp(1j * jt.direction))})")
            s.emit(f"q{c} = dPQ.real * uu.real + dPQ.imag * uu.imag")

    # -- loop equations: terms, residual, Jacobian ------------------------------
    def _residual(self):
        """Loop closure ``sum m ez`` per loop, the worst component over the call (a
        check, not an output: constant-length terms fold ``r exp(i beta)`` into one
        constant per body, the ground's into one constant per loop)."""
        s, eqs, topo = self.s, self.eqs, self.topo
        t = topo.terms
        for li in range(self.L):
            parts, const = [], 0j
            for k in range(len(t.loop)):
                if t.loop[k] != li:
                    continue
                tb = eqs.term_body[k]
                if eqs.ns and t.slider[k] >= 0:
                    m = f"({float(eqs.sign[k])!r} * q{self.ng + t.slider[k]})"
                    ez = (s.c(eqs.term_rot[k]) if tb == topo.ground
                          else f"(E{tb} * {s.c(eqs.term_rot[k])})")
                    parts.append(f"complex({m} * {ez}.real, {m} * {ez}.imag)")
                elif tb == topo.ground:
                    const += eqs.r[k] * eqs.term_rot[k]
                else:
                    parts.append(f"E{tb} * {s.c(eqs.r[k] * eqs.term_rot[k])}")
            parts.append(s.c(const))
            s.emit(f"rs = {' + '.join(parts)}")
            s.emit("ra = max(abs(rs.real), abs(rs.imag))")
            s.emit("if ra > worst or (ra != ra and worst == worst):")
            s.emit("worst = ra", 3)
            s.emit("worst_i = i", 3)

    def _jacobian(self):
        """Jacobian columns: group angle ``sum (1j m) ez``, slider ``sign ez``; ``A``
        without the driven column (the square system of ``LoopEquations.split``)."""
        s, eqs, topo = self.s, self.eqs, self.topo
        t = topo.terms
        T = len(t.loop)
        for k in range(T):
            tb = eqs.term_body[k]
            s.emit(f"ez{k} = " + (s.c(eqs.term_rot[k]) if tb == topo.ground
                                  else f"cm(E{tb}, {s.c(eqs.term_rot[k])})"))
            if eqs.ns and t.slider[k] >= 0:
                s.emit(f"m{k} = {s.f(eqs.r[k])} + {s.f(eqs.sign[k])} * q{self.ng + t.slider[k]}")
            else:
                s.emit(f"m{k} = {s.f(eqs.r[k])}")
        self.cols = [c for c in range(self.nq) if c != self.k]
        for li in range(self.L):
            ks = [k for k in range(T) if t.loop[k] == li]
            for c in range(self.nq):
                parts = []
                for k in ks:
                    if c < self.ng and t.group[k] == c:
                        parts.append(f"(1j * m{k}) * ez{k}")
                    if c >= self.ng and t.slider[k] == c - self.ng:
                        parts.append(f"ez{k} * {s.f(eqs.sign[k])}")
                s.emit(f"jz = {' + '.join(parts) if parts else '0j'}")
                s.emit(f"J{2 * li}_{c} = jz.real")
                s.emit(f"J{2 * li + 1}_{c} = jz.imag")

    def _emit_solve(self, A: str, rhs_rows: list[str], n: int, out: str,
                    factored: bool = False):
        """Fill the rhs into ``sb`` and solve with scratch ``A`` (n x n, already
        written): Cramer's rule up to 3x3 as :func:`analytic.linalg.solve_small`, else
        LU (``factored``: with the factors already in ``lu``)."""
        s = self.s
        for r, e in enumerate(rhs_rows):
            s.emit(f"sb[{r}] = {e}")
        if n > 3 and factored:
            s.emit(f"lu_solve(lu, piv, sb, {n}, {out})")
        else:
            s.emit(f"solve_small({A}, sb, {n}, {out}, lu, piv)")

    # -- rates ------------------------------------------------------------------
    def _rates(self):
        s, topo, eqs = self.s, self.topo, self.eqs
        n, k, L2 = self.n, self.k, 2 * self.L
        t = topo.terms
        # (the parameter's index first, as before the driver-row case: the same source,
        # so the kernels already in numba's cache stay valid)
        dk = s.f(topo.driver_row[k]) if k is not None else None
        for r in range(L2):
            for ci, c in enumerate(self.cols):
                s.emit(f"A[{r}, {ci}] = J{r}_{c}")
        if k is None:  # the driver's row
            for ci, c in enumerate(self.cols):
                s.emit(f"A[{L2}, {ci}] = {float(topo.driver_row[c])!r}")
        # determinant normalised by the column norms, and the singular screen
        if n:
            s.emit("colnorm = 1.0")
            s.emit("cmax = 0.0")
            s.emit("cmin = np.inf")
            cs = self.lk.column_scale  # sliders in sizes, as Kinematics.condition
            for ci in range(n):
                s.emit(f"cn = math.sqrt({' + '.join(f'A[{r}, {ci}] ** 2' for r in range(n))})")
                s.emit("colnorm *= cn")
                if self.cols[ci] >= self.ng:  # the bound: sliders in sizes
                    s.emit(f"cn = cn * {s.f(cs[ci])}")
                s.emit("cmax = max(cmax, cn)")
                s.emit("cmin = min(cmin, cn)")
            if n > 3:  # one LU for the determinant, the rates and the accelerations
                s.emit(f"sgn_lu = lu_factor(A, {n}, lu, piv)")
                s.emit(f"det = lu_det(lu, {n}, sgn_lu) / (colnorm if colnorm > 0 else 1.0)")
            else:
                s.emit(f"det = det_small(A, {n}, lu, piv) / (colnorm if colnorm > 0 else 1.0)")
            s.emit(f"bound = {float(n ** (n / 2))!r} / abs(det) * (cmax / cmin)")
            s.emit(f"if not bound < {SINGULAR_CONDITION!r}:")
            s.emit("if nsus < susp.shape[0]:", 3)
            s.emit("susp[nsus] = i", 4)
            s.emit("nsus += 1", 3)
        else:
            s.emit("det = 1.0")
        # q' : rhs = 0 - col * xd ; q'' : rhs = -gamma - col * xdd (a driver row: the
        # input's rate and acceleration are its right-hand side)
        if k is None:
            self._emit_solve("A", ["0.0"] * L2 + ["wd"], n, "xu", True)
        else:
            s.emit(f"xd = wd / {dk}")
            self._emit_solve("A", [f"0.0 - J{r}_{k} * xd" for r in range(L2)], n, "xu", True)
        self._insert("qd", "xd")
        # gamma with the rates
        ns = eqs.ns
        for li in range(self.L):
            ks = [kk for kk in range(len(t.loop)) if t.loop[kk] == li]
            parts = []
            for kk in ks:
                if t.group[kk] < 0:
                    continue  # w = 0: the term adds an exact zero
                w = f"qd{t.group[kk]}"
                if ns and t.slider[kk] >= 0:
                    md = f"({s.f(eqs.sign[kk])} * qd{self.ng + t.slider[kk]})"
                    parts.append(f"cm(2j * {md} * {w} - m{kk} * {w} * {w}, ez{kk})")
                else:
                    parts.append(f"(-m{kk} * {w} * {w}) * ez{kk}")
            s.emit(f"gz = {' + '.join(parts) if parts else '0j'}")
            s.emit(f"G{2 * li} = gz.real")
            s.emit(f"G{2 * li + 1} = gz.imag")
        if k is None:
            self._emit_solve("A", [f"-G{r}" for r in range(L2)] + ["ad"], n, "xu", True)
        else:
            s.emit(f"xdd = ad / {dk}")
            self._emit_solve("A", [f"-G{r} - J{r}_{k} * xdd" for r in range(L2)], n, "xu",
                             True)
        self._insert("qdd", "xdd")

    def _insert(self, name, driven):
        ci = 0
        for c in range(self.nq):
            if self.k is not None and c == self.k:
                self.s.emit(f"{name}{c} = {driven}")
            else:
                self.s.emit(f"{name}{c} = xu[{ci}]")
                ci += 1

    # -- tree walk: Linkage._group_rates and _propagate ------------------------
    def _propagate(self):
        s, topo, joints = self.s, self.topo, self.mech.joints
        for b, g in enumerate(topo.group_of):
            s.emit(f"w{b} = {f'qd{g}' if g >= 0 else '0.0'}")
            s.emit(f"al{b} = {f'qdd{g}' if g >= 0 else '0.0'}")
        g0 = topo.ground
        s.emit(f"V{g0} = 0j")
        s.emit(f"Ac{g0} = 0j")
        for c in topo.order[1:]:
            p, j = topo.parent[c]
            jt = joints[j]
            s.emit(f"rp = cm(E{p}, {self._at(j, p)})")
            s.emit(f"P = O{p} + rp")
            s.emit(f"vP = V{p} + 1j * w{p} * rp")
            s.emit(f"aP = Ac{p} + cm(1j * al{p} - w{p} * w{p}, rp)")
            if not isinstance(jt, Revolute):
                i = topo.n_groups + topo.slider_index[j]
                gb = topo.body_names.index(jt.guide)
                u = s.c(complex(math.cos(jt.direction), math.sin(jt.direction)))
                s.emit(f"u = cm(E{gb}, {u})")
                s.emit(f"rel_v = qd{i} * u")
                s.emit(f"rel_a = cm(qdd{i} + 2j * w{gb} * qd{i}, u)")
                if c == topo.body_names.index(jt.slider):
                    s.emit(f"PS = O{c} + cm(E{c}, {self._at(j, c)})")
                    s.emit("r = PS - P")
                    s.emit(f"vP = vP + 1j * w{p} * r + rel_v")
                    s.emit(f"aP = aP + cm(1j * al{p} - w{p} * w{p}, r) + rel_a")
                    s.emit("P = PS")
                else:
                    s.emit("vP = vP - rel_v")
                    s.emit("aP = aP - rel_a")
            s.emit(f"JP{j} = P")
            s.emit(f"rc = O{c} - P")
            s.emit(f"V{c} = vP + 1j * w{c} * rc")
            s.emit(f"Ac{c} = aP + cm(1j * al{c} - w{c} * w{c}, rc)")
        for j in topo.chords:
            bb = topo.body_names.index(joints[j].body_b)
            s.emit(f"JP{j} = O{bb} + cm(E{bb}, {self._at(j, bb)})")

    def _store_poses(self):
        s, B = self.s, self.B
        s.emit("if level >= 1:")
        s.emit("if q.shape[0] > 0:", 3)  # the forces pass of a known state writes none
        for c in range(self.nq):
            s.emit(f"q[i, {c}] = q{c}", 4)
        s.emit("if theta.shape[0] > 0:", 3)
        for b in range(B):
            s.emit(f"theta[i, {b}] = th{b}", 4)
        s.emit("if Eo.shape[0] > 0:")
        for b in range(B):
            s.emit(f"Eo[i, {b}] = E{b}", 3)
            s.emit(f"zO[i, {b}] = O{b}", 3)
        # joint points without the rates (level 0 or 1, FusedKernel.joint_positions):
        # each as the tree walk forms it (the parent's point; a prismatic joint's slider
        # point), so the numbers are those of level 2's jp bit for bit
        s.emit("if level < 2 and jp.shape[0] > 0:")
        topo, joints = self.topo, self.mech.joints
        for c in topo.order[1:]:
            p, j = topo.parent[c]
            jt = joints[j]
            if not isinstance(jt, Revolute) and c == topo.body_names.index(jt.slider):
                s.emit(f"jp[i, {j}] = O{c} + cm(E{c}, {self._at(j, c)})", 3)
            else:
                s.emit(f"jp[i, {j}] = O{p} + cm(E{p}, {self._at(j, p)})", 3)
        for j in topo.chords:
            bb = topo.body_names.index(joints[j].body_b)
            s.emit(f"jp[i, {j}] = O{bb} + cm(E{bb}, {self._at(j, bb)})", 3)

    def _store_rates(self):
        s, B, nq, n = self.s, self.B, self.nq, self.n
        s.emit("if qd.shape[0] > 0:")
        for c in range(nq):
            s.emit(f"qd[i, {c}] = qd{c}", 3)
            s.emit(f"qdd[i, {c}] = qdd{c}", 3)
        s.emit("if omega.shape[0] > 0:")
        for b in range(B):
            for arr, var in (("omega", "w"), ("alpha", "al"), ("zv", "V"), ("za", "Ac")):
                s.emit(f"{arr}[i, {b}] = {var}{b}", 3)
        s.emit("if Ao.shape[0] > 0:")
        for r in range(n):
            for c in range(n):
                s.emit(f"Ao[i, {r}, {c}] = A[{r}, {c}]", 3)
        s.emit("deto[i] = det", 3)
        for d, (_, e1, e2) in enumerate(self.trans):
            s.emit(f"trv[i, {2 * d}] = {e1}", 3)
            s.emit(f"trv[i, {2 * d + 1}] = {e2}", 3)
        s.emit("if jp.shape[0] > 0:")  # with the full result, or asked for alone
        for j in range(self.J):
            s.emit(f"jp[i, {j}] = JP{j}", 3)

    # -- kinetostatics: solve_forces ---------------------------------------------
    def _forces(self):
        """The phases of :func:`analytic.kinetostatics.solve_forces`, emitted in its
        order: effective wrenches, chord columns, subtree sums, tree-joint rows, the
        unknowns, the reactions and the power terms."""
        self._effective_wrenches()
        n_x = self._chord_columns()
        eps = self._chord_signs(n_x)
        self._subtree_sums()
        td, sd, rows = self._tree_rows(eps, n_x)
        nu = n_x - 1
        self._solve_unknowns(rows, td, sd, nu)
        self._chord_reactions()
        self._tree_reactions(eps, n_x)
        self._power_terms(nu)

    def _effective_wrenches(self):
        """Each moving body's effective force ``f{b}`` (inertia less gravity and loads)
        and its moment ``mo{b}`` about the origin, with the kinetic-energy rate ``ke``
        and the loads' power ``lp``."""
        s, topo, mech = self.s, self.topo, self.mech
        g = s.c(complex(*mech.gravity))
        s.emit("ke = 0.0")
        s.emit("lp = 0.0")
        for b, body in enumerate(mech.bodies):
            if b == topo.ground:
                continue
            m, I = s.f(body.mass), s.f(body.inertia)
            s.emit(f"rr = cm(E{b}, {s.c(cplx(body.com))})")
            s.emit(f"rG = O{b} + rr")
            s.emit(f"vG = V{b} + 1j * w{b} * rr")
            s.emit(f"aG = Ac{b} + cm(1j * al{b} - w{b} * w{b}, rr)")
            s.emit(f"f{b} = {m} * (aG - {g})")
            s.emit(f"hh = {I} * al{b}")
            s.emit(f"ke += ({m} * (aG.real * vG.real + aG.imag * vG.imag) + {I} * al{b} * w{b})")
            s.emit(f"lp += {m} * (vG.real * {g}.real + vG.imag * {g}.imag)")
            for ld in mech.loads:
                if ld.body == body.name:
                    self._load_wrench(b, ld)
            s.emit(f"mo{b} = hh + (rG.real * f{b}.imag - rG.imag * f{b}.real)")

    def _load_wrench(self, b: int, ld):
        """Subtract an external load on body ``b`` from its effective wrench and add
        its power to ``lp``."""
        s = self.s
        F, tq = s.c(complex(*ld.force)), s.f(ld.torque)
        if ld.point is not None:
            c = s.c(cplx(self.topo.body_points[b][ld.point]))
            s.emit(f"rl = cm(E{b}, {c})")
            s.emit(f"rP = O{b} + rl")
            s.emit(f"vP = V{b} + 1j * w{b} * rl")
        else:
            s.emit("rP = rG")
            s.emit("vP = vG")
        s.emit(f"f{b} -= {F}")
        s.emit("dr = rP - rG")
        s.emit(f"hh = hh - {tq} - (dr.real * {F}.imag - dr.imag * {F}.real)")
        s.emit(f"lp += vP.real * {F}.real + vP.imag * {F}.imag + {tq} * w{b}")

    def _chord_columns(self) -> int:
        """Force ``Fc{k}`` and moment ``Mc{k}`` of each unknown's unit value (two per
        chord joint, then the effort's, which acts on no chord); returns their count."""
        s, joints, names = self.s, self.mech.joints, self.topo.body_names
        chords = self.topo.chords
        n_x = 2 * len(chords) + 1
        for i, j in enumerate(chords):
            jt = joints[j]
            if isinstance(jt, Revolute):
                s.emit(f"Fc{2 * i} = 1.0 + 0j")
                s.emit(f"Fc{2 * i + 1} = 1j")
                s.emit(f"Mc{2 * i} = -JP{j}.imag")
                s.emit(f"Mc{2 * i + 1} = JP{j}.real")
            else:
                nn = s.c(1j * cmath.exp(1j * jt.direction))
                s.emit(f"Fc{2 * i} = cm(E{names.index(jt.guide)}, {nn})")
                s.emit(f"Fc{2 * i + 1} = 0j")
                s.emit(f"Mc{2 * i} = JP{j}.real * Fc{2 * i}.imag - JP{j}.imag * Fc{2 * i}.real")
                s.emit(f"Mc{2 * i + 1} = 1.0")
        s.emit(f"Fc{n_x - 1} = 0j")  # the effort's column acts on no chord
        s.emit(f"Mc{n_x - 1} = 0.0")
        return n_x

    def _chord_signs(self, n_x: int) -> np.ndarray:
        """``eps (tree joints, n_x)``: +1 where a chord's reaction acts on the subtree
        beyond a tree joint (its body_b inside, body_a outside), -1 the other way, 0 where
        it does not cross (known from the structure: nothing emitted)."""
        topo, joints, names = self.topo, self.mech.joints, self.topo.body_names
        nt = len(topo.tree)
        eps = np.zeros((nt, n_x))
        for t in range(nt):
            S = topo.subtree[t]
            for i, j in enumerate(topo.chords):
                a, b = names.index(joints[j].body_a), names.index(joints[j].body_b)
                e = (1.0 if S[b] and not S[a] else -1.0 if S[a] and not S[b] else 0.0)
                eps[t, 2 * i:2 * i + 2] = e
        return eps

    def _subtree_sums(self):
        """Net effective force ``Sf{t}`` and moment ``Smo{t}`` of each tree joint's
        subtree."""
        s, topo = self.s, self.topo
        for t in range(len(topo.tree)):
            mem = np.flatnonzero(topo.subtree[t])
            s.emit(f"Sf{t} = {' + '.join(f'f{b}' for b in mem)}")
            s.emit(f"Smo{t} = {' + '.join(f'mo{b}' for b in mem)}")

    def _tree_rows(self, eps: np.ndarray, n_x: int):
        """One equation per tree joint along its free direction (``F{t}_{k} x = R{t}``):
        a revolute joint's moment about its pin, a prismatic joint's force along its
        line.  Returns the driven joint's row and sign, and the other rows."""
        s, topo, joints, names = self.s, self.topo, self.mech.joints, self.topo.body_names
        td = sd = None
        rows = []
        for t, j in enumerate(topo.tree):
            jt = joints[j]
            c = topo.tree_child[t]
            acting = np.flatnonzero(eps[t])
            if j == topo.driver_joint:
                td, sd = t, (1.0 if names[c] == jt.body_b else -1.0)
            else:
                rows.append(t)
            for kx in range(n_x):
                s.emit(f"F{t}_{kx} = 0.0")
            if isinstance(jt, Revolute):
                P = f"JP{j}"
                for kx in acting:
                    s.emit(f"F{t}_{kx} = {float(eps[t, kx])!r} * (Mc{kx} - ({P}.real * Fc{kx}.imag "
                           f"- {P}.imag * Fc{kx}.real))")
                s.emit(f"R{t} = Smo{t} - ({P}.real * Sf{t}.imag - {P}.imag * Sf{t}.real)")
            else:
                u = s.c(cmath.exp(1j * jt.direction))
                s.emit(f"uj = cm(E{names.index(jt.guide)}, {u})")
                for kx in acting:
                    s.emit(f"F{t}_{kx} = {float(eps[t, kx])!r} * (uj.real * Fc{kx}.real "
                           f"+ uj.imag * Fc{kx}.imag)")
                s.emit(f"R{t} = uj.real * Sf{t}.real + uj.imag * Sf{t}.imag")
        return td, sd, rows

    def _solve_unknowns(self, rows: list[int], td: int, sd: float, nu: int):
        """The chord reactions ``x0 .. x{nu-1}`` from the rows of the undriven tree
        joints, then the effort ``x{nu}`` from the driven joint's row."""
        s = self.s
        for r, t in enumerate(rows):
            for kx in range(nu):
                s.emit(f"A2[{r}, {kx}] = F{t}_{kx}")
        if nu:
            self._emit_solve("A2", [f"R{t}" for t in rows], nu, "xf")
        for kx in range(nu):
            s.emit(f"x{kx} = xf[{kx}]")
        dot = " + ".join(f"F{td}_{kx} * x{kx}" for kx in range(nu)) or "0.0"
        s.emit(f"x{nu} = (R{td} - ({dot})) / {sd!r}")

    def _chord_reactions(self):
        """The chord joints' forces (by body_a on body_b), and a prismatic chord's
        normal force and moment, from the unknowns."""
        s, topo, joints = self.s, self.topo, self.mech.joints
        pidx = {j: i for i, j in enumerate(topo.prismatic)}
        for i, j in enumerate(topo.chords):
            jt = joints[j]
            if isinstance(jt, Revolute):
                s.emit(f"jf[i, {j}, 0] = x{2 * i}")
                s.emit(f"jf[i, {j}, 1] = x{2 * i + 1}")
            else:
                s.emit(f"nm[i, {pidx[j]}, 0] = x{2 * i}")
                s.emit(f"nm[i, {pidx[j]}, 1] = x{2 * i + 1}")
                s.emit(f"fz = Fc{2 * i} * x{2 * i}")
                s.emit(f"jf[i, {j}, 0] = fz.real")
                s.emit(f"jf[i, {j}, 1] = fz.imag")

    def _tree_reactions(self, eps: np.ndarray, n_x: int):
        """Each tree joint's reaction: its subtree's net effective force less the chord
        reactions acting on the subtree (a prismatic joint's normal force and moment
        too)."""
        s, topo, joints, names = self.s, self.topo, self.mech.joints, self.topo.body_names
        pidx = {j: i for i, j in enumerate(topo.prismatic)}
        for t, j in enumerate(topo.tree):
            jt = joints[j]
            c = topo.tree_child[t]
            s.emit(f"oc = Sf{t}")
            for kx in np.flatnonzero(eps[t]):
                s.emit(f"oc = oc - {float(eps[t, kx])!r} * x{kx} * Fc{kx}")
            s.emit(f"tb = {'oc' if names[c] == jt.body_b else '-oc'}")
            if isinstance(jt, Revolute):
                s.emit(f"jf[i, {j}, 0] = tb.real")
                s.emit(f"jf[i, {j}, 1] = tb.imag")
                continue
            nn = s.c(1j * cmath.exp(1j * jt.direction))
            s.emit(f"nv = cm(E{names.index(jt.guide)}, {nn})")
            s.emit("nn = nv.real * tb.real + nv.imag * tb.imag")
            s.emit(f"nm[i, {pidx[j]}, 0] = nn")
            s.emit("fz = nv * nn")
            s.emit(f"jf[i, {j}, 0] = fz.real")
            s.emit(f"jf[i, {j}, 1] = fz.imag")
            PS = f"JP{j}"
            terms = []
            for kx in range(n_x):
                terms.append(f"((Mc{kx} - ({PS}.real * Fc{kx}.imag - {PS}.imag * "
                             f"Fc{kx}.real)) * x{kx}) * {float(eps[t, kx])!r}")
            s.emit(f"mom = Smo{t} - ({PS}.real * Sf{t}.imag - {PS}.imag * Sf{t}.real) - "
                   f"(0.0 + {' + '.join(terms)})")
            s.emit(f"nm[i, {pidx[j]}, 1] = {'mom' if names[c] == jt.body_b else '-mom'}")

    def _power_terms(self, nu: int):
        """The effort, its power, ``dKE/dt``, the loads' power and the balance's
        residual (:data:`FORCE_SCALARS`)."""
        s = self.s
        s.emit(f"pw = x{nu} * wd")
        s.emit(f"sc[i, 0] = x{nu}")
        s.emit("sc[i, 1] = pw")
        s.emit("sc[i, 2] = ke")
        s.emit("sc[i, 3] = lp")
        s.emit("sc[i, 4] = pw - (ke - lp)")

    # -- the function around the body ---------------------------------------------
    def _assemble(self) -> str:
        s = self.s
        ng = self.ng
        nmax = max(self.n, 2 * len(self.topo.chords), 1)
        head = [
            "# generated by analytic.kernels.codegen: do not edit",
            # numba's cache does not see a change in the helpers a kernel inlines: their
            # source's hash is part of this file, so a new helper gives a new kernel file
            f"# helpers {_helpers_hash()}",
            "import math",
            "import numpy as np",
            "from numba import njit",
            "from analytic.kernels.smallmat import (cabs, det_small, lu_det, lu_factor,",
            "                                       lu_solve, solve_small)",
            # complex products as numpy's array multiply computes them on this machine
            f"from analytic.kernels.smallmat import {complex_multiply()} as cm",
            "",
            "",
            "@njit(cache=True, error_model='numpy', nogil=True)",
            "def kernel(level, values, vel, acc, signs, PF, PC, carry, stat, statf, susp,",
            "           q, qd, qdd, theta, omega, alpha, Eo, zO, zv, za, Ao, deto, trv, jp,",
            "           jf, nm, sc):",
            "    N = values.shape[0]",
            f"    A = np.zeros(({nmax}, {nmax}))",
            f"    A2 = np.zeros(({nmax}, {nmax}))",
            f"    lu = np.zeros(({nmax}, {nmax}))",
            f"    piv = np.zeros({nmax}, np.int64)",
            f"    sb = np.zeros({nmax})",
            f"    xu = np.zeros({nmax})",
            f"    xf = np.zeros({nmax})",
            "    bad_i = -1",
            "    worst = 0.0",
            "    worst_i = 0",
            "    nsus = 0",
            "    has_prev = carry[0] > 0",
        ]
        for g in range(ng):
            head.append(f"    prev{g} = carry[{1 + g}]")
            head.append(f"    turn{g} = carry[{1 + ng + g}]")
        for k in range(len(s.pf)):
            head.append(f"    pf{k} = PF[{k}]")
        for k in range(len(s.pc)):
            head.append(f"    pc{k} = PC[{k}]")
        B = self.B
        head += [
            # scratch of the position stages: poses, angles, kept temporaries
            f"    sE = np.empty(({CHUNK}, {B}), np.complex128)",
            f"    sO = np.empty(({CHUNK}, {B}), np.complex128)",
            f"    sT = np.empty(({CHUNK}, {B}))",
            f"    sX = np.empty(({CHUNK}, {max(len(self.persist), 1)}), np.complex128)",
            f"    for s0 in range(0, N, {CHUNK}):",
            f"        s1 = min(N, s0 + {CHUNK})",
        ] + self.stage_lines + [
            "        for i in range(s0, s1):",
        ] + ["            " + ln for ln in self._load_lines()] + [
            "            wd = vel[i if vel.shape[0] > 1 else 0]",
            "            ad = acc[i if acc.shape[0] > 1 else 0]",
        ]
        tail = [
            "    carry[0] = 1.0 if has_prev else 0.0",
        ]
        for g in range(ng):
            tail.append(f"    carry[{1 + g}] = prev{g}")
            tail.append(f"    carry[{1 + ng + g}] = turn{g}")
        tail += [
            "    stat[0] = bad_i",
            "    stat[1] = worst_i",
            "    stat[2] = nsus",
            "    statf[0] = worst",
            "",
        ]
        return "\n".join(head + ["    " + ln for ln in s.lines] + tail)

    def params(self) -> tuple[np.ndarray, np.ndarray]:
        return (np.array(self.s.pf or [0.0], float), np.array(self.s.pc or [0j], complex))


@functools.cache
def complex_multiply() -> str:
    """The helper for a complex product (:func:`smallmat.numpy_complex_multiply`),
    probed once per process."""
    from .probe import numpy_complex_multiply
    return numpy_complex_multiply()


def _helpers_hash() -> str:
    import hashlib
    from pathlib import Path
    here = Path(__file__).parent
    h = hashlib.sha256()
    for name in ("smallmat.py", "codegen.py"):
        h.update((here / name).read_bytes())
    return h.hexdigest()[:16]
