"""Stale samples: the record's exact repeats beyond its rounding's (``holds.repeat_excess``)."""
from gyro_char.diagnosis import static
from gyro_char.diagnosis.holds import repeat_excess, REPEAT_Z
import numpy as np
import pytest

DT = 0.01
LSB = 0.05 * np.pi / 180.0
BASE = static.StaticBaseline(N=7e-4, bias=0.0, drift=0.0, lsb=LSB, dt=DT)


@pytest.mark.parametrize('fx', [[], [('internal_lowpass', {'taps': 7.0, 'stages': 2.0,
                                                           'decimation': 8.0})],
                                [('gauss_markov', {'sigma': 5e-3, 'tau_s': 0.05})]])
def test_no_excess_of_repeats_without_holds_whatever_the_correlation(fx):
    x = static.simulate_twin(BASE, 2 ** 18, fx, 3)
    share, se = repeat_excess(x, LSB)
    assert np.mean(np.diff(x) == 0.0) > 0.02          # the rounding repeats samples itself
    assert abs(share) < REPEAT_Z * se


@pytest.mark.parametrize('isolated', [0.0, 1.0])
def test_the_excess_is_the_held_share_rounded_or_not(isolated):
    fx = [('stale_samples', {'p': 0.04, 'isolated': isolated})]
    x = static.simulate_twin(BASE, 2 ** 18, fx, 3)
    share, se = repeat_excess(x, LSB)
    assert share == pytest.approx(0.04, abs=4 * se) and share > 10 * REPEAT_Z * se
    fine = static.simulate_twin(static.StaticBaseline(**{**BASE.__dict__, 'lsb': 0.0}),
                                2 ** 18, fx, 3)
    share, se = repeat_excess(fine, 0.0)
    assert share == pytest.approx(0.04, abs=4 * se)
    # A step coarser than the differences' spread cannot tell.
    assert np.isnan(repeat_excess(np.round(fine / 1e-1) * 1e-1, 1e-1)[0])


def _mixed_spectrum():
    from gyro_char.diagnosis.spectra import model_spectrum
    fx = [('internal_lowpass', {'taps': 7.0, 'stages': 2.0, 'decimation': 8.0}),
          ('gauss_markov', {'sigma': 3e-3, 'tau_s': 0.2, 'order': 1.0}),
          ('vibration', {'amplitude': 3e-3, 'freq_hz': 21.8}),
          ('rate_random_walk', {'K': 3e-5})]
    spec = model_spectrum(7e-4, 0.0, DT, fx)
    grid = spec.refine(np.linspace(0.5 / 4096, 0.5, 4096)) / DT
    return spec, grid


@pytest.mark.parametrize('p', [0.1, 0.3])
def test_runs_of_one_are_isolated_holds_and_geometric_runs_independent_ones(p):
    from gyro_char.diagnosis.holds import Holds
    spec, grid = _mixed_spectrum()
    s = spec.one_sided(grid)                   # no holds in spec: the unheld PSD
    f = np.linspace(0.01, 50.0, 500)
    sf = spec.one_sided(f)
    for general, exact in [(Holds(p, False, run=1.0), Holds(p, True)),
                           (Holds(p, False, run=1.0 / (1.0 - p)), Holds(p, False))]:
        got = general.apply(f, sf, general.terms(grid, s, spec.lines, DT), DT)
        want = exact.apply(f, sf, exact.terms(grid, s, spec.lines, DT), DT)
        np.testing.assert_allclose(got, want, rtol=1e-7)
        np.testing.assert_allclose(general.g2(f, DT), exact.g2(f, DT), rtol=1e-12)
    # Runs of 20 are neither: the same share held in runs moves the spectrum by far more.
    runs = Holds(p, False, run=20.0)
    got = runs.apply(f, sf, runs.terms(grid, s, spec.lines, DT), DT)
    assert np.max(np.abs(np.log(got / want))) > 0.2      # 0.36 at p 0.1, 1e-7 above


def test_simulated_runs_hold_the_share_and_length_and_are_found_in_the_record():
    from gyro_char.diagnosis.holds import repeat_runs
    fine = static.StaticBaseline(**{**BASE.__dict__, 'lsb': 0.0})
    x = static.simulate_twin(fine, 2 ** 18, [('stale_samples', {'p': 0.1, 'run': 20.0})], 3)
    held = np.diff(x) == 0.0
    assert held.mean() == pytest.approx(0.1, rel=0.1)
    length, share = repeat_runs(x, 0.0)
    assert length == pytest.approx(20.0, rel=0.1) and share > 0.99
    # Single-sample holds: runs of two or more are a minority of the repeats.
    y = static.simulate_twin(BASE, 2 ** 18, [('stale_samples', {'p': 0.04})], 3)
    assert repeat_runs(y, LSB)[1] < 0.5


@pytest.mark.parametrize('run', [60.0, 150.0])
def test_long_runs_take_the_cosine_transform_and_agree_with_the_lag_by_lag_sum(
        run, monkeypatch):
    from gyro_char.diagnosis import holds
    from gyro_char.diagnosis.spectra import model_spectrum
    fx = [('gauss_markov', {'sigma': 3e-3, 'tau_s': 0.2, 'order': 1.0}),
          ('vibration', {'amplitude': 3e-3, 'freq_hz': 21.8}),
          ('rate_random_walk', {'K': 3e-5}),
          ('stale_samples', {'p': 0.2, 'run': run})]
    f = np.geomspace(0.005, 50.0, 200)
    spec = model_spectrum(7e-4, LSB, DT, fx)
    assert spec.holds.lags() > holds.FFT_LAGS           # the transform's path
    fast = spec.one_sided(f)
    monkeypatch.setattr(holds, 'FFT_LAGS', 10 ** 9)
    slow = model_spectrum(7e-4, LSB, DT, fx).one_sided(f)
    # 1e-6 and 4e-6 apart (5e-5 at runs of 1000, 2e4 lags, 60 times faster).
    np.testing.assert_allclose(fast, slow, rtol=1e-4)
