"""The free motion's equation of motion at one state, in compiled scalar code.

Not imported: :mod:`analytic.free_motion.compiled` reads this file's text and loads it
as a kernel module (:func:`analytic.kernels.cache._load`: its on-disk numba cache lives
under ``$XVAL_KERNEL_CACHE``; :mod:`analytic.kernels.background` compiles it in another
process).  One function for every structure: the structure is data (``iv, fv, cv``,
laid out by :class:`analytic.free_motion.compiled.Layout`), so it is compiled once per
machine, not once per mechanism.

``kernel`` evaluates, for one configuration ``q`` with the bodies' poses and unit-rate
kinematics in ``theta .. za`` (``(1, B)``: the fused kernel's outputs, or the
parallelogram chain's identities computed here when ``mode`` is 1), the same sums as
:func:`analytic.free_motion.dynamics.terms`, term by term in the same order:

    out = [M, C, Q, motor_power, load_power, damper_power, V, T, q'']

and the joint coordinates ``x`` (unwrapped to ``ref`` by whole turns), ``x_q``, ``x_qq``
(written when ``new`` is 1; with ``new`` 0 the ``x`` passed in are used as they are).
"""

import math

import numpy as np
from numba import njit

# header of ``iv``: counts and section offsets (see Layout)
H_J, H_K, H_NB, H_NL, H_NS, H_ND, H_NM = 0, 1, 2, 3, 4, 5, 6
H_OJ, H_OB, H_OL, H_OS, H_OD, H_OM, H_OC = 7, 8, 9, 10, 11, 12, 13
H_FB, H_FL, H_FS, H_FD, H_FC = 14, 15, 16, 17, 18
H_CB, H_CL, H_CS, H_CD, H_CC = 19, 20, 21, 22, 23


@njit(cache=True, error_model="numpy", nogil=True)
def _chain(q, iv, fv, cv, theta, omega, alpha, E, zO, zv, za):
    """The parallelogram chain's kinematics at ``q`` (unit rate, zero acceleration), as
    :meth:`analytic.free_motion.parallelograms.Chain.kinematics`."""
    B = theta.shape[1]
    o, of, oc = iv[H_OC], iv[H_FC], iv[H_CC]
    drv, nwin = iv[o], iv[o + 1]
    sign = fv[of]
    for b in range(B):
        theta[0, b] = 0.0
        omega[0, b] = 0.0
        alpha[0, b] = 0.0
    theta[0, drv] = sign * q
    omega[0, drv] = sign
    for w in range(nwin):
        x1, k3, x2, k1 = iv[o + 2 + 4 * w], iv[o + 3 + 4 * w], iv[o + 4 + 4 * w], iv[o + 5 + 4 * w]
        theta[0, x1] = theta[0, k3] + fv[of + 1 + 2 * w]
        theta[0, x2] = theta[0, k1] + fv[of + 2 + 2 * w]
        omega[0, x1] = omega[0, k3]
        omega[0, x2] = omega[0, k1]
    for b in range(B):
        E[0, b] = np.exp(1j * theta[0, b])
        zO[0, b] = 0.0
        zv[0, b] = 0.0
        za[0, b] = 0.0
    p = o + 2 + 4 * nwin
    nnz, ncol = iv[p], iv[p + 1]
    rows, cols, starts = p + 2, p + 2 + nnz, p + 2 + nnz + ncol
    for c in range(ncol):
        lo = iv[starts + c]
        hi = iv[starts + c + 1] if c + 1 < ncol else nnz
        s0 = 0j
        s1 = 0j
        s2 = 0j
        for i in range(lo, hi):
            b = iv[rows + i]
            v = cv[oc + i]
            w = omega[0, b]
            s0 += E[0, b] * v
            s1 += (1j * w * E[0, b]) * v
            s2 += ((1j * alpha[0, b] - w * w) * E[0, b]) * v
        col = iv[cols + c]
        zO[0, col] = s0
        zv[0, col] = s1
        za[0, col] = s2


@njit(cache=True, error_model="numpy", nogil=True)
def _joints(q, ref, iv, theta, omega, alpha, sq, sqd, sqdd, x, xq, xqq):
    """Every joint's coordinate (unwrapped to ``ref``) and its two derivatives in q."""
    J, o = iv[H_J], iv[H_OJ]
    two_pi = 2.0 * math.pi
    for k in range(J):
        rev, a, b = iv[o + 3 * k], iv[o + 3 * k + 1], iv[o + 3 * k + 2]
        if rev:
            x[k] = theta[0, b] - theta[0, a]
            xq[k] = omega[0, b] - omega[0, a]
            xqq[k] = alpha[0, b] - alpha[0, a]
        else:
            x[k], xq[k], xqq[k] = sq[0, a], sqd[0, a], sqdd[0, a]
    x[iv[H_K]] = q
    for k in range(J):
        if iv[o + 3 * k]:
            x[k] = x[k] + np.round((ref[k] - x[k]) / two_pi) * two_pi


@njit(cache=True, error_model="numpy", nogil=True)
def _velocity(E, zv, omega, b, c):
    """Unit-rate velocity of the body-frame point ``c`` of body ``b``."""
    r = E[0, b] * c
    return zv[0, b] + 1j * omega[0, b] * r


@njit(cache=True, error_model="numpy", nogil=True)
def _pair(E, zO, zv, omega, ba, pa, bb, pb, tiny):
    """A spring's or damper's length and its rate per unit q (as ``_point_pair``: ends
    nearer than ``tiny`` (m) coincide, and the direction is 0 there)."""
    ra = E[0, ba] * pa
    rb = E[0, bb] * pb
    d = (zO[0, bb] + rb) - (zO[0, ba] + ra)
    va = zv[0, ba] + 1j * omega[0, ba] * ra
    vb = zv[0, bb] + 1j * omega[0, bb] * rb
    L = abs(d)
    u = d / L if L > tiny else 0j
    dv = vb - va
    return L, u.real * dv.real + u.imag * dv.imag


@njit(cache=True, error_model="numpy", nogil=True)
def _bodies(iv, fv, cv, theta, omega, alpha, E, zO, zv, za, out):
    """Inertia, C, gravity's generalized force and potential (per-body sums)."""
    nb, ob, fb, cb = iv[H_NB], iv[H_OB], iv[H_FB], iv[H_CB]
    gr, gi = fv[0], fv[1]
    M = 0.0
    C = 0.0
    Qg = 0.0
    V = 0.0
    for i in range(nb):
        b = iv[ob + i]
        m, inertia = fv[fb + 2 * i], fv[fb + 2 * i + 1]
        r = E[0, b] * cv[cb + i]
        w, al = omega[0, b], alpha[0, b]
        rG = zO[0, b] + r
        vG = zv[0, b] + 1j * w * r
        aG = za[0, b] + (1j * al - w * w) * r
        M += m * (vG.real ** 2 + vG.imag ** 2) + inertia * w ** 2
        C += m * (vG.real * aG.real + vG.imag * aG.imag) + inertia * w * al
        Qg += m * (gr * vG.real + gi * vG.imag)
        V += m * (gr * rG.real + gi * rG.imag)
    out[0], out[1], out[6] = M, C, -V
    return Qg


@njit(cache=True, error_model="numpy", nogil=True)
def _elements(qd, eff, iv, fv, cv, omega, E, zO, zv, x, xq, out):
    """Loads, springs, dampers and motors: their generalized forces and powers."""
    Ql = 0.0
    ol, fl, cl = iv[H_OL], iv[H_FL], iv[H_CL]
    for i in range(iv[H_NL]):
        b = iv[ol + i]
        vP = _velocity(E, zv, omega, b, cv[cl + i])
        Ql += fv[fl + 3 * i] * vP.real + fv[fl + 3 * i + 1] * vP.imag \
            + fv[fl + 3 * i + 2] * omega[0, b]
    Qs = 0.0
    os_, fs, cs = iv[H_OS], iv[H_FS], iv[H_CS]
    for i in range(iv[H_NS]):
        kind, ba, bb, k = iv[os_ + 4 * i], iv[os_ + 4 * i + 1], iv[os_ + 4 * i + 2], \
            iv[os_ + 4 * i + 3]
        stiff, free = fv[fs + 2 * i], fv[fs + 2 * i + 1]
        if kind == 0:
            L, L_q = _pair(E, zO, zv, omega, ba, cv[cs + 2 * i], bb, cv[cs + 2 * i + 1],
                           fv[2])
            ext = L - free
            if L <= fv[2] and free != 0.0:
                Qs = np.nan  # a pushing spring with no direction: the numpy path says so
        else:
            ext, L_q = x[k] - free, xq[k]
        Qs -= stiff * ext * L_q
        out[6] += 0.5 * stiff * ext ** 2
    Qd = 0.0
    od, fd, cd = iv[H_OD], iv[H_FD], iv[H_CD]
    for i in range(iv[H_ND]):
        kind, ba, bb, k = iv[od + 4 * i], iv[od + 4 * i + 1], iv[od + 4 * i + 2], \
            iv[od + 4 * i + 3]
        if kind == 0:
            L_q = _pair(E, zO, zv, omega, ba, cv[cd + 2 * i], bb, cv[cd + 2 * i + 1],
                        fv[2])[1]
        else:
            L_q = xq[k]
        Qd -= fv[fd + i] * L_q ** 2 * qd
    Qm = 0.0
    om = iv[H_OM]
    for i in range(iv[H_NM]):
        Qm += eff[i] * xq[iv[om + i]]
    out[3], out[4], out[5] = Qm * qd, Ql * qd, -Qd * qd
    return Ql, Qs, Qd, Qm


@njit(cache=True, error_model="numpy", nogil=True)
def kernel(mode, new, q, qd, eff, ref, iv, fv, cv, theta, omega, alpha, E, zO, zv, za,
           sq, sqd, sqdd, x, xq, xqq, out):
    """The equation's terms at ``(q, q')`` with motor efforts ``eff``; see the module."""
    if new:
        if mode == 1:
            _chain(q, iv, fv, cv, theta, omega, alpha, E, zO, zv, za)
        _joints(q, ref, iv, theta, omega, alpha, sq, sqd, sqdd, x, xq, xqq)
    Qg = _bodies(iv, fv, cv, theta, omega, alpha, E, zO, zv, za, out)
    Ql, Qs, Qd, Qm = _elements(qd, eff, iv, fv, cv, omega, E, zO, zv, x, xq, out)
    M = out[0]
    out[2] = Qg + Ql + Qs + Qd + Qm
    out[7] = 0.5 * M * qd ** 2
    out[8] = (out[2] - out[1] * qd ** 2) / M
