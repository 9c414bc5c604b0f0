"""The live swing filter's convergence rule (``live.convergence``): own sigmas, held N periods."""
import math
from types import SimpleNamespace

from gyro_char.live.convergence import Convergence
from gyro_char.live.swing_online import SwingOnline
from gyro_char.sim.config import load
from gyro_char.sim.simulator import simulate_swing
from gyro_char.swing.model import Estimate
import numpy as np
import pytest


def _est(sfe=(1e-3, 1e-4), bias=(1e-2, 1e-4), drift=(1e-6, 1e-7)):
    return SimpleNamespace(scale_factor_error=Estimate(*sfe, '1'), bias=Estimate(*bias, 'rad/s'),
                           bias_drift=Estimate(*drift, 'rad/s^2'))


def test_every_sigma_must_be_within_its_tolerance_over_the_periods():
    conv = Convergence(period_s=5.0, rel_sigma=0.25, periods=3.0)
    assert not conv.update(_est(drift=(1e-6, 1e-4)), 100.0)  # drift sigma 100 x the drift
    assert conv.unmet == ['bias_drift']
    assert not conv.update(_est(), 101.0)  # good from 101 s on ...
    assert not conv.update(_est(), 115.9)
    assert conv.update(_est(), 116.0)  # ... for three 5 s periods
    assert conv.update(_est(drift=(1e-6, 1e-4)), 117.0)  # latched until the filter restarts
    conv.reset()
    assert not conv.converged and conv.unmet


def test_a_break_restarts_the_count():
    conv = Convergence(period_s=5.0, periods=2.0)
    conv.update(_est(), 0.0)
    conv.update(_est(sfe=(1e-3, 5e-4)), 9.0)  # sfe sigma 50 %: the run of good ones breaks
    assert not conv.update(_est(), 12.0)
    assert not conv.update(_est(), 21.9)
    assert conv.update(_est(), 22.0)


def test_an_absolute_tolerance_accepts_an_estimate_near_zero():
    near_zero = _est(drift=(1e-9, 2e-8))
    assert not Convergence(5.0, periods=0.0).update(near_zero, 10.0)
    relaxed = Convergence(5.0, periods=0.0, abs_sigma={'bias_drift': 5e-8})
    assert relaxed.update(near_zero, 10.0)
    assert relaxed.tolerance('bias_drift', 1e-9) == 5e-8
    assert relaxed.tolerance('bias', 1e-2) == pytest.approx(2.5e-3)


def test_nan_estimates_never_converge():
    conv = Convergence(5.0, periods=0.0)
    assert not conv.update(_est(bias=(math.nan, math.nan)), 1.0)
    assert not conv.update(_est(), math.nan)


@pytest.mark.parametrize('preset,seconds,converged', [
    ('adis16405', 20.0, False), ('vg910', 40.0, True)])
def test_on_simulated_runs(preset, seconds, converged):
    """A MEMS gyro after 20 s (drift sigma >> drift) is not converged; a FOG after 40 s is."""
    config = load(None, preset)
    run = simulate_swing(config, duration=seconds, seed=1)
    core = SwingOnline(run.truth['swing']['period_s'])
    conv = Convergence(run.truth['swing']['period_s'])
    gyro = run.imu.channels['gyro_' + config.gyro.axis]
    for end in np.arange(1.0, seconds + 0.5, 1.0):
        a, b = np.searchsorted(run.imu.t, [end - 1.0, end])
        core.add_imu(run.imu.t[a:b], gyro[a:b])
        a, b = np.searchsorted(run.encoder.t, [end - 1.0, end])
        core.add_encoder(run.encoder.t[a:b], run.encoder.channels['encoder'][a:b])
        est = core.estimates()
        conv.update(est, end)
    assert conv.converged == converged
    assert est.converged  # the filter's own rough flag says yes to both
    drift = est.bias_drift
    if converged:
        assert drift.sigma <= 0.25 * abs(drift.value)
    else:
        assert drift.sigma > 10 * abs(run.truth['swing']['bias_drift'])
