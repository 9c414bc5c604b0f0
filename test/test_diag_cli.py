# gyro-char diagnose: the diagnosis.json contract (DESIGN.md section 4), plots, bad input.
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
    assert (out / 'diagnosis_gyro_x.png').stat().st_size > 10_000
    # The model fitted on the first record explains the withheld one too.
    h = d['holdout']
    assert h['final_gap'] < 0.6 * h['baseline_gap']
    assert [e['name'] for e in h['effects']] == d['selected_effects']


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


def test_diagnose_swing_writes_the_contract_and_names_the_delay(tmp_path):
    rec = tmp_path / 'rec'
    cfg = tmp_path / 'g200.yaml'
    cfg.write_text('gyro: {rate_hz: 200.0}\n')
    assert main(['simulate', 'swing', '--out', str(rec), '--duration', '60', '--config',
                 str(cfg), '--effect', 'time_delay:delay_s=0.00185', '--quiet']) == 0
    out = tmp_path / 'out'
    rc = main(['diagnose', '--kind', 'swing', str(rec / 'recording.mcap'), '--out', str(out),
               '--repeats', '5', '--quiet'])
    assert rc == 0
    d = json.loads((out / 'diagnosis.json').read_text())
    assert CONTRACT <= set(d)
    assert d['kind'] == 'swing' and d['channel'] == 'gyro_x'
    assert d['where'][0]['observable'] == 'quadrature'
    assert d['where'][0]['range'] == pytest.approx([0.2, 0.2], rel=1e-4)
    assert d['where'][0]['range_unit'] == 'Hz'
    # On one period and amplitude a delay and g-sensitivity leave the same residual: the two
    # lead the ranking (in either order) and the step says so, with the separating run.
    pair = {'time_delay', 'g_sensitivity'}
    assert {r['effect'] for r in d['ranking'][:2]} == pair
    assert d['selected_effects'][0] in pair
    assert set(d['ambiguous'][0]['effects']) == pair
    assert 'second period' in d['ambiguous'][0]['separating_run']
    assert d['baseline']['period_s']['value'] == pytest.approx(5.0, rel=1e-3)
    assert (out / 'diagnosis_gyro_x.png').stat().st_size > 10_000
