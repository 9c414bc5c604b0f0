"""Band-limited flicker (bias_instability with corner_hz): simulator, closed form, search."""
from gyro_char.diagnosis import expected, static
from gyro_char.diagnosis.spectra import model_spectrum
from gyro_char.errors import InputError
from gyro_char.sim import noise_gen
from gyro_char.sim.effects import EFFECTS
import numpy as np
import pytest

DT = 0.01
BASE = static.StaticBaseline(N=7e-4, bias=0.0, drift=0.0, lsb=0.0, dt=DT)


def test_default_is_the_unbounded_flicker_bit_for_bit():
    n = 5000
    plain = static.simulate_twin(BASE, n, [('bias_instability', {'B': 3e-4})], 4)
    zero = static.simulate_twin(BASE, n, [('bias_instability', {'B': 3e-4, 'corner_hz': 0.0})],
                                4)
    assert np.array_equal(plain, zero)
    assert np.array_equal(noise_gen.flicker(n, np.random.default_rng(1)),
                          noise_gen.flicker(n, np.random.default_rng(1), corner=0.0))
    f = np.linspace(0.01, 50.0, 300)
    a = model_spectrum(7e-4, 0.0, DT, [('bias_instability', {'B': 3e-4})]).one_sided(f)
    b = model_spectrum(7e-4, 0.0, DT, [('bias_instability', {'B': 3e-4, 'corner_hz': 0.0})])
    assert np.array_equal(a, b.one_sided(f))
    with pytest.raises(InputError):
        EFFECTS['bias_instability'](B=1e-4, corner_hz=-1.0).check()


# The closed-form Allan variance against the generator's exact discrete AVAR, with and without
# a corner: test_diag_power_law.py (every slope).


def test_corner_keeps_the_floor_at_long_tau_and_bends_the_spectrum_above_it():
    n, b_coef, fc = 2 ** 20, 1e-4, 0.2
    g = expected.grids(n, DT)
    flat = expected.avar(model_spectrum(0.0, 0.0, DT, [('bias_instability', {'B': b_coef})]), g)
    spec = model_spectrum(0.0, 0.0, DT, [('bias_instability', {'B': b_coef,
                                                               'corner_hz': fc})])
    band = expected.avar(spec, g)
    long_ = g.m * DT > 50.0 / fc
    assert np.all(np.abs(band[long_] / flat[long_] - 1.0) < 0.05)
    assert band[0] < 0.2 * flat[0]     # the high-frequency part of the flicker is gone
    # 1/f below the corner, 1/f^2 well above it (the PSD's log-log slope).
    f = np.array([0.002, 0.004, 5.0, 10.0])
    s = spec.one_sided(f)
    assert np.log(s[1] / s[0]) / np.log(2.0) == pytest.approx(-1.0, abs=0.03)
    assert np.log(s[3] / s[2]) / np.log(2.0) == pytest.approx(-2.0, abs=0.1)


def _problem(effects, seed, n=180000):
    from gyro_char.diagnosis import static_expect
    base = static.StaticBaseline(N=7e-4, bias=0.0, drift=0.0, lsb=0.05 * np.pi / 180.0, dt=DT)
    x = static.simulate_twin(base, n, effects, seed)
    return static_expect.closed_form_problem([x], DT, twins=5, seed=seed + 1)


def _diagnose(effects, seed, n=180000):
    from gyro_char.diagnosis import engine
    return engine.run(_problem(effects, seed, n), repeats=5, seed=seed + 1, max_steps=2)


def test_search_finds_the_corner_of_a_band_limited_flicker():
    # Half an hour of the simulator's band-limited flicker, 1/f^2 above 0.3 Hz: without the
    # corner the catalogue named a Gauss-Markov process (free correlation time) for it.
    from gyro_char.diagnosis import engine
    truth = [('bias_instability', {'B': 1e-3, 'corner_hz': 0.3})]
    d = _diagnose(truth, seed=31)
    assert d.selected_effects[:1] == ['bias_instability']
    fit = dict(d.model)['bias_instability']
    assert 0.15 < fit['corner_hz'] < 0.6, fit
    assert abs(fit['B'] / 1e-3 - 1.0) < 0.3, fit
    # A strong long-memory process scatters far beyond the baseline's twins: the right model
    # ends near the gap the true model itself scores on this record (~10 here), not near 1;
    # its own twins score ~5 on average, and this realization lies twice as far out.
    at_truth = engine.evaluate_model(_problem(truth, seed=31), truth, repeats=5, seed=32).gap
    assert d.final_gap < 1.1 * at_truth < d.baseline_gap
    assert d.final_gap > 2.0 * d.null_gap['q95']


def test_unbounded_flicker_and_gauss_markov_keep_their_names():
    # The extra freedom must not steal a first-order Gauss-Markov process (flat below its
    # corner, which no flicker is) nor invent a corner for the plain 1/f flicker.
    d = _diagnose([('gauss_markov', {'sigma': 3e-3, 'tau_s': 2.0, 'order': 1.0})], seed=33)
    assert d.selected_effects[:1] == ['gauss_markov']
    d = _diagnose([('bias_instability', {'B': 1e-3})], seed=35)
    assert d.selected_effects[:1] == ['bias_instability']
    fit = dict(d.model)['bias_instability']
    # No corner, or one where this flicker is below a tenth of the white noise (above
    # B^2 / (0.2 pi N^2) = 3.2 Hz), i.e. none the record can see.
    assert fit['corner_hz'] == 0.0 or fit['corner_hz'] > 3.2, fit
