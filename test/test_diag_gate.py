"""Holds a glitch gate selects (``stale_samples:gate=G``): simulator, closed form, fit."""
from gyro_char.diagnosis import gate, static, static_expect
from gyro_char.diagnosis.engine import run
from gyro_char.diagnosis.holds import repeat_excess
from gyro_char.diagnosis.spectra import model_spectrum
from gyro_char.errors import InputError
from gyro_char.sim.effects import EFFECTS, SimContext
from gyro_char.sim.effects.timing import gated
import numpy as np
import pytest
from scipy import signal
from static_twin_base import BASE, check_twin_means, DT, LSB, N_ARW

SD = N_ARW / np.sqrt(DT)          # the per-sample white sd


def gated_holds(g_sd):
    return ('stale_samples', {'p': 0.0, 'gate': g_sd * SD})


def test_the_gate_keeps_the_last_output_while_a_sample_is_beyond_it_on_each_gyro_axis():
    with pytest.raises(InputError, match='gate'):
        EFFECTS['stale_samples'](gate=-1.0).check()
    EFFECTS['stale_samples'](gate=1.0, p=0.9).check()       # p unused with a gate
    rng = np.random.default_rng(3)
    gyro, accel = rng.standard_normal((3, 5000)), rng.standard_normal((3, 5000))
    y, a = EFFECTS['stale_samples'](gate=2.5).output(
        SimContext(config=None, kind='static', seed=3, dt=DT), gyro, accel)
    assert a is accel
    for row, x in zip(y, gyro):
        for k in range(1, x.size):                            # the definition, sample by sample
            want = x[k] if abs(x[k] - row[k - 1]) <= 2.5 else row[k - 1]
            assert row[k] == want
    assert 0.05 < np.mean(y[:, 1:] == y[:, :-1]) < 0.12     # ~7.7 % held at 2.5 sds
    # The stationary law of the chain is the input's: the variance is kept.
    z = gated(rng.standard_normal(2 ** 20), 2.8)
    assert z.var() == pytest.approx(1.0, abs=0.01)


@pytest.mark.parametrize('g_sd', [2.5, 3.6])
def test_share_correlation_and_psd_equal_the_simulators(g_sd):
    x = static.simulate_twin(BASE, 2 ** 20, [gated_holds(g_sd)], 2)
    spec = model_spectrum(N_ARW, LSB, DT, [gated_holds(g_sd)])
    holds = spec.holds
    excess, se = repeat_excess(x, LSB)           # the repeats beyond the rounding's own
    assert excess == pytest.approx(holds.p, abs=4 * se)
    u = (x - x.mean())
    rho = [np.mean(u[:-k] * u[k:]) / (holds.sigma ** 2 + LSB ** 2 / 12) for k in (1, 2, 3)]
    assert rho == pytest.approx(holds.c[1:4], abs=0.004)
    f, px = signal.welch(u, fs=1.0 / DT, nperseg=2048)
    band = (f > 0.5) & (f < 49.5)
    ratio = px[band] / spec.one_sided(f[band])
    # 2^20 samples: ~1000 segments, each bin within ~3 % (1 sd); 16 bands of 63 bins tighter.
    assert np.all(np.abs([r.mean() - 1.0 for r in np.array_split(ratio, 16)]) < 0.02)
    # Random holds of the same share take far less from the top of the band.
    random = model_spectrum(N_ARW, LSB, DT, [('stale_samples', {'p': holds.p})])
    top = f[band][-50:]
    assert np.mean(px[band][-50:]) < 0.97 * np.mean(random.one_sided(top))


def test_the_white_input_is_found_from_the_gated_outputs_level():
    for g_sd in (2.0, 2.8, 4.0, 7.0):
        sd = gate.input_sd(g_sd, 1.3)           # the gain tabulated: to its interpolation
        assert sd * gate.GateHolds(g_sd, sd).gain() == pytest.approx(1.3, rel=1e-3)
    assert gate.gate_for_share(gate.share(3.1)) == pytest.approx(3.1, rel=1e-6)


def test_expected_observables_equal_the_twins_means():
    check_twin_means([gated_holds(2.8)], seed0=60)


def test_gated_holds_are_named_stale_samples_with_their_gate():
    x = static.simulate_twin(BASE, 720000, [gated_holds(3.0)], 9)
    d = run(static_expect.closed_form_problem([x], DT, twins=8, seed=3), repeats=8, seed=3)
    assert d.selected_effects[:1] == ['stale_samples']
    fitted = d.refined['params']['stale_samples']
    assert fitted['gate'] == pytest.approx(3.0 * SD, rel=0.05)
    assert d.final_gap < 0.1 * d.baseline_gap
