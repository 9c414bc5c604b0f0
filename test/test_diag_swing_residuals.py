"""
The swing residual streams: the samples two runs share, and what a geometry keeps.

Ground truth: numpy's intersection and least squares, and the observables of the same streams
on a geometry that has kept nothing (what is kept must never change a number).
"""
from gyro_char.diagnosis import swing_obs
from gyro_char.diagnosis.swing_residuals import (
    column_normal, common_samples, Residuals, residuals, solve_columns)
from gyro_char.records import ENCODER_CHANNEL
from gyro_char.sim import simulator
from gyro_char.sim.config import BenchConfig
import numpy as np
import pytest

PERIOD = 5.0


def _run(seed: int, effects=()) -> Residuals:
    cfg = BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': 200.0},
                                                'stand': {'period_s': PERIOD}})
    run = simulator.simulate_swing(cfg, duration=40.0, seed=seed, effects=effects,
                                   channels=('gyro_x',))
    return residuals(run.imu.t, run.imu.channels['gyro_x'], run.encoder.t,
                     run.encoder.channels[ENCODER_CHANNEL], PERIOD)


def _fresh(res: Residuals) -> Residuals:
    keep_g, keep_e = np.arange(res.r.size), np.arange(res.r_e.size)
    out = res.take(keep_g, keep_e)
    assert out.memo == {}
    return out


def _equal(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(np.asarray(a[k]), np.asarray(b[k]), err_msg=k)


def test_common_samples_are_numpys_intersection_and_skip_it_when_equal():
    a = np.arange(100, 200)
    ia, ib = common_samples(a, a.copy())
    np.testing.assert_array_equal(ia, np.arange(a.size))
    np.testing.assert_array_equal(ib, ia)
    b = np.r_[99, np.arange(101, 150), np.arange(151, 201)]      # one shifted edge, one hole
    ia, ib = common_samples(a, b)
    _, wa, wb = np.intersect1d(a, b, return_indices=True)
    np.testing.assert_array_equal(ia, wa)
    np.testing.assert_array_equal(ib, wb)
    np.testing.assert_array_equal(a[ia], b[ib])
    assert ia.size == 98


def test_solve_columns_with_a_kept_normal_matrix_is_least_squares():
    rng = np.random.default_rng(3)
    x = np.linspace(0.0, 1.0, 5000)
    cols = [np.ones_like(x), x, np.sin(40.0 * x) * 1e3, x * x]
    y = rng.standard_normal(x.size)
    want = np.linalg.lstsq(np.array(cols).T, y, rcond=None)[0]
    assert solve_columns(cols, y) == pytest.approx(want, rel=1e-9, abs=1e-12)
    normal = column_normal(np.array(cols))
    for y2 in (y, rng.standard_normal(x.size)):
        want = np.linalg.lstsq(np.array(cols).T, y2, rcond=None)[0]
        assert solve_columns(cols, y2, normal) == pytest.approx(want, rel=1e-9, abs=1e-12)


def test_what_a_geometry_keeps_never_changes_the_observables():
    # The clean run's geometry decomposes its own streams, then another run's (the pseudo-
    # twins' use): each time equal to a geometry that kept nothing.
    res = _run(5)
    other = _run(6, effects=['time_delay:delay_s=0.001'])
    lay = swing_obs.layout(swing_obs.PSD_BINS, res.dt, PERIOD)
    own = swing_obs.raw_parts(res, lay)
    assert {'harmonics', 'columns', 'z1_e', 'phase_bins', 'angles', 'rate_bins'} <= set(res.memo)
    _equal(own, swing_obs.raw_parts(_fresh(res), lay))
    n, ne = min(res.r.size, other.r.size), min(res.r_e.size, other.r_e.size)
    geo = res.take(np.arange(n), np.arange(ne))
    first = swing_obs.raw_parts(geo, lay, other.r[:n], other.r_e[:ne])
    again = swing_obs.raw_parts(geo, lay, other.r[:n], other.r_e[:ne])
    _equal(first, swing_obs.raw_parts(_fresh(geo), lay, other.r[:n], other.r_e[:ne]))
    _equal(first, again)
    # And the other streams' parts are theirs, not the kept geometry's own.
    assert not np.allclose(first['harm'], swing_obs.raw_parts(geo, lay)['harm'])
