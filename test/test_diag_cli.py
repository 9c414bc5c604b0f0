# gyro-char diagnose: the diagnosis.json contract (docs/design.md), plots, bad input.
import json

from gyro_char.cli import main
import numpy as np
import pytest

CONTRACT = {'kind', 'gap_metric', 'baseline_gap', 'where', 'steps', 'selected_effects',
            'final_gap', 'ranking'}


def _write_csv(path, x_dps, dt=0.01):
    t = np.arange(x_dps.size) * dt
    with open(path, 'w') as fh:
        fh.write('t_s,gyro_x_dps\n')
        for ti, xi in zip(t, x_dps):
            fh.write(f'{ti:.2f},{xi:.2f}\n')


def test_diagnose_static_finds_an_unannounced_tone_and_writes_the_contract(tmp_path):
    rng = np.random.default_rng(21)
    n = 4096
    t = np.arange(n) * 0.01
    x = 0.4 * rng.standard_normal(n) + 0.25 * np.sin(2 * np.pi * 23.0 * t + 1.0)
    x = np.round(x / 0.05) * 0.05          # the ADIS16405's 0.05 deg/s output step
    csv = tmp_path / 'rec.csv'
    _write_csv(csv, x)
    # A second record of the same sensor, withheld from the fit.
    x2 = 0.4 * rng.standard_normal(n) + 0.25 * np.sin(2 * np.pi * 23.0 * t + 2.0)
    held = tmp_path / 'held.csv'
    _write_csv(held, np.round(x2 / 0.05) * 0.05)
    out = tmp_path / 'out'
    rc = main(['diagnose', '--kind', 'static', str(csv), '--out', str(out), '--repeats', '5',
               '--holdout', str(held), '--quiet'])
    assert rc == 0
    d = json.loads((out / 'diagnosis.json').read_text())
    assert CONTRACT <= set(d)
    assert d['kind'] == 'static' and isinstance(d['gap_metric'], str)
    for w in d['where']:
        assert {'observable', 'range', 'range_unit', 'excess'} <= set(w)
        assert len(w['range']) == 2
    for s in d['steps']:
        assert {'effect', 'params', 'gap_after'} <= set(s) and isinstance(s['params'], dict)
    assert {r['effect'] for r in d['ranking']} >= {'vibration', 'internal_lowpass'}
    assert all({'effect', 'gap_after'} <= set(r) for r in d['ranking'])
    # The tone is where the gap is, and the effect that closes it.
    assert d['where'][0]['observable'] in ('tone', 'psd', 'acf')
    assert d['selected_effects'][:1] == ['vibration']
    assert abs(d['steps'][0]['params']['freq_hz'] - 23.0) < 0.3
    # ... down to what the simulation scores against itself
    assert d['final_gap'] < d['null_gap']['final_model_q95'] < d['baseline_gap']
    assert d['verdict']['code'] == 'explained' and 'vibration' in d['verdict']['text']
    assert (out / 'diagnosis_gyro_x.png').stat().st_size > 10_000
    # The selected tone makes the band's steady envelope: no band is reported.
    assert d['non_gaussian_bands'] == []
    # The model fitted on the first record explains the withheld one too.
    h = d['holdout']
    assert h['final_gap'] < 0.6 * h['baseline_gap']
    assert [e['name'] for e in h['effects']] == d['selected_effects']


def test_diagnose_static_says_which_band_is_not_gaussian(tmp_path):
    # A machine running 1 s in 5 (a tone switched on and off): its band's power comes and
    # goes, which no catalogue effect makes; the rest of the spectrum is Gaussian.
    rng = np.random.default_rng(4)
    n = 2 ** 15
    t = np.arange(n) * 0.01
    on = (np.floor(t) % 5 == 0).astype(float)
    x = 0.4 * rng.standard_normal(n) + 1.0 * on * np.sin(2 * np.pi * 31.0 * t)
    csv = tmp_path / 'rec.csv'
    _write_csv(csv, np.round(x / 0.05) * 0.05)
    out = tmp_path / 'out'
    assert main(['diagnose', '--kind', 'static', str(csv), '--out', str(out), '--repeats', '5',
                 '--check', '0', '--quiet']) == 0
    d = json.loads((out / 'diagnosis.json').read_text())
    bands = d['non_gaussian_bands']
    assert len(bands) == 1 and bands[0]['range_hz'] == pytest.approx([30.0, 35.0]), bands
    assert bands[0]['excess_kurtosis'] > bands[0]['model'] + 1.0
    assert any(w.startswith('30-35 Hz: excess kurtosis') for w in d['warnings'])


@pytest.mark.parametrize('args, message', [
    (['--kind', 'swing', '--period', '5'], 'encoder'),
    (['--kind', 'static'], 'too short'),
])
def test_diagnose_refuses_with_a_one_line_reason(tmp_path, capsys, args, message):
    csv = tmp_path / 'short.csv'
    _write_csv(csv, np.zeros(500) + 0.05 * (np.arange(500) % 3))
    rc = main(['diagnose', *args, str(csv), '--out', str(tmp_path / 'o'), '--quiet'])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and len(err.strip().splitlines()) == 1


def _swing_bag(tmp_path, name, period, seed, effect):
    cfg = tmp_path / f'{name}.yaml'
    cfg.write_text(f'gyro: {{rate_hz: 200.0}}\nstand: {{period_s: {period}}}\n')
    rec = tmp_path / name
    assert main(['simulate', 'swing', '--out', str(rec), '--duration', '60', '--config',
                 str(cfg), '--seed', str(seed), '--effect', effect, '--quiet']) == 0
    return str(rec / 'recording.mcap')


def test_diagnose_swing_two_periods_and_a_holdout_write_the_contract(tmp_path):
    # A 1.85 ms stamp delay on two runs of one gyro, at periods 5 s and 2.5 s (periods found
    # from the encoders), and a third run at 5 s withheld from the fit.
    effect = 'time_delay:delay_s=0.00185'
    runs = [_swing_bag(tmp_path, n, p, s, effect)
            for n, p, s in (('slow', 5.0, 3), ('fast', 2.5, 4), ('held', 5.0, 5))]
    out = tmp_path / 'out'
    rc = main(['diagnose', '--kind', 'swing', runs[0], runs[1], '--holdout', runs[2],
               '--out', str(out), '--repeats', '5', '--quiet'])
    assert rc == 0
    d = json.loads((out / 'diagnosis.json').read_text())
    assert CONTRACT <= set(d)
    assert d['kind'] == 'swing' and d['channel'] == 'gyro_x'
    quad = [w for w in d['where'] if w['observable'] == 'quadrature']
    assert sorted(w['record'] for w in quad) == [0, 1]
    assert sorted(w['range'][0] for w in quad) == pytest.approx([0.2, 0.4], rel=1e-3)
    assert all(w['excess'] < -5.0 and w['range_unit'] == 'Hz' for w in quad)
    # Two periods tell the delay from g-sensitivity: no ambiguity, the delay alone.
    assert d['selected_effects'] == ['time_delay'] and d['ambiguous'] == []
    assert d['ranking'][0]['effect'] == 'time_delay'
    assert d['steps'][0]['params']['delay_s'] == pytest.approx(0.00185, rel=0.25)
    # Per record: period, amplitude and the Kalman scale factor the twin replaced by the
    # pooled one.
    recs = d['per_record']
    assert [r['period_s'] for r in recs] == pytest.approx([5.0, 2.5], rel=1e-3)
    ratio = recs[1]['peak_rate_rad_s'] / recs[0]['peak_rate_rad_s']
    assert ratio == pytest.approx(2.0, rel=0.01)
    pooled = d['baseline']['pooled_scale_factor_error']['value']
    assert all(r['twin_scale_factor_error'] == pooled for r in recs)
    lo, hi = sorted(r['kalman_scale_factor_error'] for r in recs)
    assert lo <= pooled <= hi
    # A delay leaves the rates' Nyquist band alone: each run screened, none flagged.
    assert all(r['rate_nyquist']['tested'] and not r['rate_nyquist']['flagged'] for r in recs)
    assert all(r['rate_nyquist']['dof'] == 5 for r in recs) and 'warnings' not in d
    # Too short for the waveform screen's six segments of 12 periods: not tested, said why.
    assert all(not r['waveform_drift']['tested'] and 'need' in r['waveform_drift']['reason']
               for r in recs)
    # Simulated stamps carry white jitter only: no gaps, no stalls.
    assert all(r['imu_stalls']['tested'] and r['imu_stalls']['gaps'] == 0
               and not r['imu_stalls']['flagged'] for r in recs)
    # The withheld run: the model fitted on the other two shrinks its gap.
    h = d['holdout']
    assert h['final_gap'] < 0.6 * h['baseline_gap']
    assert h['baseline_gap'] > h['null_gap_q95'] > h['final_gap']
    assert [e['name'] for e in h['effects']] == ['time_delay']
    assert h['record']['rate_nyquist']['tested'] and not h['record']['rate_nyquist']['flagged']
    assert 'reason' in h['record']['waveform_drift']
    assert h['record']['imu_stalls']['tested'] and not h['record']['imu_stalls']['flagged']
    for png in ('diagnosis_gyro_x.png', 'diagnosis_gyro_x_record2.png'):
        assert (out / png).stat().st_size > 10_000


def test_diagnose_swing_refuses_a_period_count_that_matches_no_record(tmp_path, capsys):
    run = _swing_bag(tmp_path, 'r', 5.0, 3, 'time_delay:delay_s=0.001')
    rc = main(['diagnose', '--kind', 'swing', run, run, '--period', '5,2.5,1',
               '--out', str(tmp_path / 'o'), '--quiet'])
    err = capsys.readouterr().err
    assert rc == 2 and '--period' in err and len(err.strip().splitlines()) == 1
