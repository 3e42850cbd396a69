"""The exact one-degree-of-freedom equation of motion, from the solver's kinematics.

For a linkage with one degree of freedom and the coordinate ``q`` of one joint (the
integrated coordinate: the driver joint of the :class:`analytic.Linkage` passed here),
every velocity is ``v = v_q q'`` and every acceleration ``a = v_q q'' + a_qq q'^2``,
where ``v_q`` and ``a_qq`` are the velocity and acceleration the solver returns at unit
input rate and zero input acceleration (its exact vector-loop solution; no finite
differences).  Lagrange's equation is then

    M(q) q'' + C(q) q'^2 = Q(q, q', t),
    M = sum_b m_b |v_Gb,q|^2 + I_b w_b,q^2          (generalized inertia, kg m^2 or kg)
    C = sum_b m_b v_Gb,q . a_Gb,qq + I_b w_b,q a_b,qq   (= M'(q) / 2)
    Q = sum F . v_P,q  (virtual power of gravity, loads, springs, dampers, motors).

Joint coordinates: revolute ``theta_b - theta_a`` (rad), prismatic ``s`` (m); their
coefficients ``x_q`` come from the same solution.  Potential energy: gravity
``-m g . r_G`` and springs ``k (L - L0)^2 / 2``; constant loads, motors and dampers
enter through their work, integrated with the motion (:mod:`.integrate`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import LinkageError, MissingMassError
from ..mechanism import Revolute
from ..motion_spec import JointSpring, PointDamper, PointSpring
from ..planar import cplx


@dataclass
class Coefficients:
    """Kinematic coefficients at N values of the integrated coordinate.

    ``kin`` is the solver's :class:`analytic.Kinematics` at unit rate and zero
    acceleration; ``x, x_q, x_qq`` ``(N, J)`` are every joint's coordinate (wrapped
    to the solver's angles; see :func:`unwrap_to`) and its first two derivatives with
    respect to ``q``.
    """

    kin: object
    x: np.ndarray
    x_q: np.ndarray
    x_qq: np.ndarray


def coefficients(lk, q) -> Coefficients:
    """The solver's kinematics at ``q`` (scalar or ``(N,)``) with ``q' = 1, q'' = 0``."""
    q = np.atleast_1d(np.asarray(q, float))
    chain = _chain(lk)
    if chain is not None and chain.applies(q):  # parallelogram windows: exact identities
        kin = chain.kinematics(q)
    else:
        kin = lk.kinematics(q, 1.0, 0.0, on_singular="flag")
    rev, ia, ib = _revolute_pairs(lk)
    x, x_q, x_qq = (arr[:, ib] - arr[:, ia] for arr in (kin.theta, kin.omega, kin.alpha))
    for k in np.flatnonzero(~rev):
        x[:, k], x_q[:, k], x_qq[:, k] = kin.slider(lk.mech.joints[k].name)
    # the integrated coordinate is q itself (the solver may wrap its angle)
    k = [j.name for j in lk.mech.joints].index(lk.mech.driver.joint)
    x[:, k] = q
    return Coefficients(kin, x, x_q, x_qq)


def _chain(lk):
    """The linkage's parallelogram chain (:mod:`.parallelograms`) or None, kept in its
    ``derived``: the solver's own rates are ill-conditioned at a window's change point."""
    d = lk.derived
    if "free_chain" not in d:
        from .parallelograms import Chain
        d["free_chain"] = Chain.of(lk)
    return d["free_chain"]


def _massive(lk):
    """The moving bodies with mass or inertia: indices, centres of mass (body frame,
    complex), masses and inertias, kept in the linkage's ``derived``."""
    got = lk.derived.get("free_massive")
    if got is None:
        rows = [(b, cplx(body.com), body.mass or 0.0, body.inertia or 0.0)
                for b, body in enumerate(lk.mech.bodies)
                if b != lk.topo.ground and (body.mass or body.inertia)]
        bs, com, mass, inertia = zip(*rows, strict=True) if rows else ((), (), (), ())
        got = lk.derived["free_massive"] = (np.array(bs, int), np.array(com, complex),
                                            np.array(mass, float), np.array(inertia, float))
    return got


def _size(lk) -> float:
    """The mechanism's size (m), kept in the linkage's ``derived``."""
    got = lk.derived.get("free_size")
    if got is None:
        from ..mechanism import mechanism_size
        got = lk.derived["free_size"] = mechanism_size(lk.mech.bodies) or 1.0
    return got


def _revolute_pairs(lk):
    """Per joint: revolute or not, and the body indices of its two bodies (revolute;
    0 for a prismatic joint), cached on the linkage."""
    got = getattr(lk, "_free_pairs", None)
    if got is None:
        names = lk.topo.body_names
        rev = np.array([isinstance(j, Revolute) for j in lk.mech.joints])
        pairs = [(names.index(j.body_a), names.index(j.body_b)) if r else (0, 0)
                 for j, r in zip(lk.mech.joints, rev, strict=True)]
        ia, ib = (np.array(c, int) for c in zip(*pairs, strict=True))
        got = lk._free_pairs = (rev, ia, ib)
    return got


def unwrap_to(x: np.ndarray, ref: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """Revolute joint angles ``x`` moved by whole turns to lie within pi of ``ref``."""
    two_pi = 2.0 * math.pi
    d = np.where(revolute, np.round((ref - x) / two_pi) * two_pi, 0.0)
    return x + d


def check_masses(mech) -> None:
    """Free motion needs every moving body's mass and inertia."""
    missing = [b.name for b in mech.moving_bodies if b.mass is None]
    if missing:
        raise MissingMassError(f"free motion needs the mass and inertia of every moving "
                               f"body; missing for {missing}", mech.source)


@dataclass
class Terms:
    """The equation's terms at N states (SI): inertia ``M``, ``C``, the generalized
    force ``Q``, the powers of the motors, constant loads and gravity, the dissipated
    power (>= 0), and the potential energy of gravity and springs."""

    M: np.ndarray
    C: np.ndarray
    Q: np.ndarray
    motor_power: np.ndarray
    load_power: np.ndarray
    damper_power: np.ndarray
    potential: np.ndarray
    kinetic: np.ndarray


#: Ends of a spring or damper closer than this fraction of the mechanism's size coincide
#: (the same pin, computed through two bodies: rounding leaves ~1e-16 of the size): the
#: element's line, and so its direction, is undefined there.
COINCIDENT = 1e-12


class CoincidentEndsError(LinkageError):
    """A spring with a non-zero free length whose ends coincide: its force has a size
    but no direction."""


def _point_pair(kin, el, size: float = 1.0):
    """Positions and unit-rate velocities (complex) of a spring's or damper's ends,
    its length L and its rate per unit q, L_q.  Where the ends coincide the direction
    ``u`` is 0 (a zero-length spring or a damper there exerts no force; see
    :func:`_check_coincident` for a spring that should push)."""
    ra, va, _ = kin.point_c(el.body_a, el.point_a)
    rb, vb, _ = kin.point_c(el.body_b, el.point_b)
    d = rb - ra
    L = np.abs(d)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = np.where(L > COINCIDENT * size, d / L, 0.0)
    L_q = u.real * (vb - va).real + u.imag * (vb - va).imag
    return L, L_q, u


def _check_coincident(mech, s, L, size: float) -> None:
    if s.free_length and np.any(L <= COINCIDENT * size):
        raise CoincidentEndsError(
            f"{mech.source + ': ' if mech.source else ''}spring {s.body_a}.{s.point_a} - "
            f"{s.body_b}.{s.point_b}: its ends coincide (length 0) while its free length is "
            f"{s.free_length:g} m, so its force ({s.stiffness * s.free_length:.6g} N) has "
            "no direction; give free_length = 0 or ends that do not meet")


def terms(lk, co: Coefficients, x: np.ndarray, qd, t) -> Terms:
    """The equation's terms at states ``(q, q', t)`` whose coefficients are ``co``;
    ``x`` ``(N, J)`` are the joint coordinates, unwrapped (for torsional springs)."""
    mech = lk.mech
    kin = co.kin
    qd = np.asarray(qd, float)
    N = co.x.shape[0]
    g = complex(*mech.gravity)
    M, C, Qg = np.zeros(N), np.zeros(N), np.zeros(N)
    V = np.zeros(N)
    bs, com, mass, inertia = _massive(lk)
    if len(bs):  # every body at once: sum over bodies of the same per-body terms
        r = kin.E[:, bs] * com
        w, al = kin.omega[:, bs], kin.alpha[:, bs]
        rG = kin.zO[:, bs] + r
        vG = kin.zv[:, bs] + 1j * w * r
        aG = kin.za[:, bs] + (1j * al - w * w) * r
        M += (mass * (vG.real ** 2 + vG.imag ** 2) + inertia * w ** 2).sum(axis=1)
        C += (mass * (vG.real * aG.real + vG.imag * aG.imag) + inertia * w * al).sum(axis=1)
        Qg += (mass * (g.real * vG.real + g.imag * vG.imag)).sum(axis=1)
        V -= (mass * (g.real * rG.real + g.imag * rG.imag)).sum(axis=1)
    Ql = np.zeros(N)
    for ld in mech.loads:
        b = lk.body_index(ld.body)
        F = complex(*ld.force)
        vP = (kin.point_c(b, ld.point)[1] if ld.point is not None else kin.com_c(b)[1])
        Ql += F.real * vP.real + F.imag * vP.imag + ld.torque * kin.omega[:, b]
    fm = mech.motion
    jidx = {j.name: k for k, j in enumerate(mech.joints)}
    Qs, Qd, Qm = np.zeros(N), np.zeros(N), np.zeros(N)
    for s in (fm.springs if fm else ()):
        if isinstance(s, PointSpring):
            L, L_q, _ = _point_pair(kin, s, _size(lk))
            _check_coincident(mech, s, L, _size(lk))
            ext = L - s.free_length
        else:
            k = jidx[s.joint]
            ext, L_q = x[:, k] - s.free_value, co.x_q[:, k]
        Qs -= s.stiffness * ext * L_q
        V += 0.5 * s.stiffness * ext ** 2
    for d in (fm.dampers if fm else ()):
        L_q = (_point_pair(kin, d, _size(lk))[1] if isinstance(d, PointDamper)
               else co.x_q[:, jidx[d.joint]])
        Qd -= d.coefficient * L_q ** 2 * qd
    for mo in (fm.motors if fm else ()):
        Qm += np.array([mo.at(ti) for ti in np.broadcast_to(t, (N,))]) * co.x_q[:, jidx[mo.joint]]
    T = 0.5 * M * qd ** 2
    return Terms(M, C, Qg + Ql + Qs + Qd + Qm, Qm * qd, Ql * qd, -Qd * qd, V, T)


@dataclass(frozen=True)
class ElementLoad:
    """A force element's action on one body at N states, as the solver's kinetostatics
    takes a :class:`analytic.mechanism.Load`: ``force`` (N,) complex (N, world axes) at
    the body point ``point`` (None: the centre of mass), ``torque`` (N,) N m ccw."""

    body: str
    point: str | None
    force: np.ndarray
    torque: np.ndarray


def element_forces(lk, co: Coefficients, x: np.ndarray, qd, t) -> list[ElementLoad]:
    """The springs', dampers' and motors' actions at N states ``(co, x, q', t)`` (``x``
    ``(N, J)`` unwrapped joint coordinates; ``qd``, ``t`` scalars or ``(N,)``) as loads
    on the moving bodies, in a fixed order (the same bodies and points at every state)."""
    mech, kin = lk.mech, co.kin
    fm = mech.motion
    N = co.x.shape[0]
    qd = np.broadcast_to(np.asarray(qd, float), (N,))
    t = np.broadcast_to(np.asarray(t, float), (N,))
    zero = np.zeros(N)
    loads = []
    jidx = {j.name: k for k, j in enumerate(mech.joints)}
    joint_effort: dict[str, np.ndarray] = {}
    for el in fm.springs + fm.dampers:
        if isinstance(el, PointSpring | PointDamper):
            L, L_q, u = _point_pair(kin, el, _size(lk))
            tension = (el.stiffness * (L - el.free_length) if isinstance(el, PointSpring)
                       else el.coefficient * L_q * qd)
            F = tension * u  # pulls b towards a, a towards b
            loads.append(ElementLoad(el.body_a, el.point_a, F, zero))
            loads.append(ElementLoad(el.body_b, el.point_b, -F, zero))
        else:
            k = jidx[el.joint]
            e = (-el.stiffness * (x[:, k] - el.free_value) if isinstance(el, JointSpring)
                 else -el.coefficient * co.x_q[:, k] * qd)
            joint_effort[el.joint] = joint_effort.get(el.joint, 0.0) + e
    for mo in fm.motors:
        e = np.array([mo.at(ti) for ti in t])
        joint_effort[mo.joint] = joint_effort.get(mo.joint, 0.0) + e
    for name, e in joint_effort.items():
        loads += _joint_effort_loads(lk, kin, mech.joint(name), e, zero)
    return [ld for ld in loads if ld.body != mech.ground]


def _joint_effort_loads(lk, kin, jt, e: np.ndarray, zero: np.ndarray):
    """An effort ``e`` (N,) on a joint's coordinate as loads: a couple on body_b and the
    opposite on body_a (revolute), or a force along the line on the slider point and
    the opposite on the guide at the same world point (prismatic)."""
    if isinstance(jt, Revolute):
        return [ElementLoad(jt.body_b, None, zero + 0j, e),
                ElementLoad(jt.body_a, None, zero + 0j, -e)]
    gb = lk.body_index(jt.guide)
    u = kin.E[:, gb] * complex(math.cos(jt.direction), math.sin(jt.direction))
    P = kin.point_c(jt.slider, jt.point)[0]
    O = kin.point_c(jt.guide, jt.origin)[0]
    F = e * u
    r = P - O
    return [ElementLoad(jt.slider, jt.point, F, zero),
            ElementLoad(jt.guide, jt.origin, -F, -(r.real * F.imag - r.imag * F.real))]
