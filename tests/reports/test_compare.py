"""The comparison helper: normalisation by peak, location of the worst sample, NaN."""

from __future__ import annotations

import numpy as np
import pytest

from reports.compare import compare


def test_normalised_by_peak_not_pointwise():
    x = np.linspace(0, 360, 361)
    ref = np.sin(np.radians(x))        # crosses zero: pointwise relative error would blow up
    tst = ref + 1e-4 * np.cos(np.radians(x))
    c = compare("s", ref, tst, x, 2e-4)
    assert c.passed and c.normalised == pytest.approx(1e-4, rel=1e-3)
    assert c.at in (0.0, 180.0, 360.0)


def test_vectors_use_euclidean_norm_and_fail_loudly():
    x = np.arange(4.0)
    ref = np.array([[3.0, 4.0], [0, 0], [0, 0], [0, 0]])
    tst = ref.copy()
    tst[2] = [0.03, 0.04]
    c = compare("F", ref, tst, x, 1e-3)
    assert not c.passed and c.max_abs == pytest.approx(0.05) and c.at == 2.0
    assert c.normalised == pytest.approx(0.01)
    assert "FAIL" in str(c)


def test_nan_is_a_failure_at_its_angle():
    x = np.arange(5.0)
    tst = np.ones(5)
    tst[3] = np.nan
    c = compare("q", np.ones(5), tst, x, 1.0)
    assert not c.passed and c.at == 3.0 and c.normalised == float("inf")


def test_shape_mismatch_is_an_error():
    with pytest.raises(ValueError, match="shape"):
        compare("q", np.ones(3), np.ones(4), np.arange(3.0), 1.0)
