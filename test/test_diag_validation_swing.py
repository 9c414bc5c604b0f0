# The swing validation harness (bench/validate_diagnosis_swing.py): its effect shapes are what
# it says they are, and its report counts top-1, ambiguity and false alarms as documented.
import bench_script
import numpy as np
import pytest


def _harness():
    return bench_script.load('validate_diagnosis_swing')


SHORT = {'duration': 60.0, 'rate_hz': 200.0}


@pytest.mark.parametrize('samples', [0.23, 0.61, 2.4])
def test_lagrange_delay_is_the_stated_delay(samples):
    h = _harness()
    dt, f = 1.0 / 200.0, 1.0 / h.PERIOD
    t = np.arange(int(60.0 / dt)) * dt
    x = np.cos(2 * np.pi * f * t)
    _, y, _, _ = h.lagrange_delay(t, x, None, None, None, None, samples * dt)
    m = slice(10, None)
    a = np.linalg.lstsq(np.c_[np.cos(2 * np.pi * f * t[m]), np.sin(2 * np.pi * f * t[m])],
                        y[m], rcond=None)[0]
    delay = np.arctan2(a[1], a[0]) / (2 * np.pi * f)
    assert delay / dt == pytest.approx(samples, rel=0.01)


def test_encoder_shapes_differ_from_the_catalogue():
    h = _harness()
    imu0, enc0 = h.make_record([], 11, **SHORT)
    _, enc = h.make_record([('encoder_cyclic_error', 0)], 11, **SHORT)
    err = enc.channels['encoder'] - enc0.channels['encoder']
    phi = enc0.channels['encoder']
    # 1st + 3rd harmonic on 1000 lines (the catalogue: 1st + 2nd on 2048).
    cols = np.c_[np.sin(1000 * phi), np.cos(1000 * phi), np.sin(3000 * phi), np.cos(3000 * phi)]
    c = np.linalg.lstsq(cols, err, rcond=None)[0]
    assert np.hypot(c[0], c[1]) == pytest.approx(5e-5, rel=1e-6)
    assert np.hypot(c[2], c[3]) == pytest.approx(2e-5, rel=1e-6)
    imu1, enc1 = h.make_record([('timestamp_jitter', 1)], 11, **SHORT)
    d = enc1.t - enc0.t
    assert np.array_equal(imu1.t, imu0.t)
    assert np.abs(d).max() <= 3e-4 and np.std(d) == pytest.approx(3e-4 / np.sqrt(3), rel=0.05)


def test_report_counts_top1_ambiguity_and_false_alarms(capsys):
    h = _harness()

    def row(truth, selected, detected=True, ambiguous=()):
        return {'mode': 'single', 'truth': truth, 'label': '', 'seed': 1, 'detected': detected,
                'selected': selected, 'ambiguous': list(ambiguous), 'shrink': 0.8,
                'shrink_excess': 0.9}
    rows = [row(['time_delay'], ['time_delay']),
            row(['time_delay'], ['g_sensitivity'], ambiguous=('g_sensitivity', 'time_delay')),
            row(['scale_factor_asymmetry'], ['scale_factor_asymmetry']),
            row(['scale_factor_asymmetry'], [], detected=False),
            row(['encoder_cyclic_error'], []),
            row([], []), row([], ['vibration'])]
    h.report('single', rows)
    out = capsys.readouterr().out
    assert 'detected 4/5' in out
    assert 'top-1 (first selected == truth) among detected 2/4 = 50 %' in out
    assert 'where an effect was named: right 2/3 = 67 %; nothing named' in out
    assert 'nothing named (gap left unexplained) 1' in out
    assert 'flagged ambiguous with the truth: 1' in out
    assert 'false alarms on clean records: 1/2' in out


def test_every_shape_has_one_signature_and_three_levels_the_edge_weakest():
    h = _harness()
    imu0, enc0 = h.make_record([], 11, **SHORT)
    cfg = h.BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': 200.0}})
    for name, (fn, levels) in h.shapes(200.0).items():
        assert len(levels) == 3, name
        outs = []
        for p in levels:
            out = fn(imu0.t, imu0.channels['gyro_x'], enc0.t, enc0.channels['encoder'],
                     h.stand_of(cfg), np.random.default_rng(1), **p)
            assert len(out) == 4 and out[0].size == out[1].size and out[2].size == out[3].size
            base = (imu0.channels['gyro_x'], enc0.t, enc0.channels['encoder'])
            outs.append(max(float(np.std(o - b)) for o, b in zip(out[1:], base)))
        # weak < strong, and the edge (15 min at 1 kHz) below the weak level (60 s).
        assert outs[2] < outs[0] < outs[1], (name, outs)


def test_held_out_without_its_file_says_so(monkeypatch, capsys):
    h = _harness()
    assert {'b', 'n', 'o'} <= set(h.held_out_letters())       # found from the files
    with pytest.raises(SystemExit):
        h.main(['--held-out', 'zz', '--quick'])
    assert "invalid choice: 'zz'" in capsys.readouterr().err
    monkeypatch.setattr(h, 'HELD_OUT', 'no_such_heldout_file')
    assert h.held_out_letters() == []
    with pytest.raises(SystemExit, match='no no_such_heldout_file.py'):
        h.held_out_shapes(1000.0, 'b')


def test_extra_clean_runs_have_their_own_seeds_and_clean_only_drops_the_shapes():
    h = _harness()
    todo = list(h.cases('single', False, [11], {}, clean_extra=3))
    assert todo == [('single', [], 11)] + [('single', [], h.CLEAN_SEED0 + k) for k in range(3)]
    full = list(h.cases('two', False, [11], clean_extra=1))
    assert [c for c in full if not c[1]] == [('two', [], 11), ('two', [], h.CLEAN_SEED0)]
    assert len(full) == 2 + sum(len(levels) for _, levels in h.SHAPES.values())


def test_stand_is_the_motion_the_encoder_reads():
    # The shapes' stand(t) is the simulator's stand without its system noises: offset and
    # drift included, so an error locked to the disk stays locked over the whole run.
    h = _harness()
    from gyro_char.records import ENCODER_CHANNEL
    from gyro_char.sim import simulator
    from gyro_char.diagnosis.swing_gains import clean_config
    from gyro_char.sim.config import BenchConfig
    cfg = clean_config(BenchConfig.from_preset('adis16405'))
    assert cfg.stand.offset != 0.0 and cfg.stand.drift_rate != 0.0
    run = simulator.simulate_swing(cfg, duration=900.0, seed=3, channels=('gyro_x',))
    t = run.encoder.t[::97]
    angle, rate = h.stand_of(cfg)(t)
    assert np.max(np.abs(angle - run.encoder.channels[ENCODER_CHANNEL][::97])) < 1e-9
    t = run.encoder.t[:5000]
    angle, rate = h.stand_of(cfg)(t)
    assert np.allclose(np.gradient(angle, t), rate, atol=1e-5 * np.max(np.abs(rate)))
