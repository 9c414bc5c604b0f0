"""Markov terms in the noise fit, spikes (detection, note, --despike), the new output fields."""
import json

from gyro_char.allan import spikes
from gyro_char.allan.compute import compute
from gyro_char.allan.fit import fit_result
from gyro_char.cli import main
from gyro_char.records import Recording
from gyro_char.sim.config import BenchConfig
from gyro_char.sim.noise_gen import generate
from gyro_char.sim.simulator import simulate_static
import numpy as np
import pytest

DT = 0.01


def _static(seed, effects=(), duration=3600.0, noise=None):
    noise = noise or {'N': 1e-3, 'B': 0.0, 'K': 0.0, 'Q': 0.0, 'R': 0.0}
    cfg = BenchConfig.from_preset('adis16405', {
        'gyro': {'static_rate_hz': 1.0 / DT, 'output_step': 0.0, 'jitter_s': 0.0},
        'noise': {'gyro_x': noise}})
    run = simulate_static(cfg, duration=duration, seed=seed, effects=list(effects),
                          channels=('gyro_x',))
    return Recording(run.imu.t, {'gyro_x': run.imu.channels['gyro_x']})


@pytest.mark.parametrize('seed', [1, 2])
def test_markov_term_found_with_its_correlation_time(seed):
    # 1 h at 100 Hz: white noise + a Gauss-Markov rate (sigma 0.6 mrad/s, T_c 20 s) from the
    # simulator's gauss_markov effect: one Markov term is selected, T_c within a factor 1.6
    # (8 seeds: 12.7-21.5 s with 'l1'), sigma within 30 %, N within 2 %.
    gm = {'name': 'gauss_markov', 'params': {'sigma': 6e-4, 'tau_s': 20.0, 'axis': 0.0}}
    res = compute(_static(seed, [gm]))
    fit = fit_result(res, n_boot=20, markov=2)['gyro_x']
    assert len(fit.markov) == 1, [m.to_json() for m in fit.markov]
    term = fit.markov[0]
    assert 20.0 / 1.6 < term.tau_c < 20.0 * 1.6
    assert term.sigma.value == pytest.approx(6e-4, rel=0.3) and term.sigma.resolved
    assert fit.terms['N'].value == pytest.approx(1e-3, rel=0.02)
    # the fitted model (with the Markov term) follows the curve within 1.5x (3 sd at 60 s)
    well = res.tau < 60.0
    assert np.all(np.abs(np.log(fit.model_avar(res.tau[well]) / res.avar[well, 0])) < 0.4)


@pytest.mark.parametrize('truth', [{'N': 1e-3}, {'N': 1e-3, 'K': 2e-5}], ids=['white', 'rw'])
def test_no_markov_term_where_formula_4_explains_the_record(truth):
    # Records formula (4) describes keep formula (4)'s own selection, unchanged.
    rate = generate(360_000, DT, rng=np.random.default_rng(5), **truth)
    res = compute(Recording(np.arange(rate.size) * DT, {'gyro_x': rate}))
    with_m = fit_result(res, n_boot=10, markov=2)['gyro_x']
    plain = fit_result(res, n_boot=10)['gyro_x']
    assert with_m.markov == [] and with_m.fitted == plain.fitted


def _spiky(n=200_000, count=25, seed=3):
    rng = np.random.default_rng(seed)
    rate = generate(n, DT, rng=rng, N=1e-3)
    sd = 1e-3 / np.sqrt(DT)
    where = np.sort(rng.choice(np.arange(5, n - 5, 10), count, replace=False))  # isolated
    size = rng.choice([-1.0, 1.0], count) * rng.uniform(12.0, 40.0, count) * sd
    spiky = rate.copy()
    spiky[where] += size
    return rate, spiky, where, size


def test_spikes_counted_exactly_and_their_bias_predicted():
    rate, spiky, where, size = _spiky()
    assert spikes.detect(rate, DT).count == 0
    rep = spikes.detect(spiky, DT)
    assert rep.count == where.size and np.array_equal(rep.index, where)
    assert rep.largest == pytest.approx(np.max(np.abs(size)), rel=0.1)  # + noise in e
    # the bias: white noise of density sqrt(dt sum A^2 / L) added to every tau
    m = np.array([1, 10, 100])
    tau, clean, _ = overlapping_avar_of(rate, m)
    _, dirty, _ = overlapping_avar_of(spiky, m)
    assert np.allclose(dirty - clean, rep.n_spike ** 2 / tau, rtol=0.1)
    _, fixed, _ = overlapping_avar_of(spikes.remove(spiky, rep.index), m)
    assert np.allclose(fixed, clean, rtol=0.01)


def overlapping_avar_of(x, m):
    from gyro_char.allan.kernel import overlapping_avar
    return overlapping_avar(x, DT, m=m)


def test_despike_in_the_cli_is_counted_and_never_silent(tmp_path, capsys):
    rate, spiky, where, _ = _spiky(n=60_000, count=12)
    path = tmp_path / 'spiky.csv'
    np.savetxt(path, np.column_stack([np.arange(rate.size) * DT, spiky]), delimiter=',',
               header='t_s,gyro_x_rads', comments='', fmt='%.10g')
    for despike in (False, True):
        out = tmp_path / f'out{int(despike)}'
        argv = ['allan', str(path), '--out', str(out), '--boot', '5', '--quiet',
                '--sensor-filter', 'auto', '--markov', '1'] + (['--despike'] if despike else [])
        assert main(argv) == 0
        err = capsys.readouterr().err
        assert '12 spike(s)' in err and ('replaced' in err) == despike, err
        noise = json.loads((out / 'noise.json').read_text())['channels']['gyro_x']
        assert noise['spikes']['count'] == 12 and noise['spikes']['removed'] == despike
        assert noise['sensor_filter']['kind'] == 'none'
        assert noise['sensor_filter']['source'] == 'auto' and isinstance(noise['markov'], list)
        assert set(noise) >= {'N', 'B', 'K', 'Q', 'R'}
        n_fit = noise['N']['value']
        if despike:
            assert n_fit == pytest.approx(1e-3, rel=0.02)
        else:  # the spikes' white noise is in N: sqrt(1 + (N_spike / N)^2)
            assert n_fit > 1.05e-3


def test_bad_sensor_filter_is_a_usage_error(tmp_path, capsys):
    assert main(['allan', str(tmp_path / 'missing.csv'), '--sensor-filter', 'gauss:3',
                 '--out', str(tmp_path / 'o'), '--quiet']) == 2
    err = capsys.readouterr().err.strip()
    assert 'sensor filter' in err and len(err.splitlines()) == 1
