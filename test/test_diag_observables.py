# Observables and the gap of the sim-to-real diagnosis, against closed forms on synthetic data.
from gyro_char.diagnosis import gap as diag_gap
from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis import static as diag_static
import numpy as np
from scipy import signal

DT = 0.01


def test_acf_of_moving_average_matches_theory():
    rng = np.random.default_rng(1)
    x = signal.lfilter([0.5, 0.5], [1.0], rng.standard_normal(2 ** 16))
    acf = obs.autocorrelation(x)
    assert abs(acf[0] - 0.5) < 0.02          # MA(2): rho1 = 1/2, zero beyond
    assert np.all(np.abs(acf[1:]) < 0.02)


def test_adev_block_follows_white_noise_line():
    rng = np.random.default_rng(2)
    n_arw = 7e-4
    x = n_arw / np.sqrt(DT) * rng.standard_normal(2 ** 16)
    lay = obs.static_layout(x.size, DT)
    o = obs.static_observables(x, lay)
    tau = lay.coords['adev']
    expected = np.log10(n_arw / np.sqrt(tau))
    assert np.all(np.abs(o['adev'][:8] - expected[:8]) < 0.03)   # well-averaged short taus
    # PSD: one-sided 2 N^2 for white rate noise of density N (the lowest bins hold only a few
    # Welch frequencies, hence the looser bound there)
    err = np.abs(o['psd'] - np.log10(2 * n_arw ** 2))
    assert np.all(err[:5] < 0.2) and np.all(err[5:] < 0.05)


def test_tone_found_at_its_frequency_and_not_in_white_noise():
    rng = np.random.default_rng(3)
    t = np.arange(2 ** 15) * DT
    x = rng.standard_normal(t.size)
    assert obs.detected_tones(x, DT).size == 0
    f = obs.detected_tones(x + 0.3 * np.sin(2 * np.pi * 19.3 * t), DT)
    assert f.size >= 1 and abs(f[0] - 19.3) < 0.1


def test_broad_peak_finds_a_wide_mode_and_nothing_in_monotone_spectra():
    rng = np.random.default_rng(13)
    n = 2 ** 20
    white = rng.standard_normal(n)
    # A mode at 28 Hz of width ~3 Hz (q ~ 9): no narrow peak, a bump 10x over the white floor.
    r, th = np.exp(-np.pi * 3.0 * DT), 2 * np.pi * 28.0 * DT
    mode = signal.lfilter([1.0], [1, -2 * r * np.cos(th), r * r], rng.standard_normal(n))
    mode *= 1.0 / np.std(mode)
    f_b = obs.broad_peak(obs.welch_psd(white + mode, DT))
    assert f_b is not None and abs(f_b - 28.0) < 1.5
    assert obs.narrow_lines(white + mode, DT)[0].size == 0
    flicker = np.cumsum(rng.standard_normal(n)) * 0.01           # a falling spectrum
    lowpassed = signal.lfilter([0.25] * 4, [1.0], white)           # a falling spectrum
    for x in (white, white + flicker, lowpassed, np.diff(white)):  # np.diff: a rising one
        assert obs.broad_peak(obs.welch_psd(x, DT)) is None


def test_drift_block_sees_a_warm_up_but_not_a_line():
    rng = np.random.default_rng(4)
    n = 2 ** 15
    t = np.arange(n) * DT
    lay = obs.static_layout(n, DT)
    w = rng.standard_normal(n) * 0.01
    line = obs.static_observables(w + 1e-3 * t, lay)['drift']
    warm = obs.static_observables(w + 0.05 * np.exp(-t / 20.0), lay)['drift']
    assert np.all(np.abs(line) < 5e-3)
    assert warm[0] > 0.02


def test_drift_windows_are_disjoint_shells_nearly_uncorrelated_on_white_noise():
    # Nested windows (the first 1/64, 1/32, ... of the record) correlate up to 0.7 on white
    # noise, so one chance excursion at the start moved the whole block (a clean record was
    # named a warm-up); disjoint shells do not.
    n = 2 ** 16
    win = obs.drift_windows(n)
    assert win[0][0] == 0 and win[-1][1] == n // 2
    assert all(a[1] == b[0] for a, b in zip(win, win[1:]))
    t = np.arange(n) - (n - 1) / 2.0
    forms = []
    for a, b in win:
        c = np.zeros(n)
        c[a:b] = 1.0 / (b - a)
        c[n // 2:] -= 1.0 / (n - n // 2)
        c -= c.mean()
        forms.append(c - t * (t @ c) / (t @ t))         # the record minus its line
    cov = np.array(forms) @ np.array(forms).T
    corr = cov / np.sqrt(np.outer(np.diag(cov), np.diag(cov)))
    assert np.max(np.abs(corr - np.eye(len(win)))) < 0.4
    x = np.random.default_rng(6).standard_normal(n)
    x -= np.polyval(np.polyfit(np.arange(n), x, 1), np.arange(n))
    assert np.allclose(obs.drift_means(x), np.array(forms) @ x, atol=1e-12)


def test_output_step_and_baseline_fit_recover_truth():
    rng = np.random.default_rng(5)
    lsb = 0.05 * np.pi / 180
    n_arw = 7e-4
    x = np.round((n_arw / np.sqrt(DT) * rng.standard_normal(2 ** 16) + 0.01) / lsb) * lsb
    assert abs(diag_static.output_step(x) - lsb) < 1e-12
    assert diag_static.output_step(rng.standard_normal(1000)) == 0.0
    base = diag_static.fit_baseline(x, DT)
    assert abs(base.N / n_arw - 1) < 0.05
    assert abs(base.bias - 0.01) < 1e-3


def test_gap_is_about_one_for_a_draw_from_the_model_and_large_for_an_offset():
    rng = np.random.default_rng(6)
    reps = [{'a': rng.standard_normal(20)} for _ in range(40)]
    stats = diag_gap.sim_stats(reps)
    same = {'a': rng.standard_normal(20)}
    assert 0.6 < diag_gap.gap(same, stats) < 1.5
    shifted = {'a': same['a'] + np.r_[np.zeros(10), 5 * np.ones(10)]}
    assert diag_gap.gap(shifted, stats) > 3
    where = diag_gap.locate(diag_gap.zscores(shifted, stats),
                            {'a': np.c_[np.arange(20), np.arange(20) + 1.0]}, {'a': 'u'})
    assert where[0]['observable'] == 'a' and where[0]['range'][0] >= 9
    assert where[0]['excess'] > 3
    null = diag_gap.null_gaps([stats])
    assert null.size == 40 and 0.7 < np.median(null) < 1.4


def test_gap_yardstick_stops_an_effect_from_winning_by_adding_scatter():
    rng = np.random.default_rng(7)
    base = diag_gap.sim_stats([{'a': rng.standard_normal(10)} for _ in range(20)])
    noisy = diag_gap.sim_stats([{'a': 10 * rng.standard_normal(10)} for _ in range(20)])
    real = {'a': np.full(10, 4.0)}
    # In its own scatter the noisy model looks better; in the baseline's it does not.
    assert diag_gap.gap(real, noisy) < diag_gap.gap(real, base)
    assert diag_gap.gap(real, noisy, base.std) > 0.9 * diag_gap.gap(real, base)


def test_observables_on_the_real_adis16405_record_match_what_is_known(adis_records):
    # Outside reference: the shared data's README (0.05 deg/s step, lag-1 autocorrelation
    # ~0.2-0.3 from the internal averaging, ARW 2.2-2.8 deg/sqrt(h) from ADEV at 1 s, a Z tone
    # near 17-21 Hz) - measured here with the diagnosis's own observables.
    from gyro_char.io import read_imu
    rec = read_imu(str(adis_records[0]), quiet=True)
    n = 2 ** 16
    for ch in ('gyro_x', 'gyro_y', 'gyro_z'):
        x = rec.channels[ch][:n]
        assert abs(diag_static.output_step(x) - 0.05 * np.pi / 180) < 1e-9
        o = obs.static_observables(x, obs.static_layout(n, rec.dt))
        assert 0.15 < o['acf'][0] < 0.3
        base = diag_static.fit_baseline(x, rec.dt)
        assert 2.1 < base.N * 180 / np.pi * 60 < 2.9        # deg/sqrt(h)
    tone = obs.detected_tones(rec.channels['gyro_z'][:n], rec.dt)
    assert tone.size and 17.0 < tone[0] < 23.0
