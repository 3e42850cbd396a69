"""One comparison helper shared by the tests and the report (cf. Drake's CompareMatrices).

Errors are normalised by the peak magnitude of the reference quantity over the
sampled cycle, so zero crossings do not blow them up.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np


@dataclass(frozen=True)
class Comparison:
    """The diagnostic of one quantity: where and how far the test values stray.

    Attributes
    ----------
    quantity : str
        What was compared, e.g. ``"rocker.alpha"`` or ``"B.force"``.
    max_abs : float
        Largest absolute error over the samples (SI units of the quantity; for vectors
        the Euclidean norm of the error).
    peak : float
        Peak magnitude of the reference over the samples.
    normalised : float
        ``max_abs / peak`` (``inf`` when the test values hold NaN).
    at : float
        The input value (deg or m) where ``max_abs`` occurs.
    tolerance : float
        The normalised tolerance applied.
    passed : bool
    """

    quantity: str
    max_abs: float
    peak: float
    normalised: float
    at: float
    tolerance: float
    passed: bool

    def as_dict(self) -> dict:
        return asdict(self)

    def __str__(self) -> str:
        verdict = "pass" if self.passed else "FAIL"
        return (f"{self.quantity}: max error {self.max_abs:.3g} at {self.at:.6g} "
                f"({self.normalised:.3g} of peak {self.peak:.4g}; tolerance "
                f"{self.tolerance:.1g}) {verdict}")


def compare(quantity: str, reference, test, at, tolerance: float,
            peak_floor: float = 0.0) -> Comparison:
    """Compare ``test`` with ``reference`` sample by sample.

    Parameters
    ----------
    reference, test
        Arrays ``(N,)`` or ``(N, k)`` (vectors per sample, e.g. forces ``(N, 2)``).
    at
        ``(N,)`` input values labelling the samples (deg or m).
    tolerance
        Allowed ``max error / peak``.
    peak_floor
        Lower bound for the peak (a quantity identically zero is compared with this
        scale instead of its own round-off).
    """
    ref = np.asarray(reference, float)
    tst = np.asarray(test, float)
    if ref.shape != tst.shape:
        raise ValueError(f"{quantity}: reference shape {ref.shape} != test shape {tst.shape}")
    err = ref - tst
    if err.ndim > 1:
        err = np.linalg.norm(err.reshape(len(err), -1), axis=1)
        mag = np.linalg.norm(ref.reshape(len(ref), -1), axis=1)
    else:
        err, mag = np.abs(err), np.abs(ref)
    peak = max(float(np.max(mag)) if mag.size else 0.0, peak_floor)
    if not np.all(np.isfinite(err)):
        k = int(np.flatnonzero(~np.isfinite(err))[0])
        return Comparison(quantity, float("inf"), peak, float("inf"), float(at[k]),
                          tolerance, False)
    k = int(np.argmax(err)) if err.size else 0
    max_abs = float(err[k]) if err.size else 0.0
    norm = max_abs / peak if peak > 0 else (0.0 if max_abs == 0 else float("inf"))
    return Comparison(quantity, max_abs, peak, norm, float(np.asarray(at)[k]) if err.size
                      else float("nan"), tolerance, bool(norm <= tolerance))
