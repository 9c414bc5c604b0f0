"""The fine-resolution line check beside the gap (``narrow_lines``)."""
from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis.narrow_lines import line_scan, narrow_lines
from gyro_char.diagnosis.spectra import model_spectrum
import numpy as np
import pytest

DT = 0.01
N_ARW = 2.4 * np.pi / 180.0 / 60.0
SIG = N_ARW / np.sqrt(DT)
N = 2 ** 18                       # 44 min at 100 Hz: segments of 2^13, 63 of them


def tone(n, f0, amp, rng):
    t = np.arange(n) * DT
    return amp * np.sin(2 * np.pi * f0 * t + rng.uniform(0, 2 * np.pi))


def test_family_wise_p_is_calibrated_on_white_noise():
    # Under the null the family-wise p of the largest bin is ~uniform: 40 records, fixed
    # seeds; about 4 below 0.1 and none below the report level are expected.
    ps = np.array([line_scan(SIG * np.random.default_rng(s).standard_normal(N), DT)['p'].min()
                   for s in range(40)])
    assert np.sum(ps < 0.1) <= 9
    assert np.sum(ps < 0.5) >= 8            # not so conservative that it never fires
    assert np.all(ps > 1e-3)


def test_a_line_the_tone_block_cannot_see_is_found_at_fine_resolution():
    # A 2 h record and a line of 0.02 of the white noise's per-sample sd (0.04 % of its power).
    n = 720000
    noise = SIG * np.random.default_rng(3).standard_normal(n)
    line = tone(n, 13.3, 0.02 * SIG, np.random.default_rng(4))
    layout = obs.static_layout(n, DT)
    with_line = obs.static_observables(noise + line, layout)['tone']
    without = obs.static_observables(noise, layout)['tone']
    # The coarse tone block's 10-15 Hz element stays within its own noise (log10 excess) ...
    assert with_line[2] < 0.1 and with_line[2] - without[2] < 0.05
    assert narrow_lines(noise, DT)['lines'] == []
    found = narrow_lines(noise + line, DT)['lines']
    # ... while the fine scan puts the line at its frequency, far beyond the report level.
    assert len(found) == 1 and abs(found[0]['frequency_hz'] - 13.3) < 0.01
    assert found[0]['p_value'] < 1e-6
    assert 'in_model' not in found[0]       # no model given


def test_the_models_own_line_is_marked_and_a_mode_is_not_a_line():
    rng = np.random.default_rng(4)
    amp = 0.3 * SIG
    x = SIG * rng.standard_normal(N) + tone(N, 21.0, amp, rng)
    base = model_spectrum(N_ARW, 0.0, DT, [])
    with_line = model_spectrum(N_ARW, 0.0, DT, [('vibration', {'freq_hz': 21.0,
                                                               'amplitude': amp})])
    assert narrow_lines(x, DT, base)['lines'][0]['in_model'] is False
    got = narrow_lines(x, DT, with_line)['lines'][0]
    assert got['in_model'] is True and got['model_excess'] > 0.5 * got['excess']
    # A broad structural mode (q 20 at 30 Hz: 1.5 Hz wide) lifts its own floor: no line.
    from scipy import signal
    b, a = signal.iirpeak(30.0, 20.0, fs=1 / DT)
    mode = signal.lfilter(b, a, 3 * SIG * rng.standard_normal(N))
    assert narrow_lines(SIG * rng.standard_normal(N) + mode, DT)['lines'] == []


def test_a_record_too_short_to_look_finer_is_skipped_not_failed():
    x = SIG * np.random.default_rng(0).standard_normal(40000)
    assert narrow_lines(x, DT) is None
    with pytest.raises(ValueError, match='too short'):
        line_scan(x, DT)


def test_the_cli_reports_the_scan_and_warns_only_of_lines_the_model_lacks(tmp_path):
    import json
    from gyro_char.cli import main
    from gyro_char.jobs.diagnose_static import line_warnings
    n = 2 ** 17                            # 22 min: segments of 2^12 against the gap's 2^11
    rng = np.random.default_rng(8)
    x = SIG * rng.standard_normal(n) + tone(n, 23.0, 2 * SIG, rng)
    csv = tmp_path / 'rec.csv'
    t = np.arange(n) * DT
    np.savetxt(csv, np.c_[t, np.rad2deg(x)], delimiter=',', header='t_s,gyro_x_dps',
               comments='', fmt='%.6f')
    out = tmp_path / 'out'
    assert main(['diagnose', '--kind', 'static', str(csv), '--out', str(out), '--repeats', '5',
                 '--check', '0', '--quiet']) == 0
    d = json.loads((out / 'diagnosis.json').read_text())
    scan = d['narrow_lines']
    assert scan['segment'] == 4096 and scan['lines']
    top = scan['lines'][0]
    # The tone the gap selected is the model's own: reported, marked, not warned about.
    assert d['selected_effects'][:1] == ['vibration']
    assert abs(top['frequency_hz'] - 23.0) < 0.05 and top['in_model'] is True
    assert not any('narrow line' in w for w in d.get('warnings', []))
    # Without the model the same line is warned about, with its frequency.
    bare = narrow_lines(x, DT, model_spectrum(N_ARW, 0.0, DT, []))
    warned = line_warnings(bare)
    assert len(warned) == 1 and 'narrow line at 23.000' in warned[0]
    assert bare['lines'][0]['in_model'] is False


def test_the_search_names_a_line_only_the_fine_scan_sees_and_leaves_noise_alone():
    from gyro_char.diagnosis import engine, static_expect
    n = 720000                             # 2 h: the gap alone finds this record consistent
    noise = SIG * np.random.default_rng(5).standard_normal(n) + 0.003
    line = tone(n, 13.3, 0.02 * SIG, np.random.default_rng(6))
    found = []
    for x in (noise, noise + line):
        problem = static_expect.closed_form_problem([x], DT, twins=16, seed=3)
        found.append(engine.run(problem, repeats=16, seed=3, max_steps=2))
    clean, lined = found
    assert clean.selected_effects == [] and clean.verdict['code'] == 'consistent'
    assert lined.baseline_gap < lined.null_gap['q95']       # invisible to the gap ...
    assert lined.selected_effects == ['vibration']          # ... named by the line scan
    step = lined.steps[-1]
    assert step['evidence']['check'] == 'narrow_lines'
    assert abs(step['params']['freq_hz'] - 13.3) < 0.002
    assert step['params']['amplitude'] == pytest.approx(0.02 * SIG, rel=0.25)
    assert lined.verdict['code'] == 'explained' and '13.300 Hz' in lined.verdict['text']


def test_a_record_whose_level_changes_along_it_makes_no_lines(monkeypatch):
    # White noise whose second half is low-passed (a filter switched on mid-record): above
    # the corner, half the segments hold all the power, the Welch bins have fewer degrees
    # of freedom than the segment count says, and their tails would pass for lines.
    from scipy import signal
    from gyro_char.diagnosis import narrow_lines as nl
    b, a = signal.butter(2, 5.0, fs=1 / DT)
    records = []
    for seed in range(1, 7):
        x = SIG * np.random.default_rng(seed).standard_normal(N)
        x[N // 2:] = signal.lfilter(b, a, x[N // 2:])
        records.append(x)
    assert sum(len(narrow_lines(x, DT)['lines']) for x in records) == 0
    # Without the segments' own dispersion, the same records report lines.
    monkeypatch.setattr(nl, 'dispersion', lambda seg, p, size: np.ones(p.size))
    assert sum(len(narrow_lines(x, DT)['lines']) for x in records) >= 1


def test_the_twin_path_reports_the_scan_against_its_own_baseline():
    from gyro_char.diagnosis import static
    from gyro_char.jobs.diagnose_static import narrow
    n = 2 ** 17
    rng = np.random.default_rng(9)
    x = SIG * rng.standard_normal(n) + tone(n, 17.0, 2 * SIG, rng)
    problem = static.static_problem([x], DT, channel='gyro_x')
    assert problem.expect is None and problem.lines is None     # no naming on this path
    scan = narrow(x, DT, None, problem, [])
    assert abs(scan['lines'][0]['frequency_hz'] - 17.0) < 0.01
    assert scan['lines'][0]['in_model'] is False
