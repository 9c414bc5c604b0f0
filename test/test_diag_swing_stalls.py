"""The swing stall screen, the sample interval of stalled stamps and the delay's stall form."""
from gyro_char.diagnosis import engine, swing as diag_swing
from gyro_char.diagnosis.swing_baseline import sample_interval, sample_numbers
from gyro_char.diagnosis.swing_stalls import (
    destalled, MIN_SAMPLES, stall_latency, stall_screen, stall_warning, twin_latency)
from gyro_char.errors import InputError
from gyro_char.records import Recording
from gyro_char.sim import simulator
from gyro_char.sim.config import BenchConfig
from gyro_char.sim.effects.timing import in_order, increasing
import numpy as np
import pytest

DT = 1e-3
JITTER = 2e-5        # s: the preset's white stamp jitter


def stalled(n=300_000, every=3.0, length=0.05, drain=6, seed=0):
    """
    Return (stamps, produced instants) of a 1 kHz IMU read by a host that stalls.

    Stalls of ``length`` s every ``every`` s (from 1 s): no sample is read inside one; after
    it the reader catches up ``drain`` samples a step, every sample kept.
    """
    rng = np.random.default_rng(seed)
    p = DT * np.arange(n) + JITTER * rng.standard_normal(n)
    r, count = read_late(p, every, length, drain)
    return r, p, count


def read_late(p, every, length, drain, first=1.0):
    """Return the stamps of instants ``p`` read by a host stalling as ``stalled``'s, and count."""
    r = p.copy()
    starts = np.arange(first, p[-1], every)
    ends = starts + length
    j = np.searchsorted(starts, p, side='right') - 1
    inside = (j >= 0) & (p < ends[np.maximum(j, 0)])
    r[inside] = ends[j[inside]]
    for k in range(1, p.size):                  # the catch-up: r_k >= r_(k-1) + dt / drain
        if r[k] < r[k - 1] + DT / drain:
            r[k] = r[k - 1] + DT / drain
    return r, starts.size


def test_stalled_stamps_number_as_kept_and_give_the_true_interval():
    # 100 stalls of 50 ms over 300 s: 5000 samples stamped late, none lost. Counted as
    # losses (the gap's length over the median step) the interval came out ~1.6 % short.
    r, p, count = stalled()
    k = sample_numbers(r)
    assert k[-1] == r.size - 1
    assert sample_interval(r) == pytest.approx(DT, rel=1e-7)
    naive = np.concatenate([[0.0], np.cumsum(np.maximum(np.round(np.diff(r) / DT), 1.0))])
    assert (r[-1] - r[0]) / naive[-1] < 0.99 * DT


def test_the_screen_flags_stalls_and_measures_their_latency():
    r, p, count = stalled()
    s = stall_screen(r)
    assert s['tested'] and s['flagged']
    assert s['samples_lost'] == 0 and s['gaps'] == count and s['stalls'] == count
    late = r - p
    truth_share = np.mean(late > 0.5 * DT)
    assert s['late_share'] == pytest.approx(truth_share, rel=0.05)
    assert s['mean_latency_s'] == pytest.approx(np.mean(np.where(late > 0.5 * DT, late, 0)),
                                                rel=0.05)
    assert s['max_latency_s'] == pytest.approx(0.05, rel=0.05)
    w = stall_warning('record 2', s)
    assert w.startswith('record 2: the IMU stamps show 100 stalls') and 'imu_stalls' in w


def test_dropped_samples_and_plain_jitter_are_not_flagged():
    rng = np.random.default_rng(4)
    n = 200_000
    t = DT * np.arange(n) + JITTER * rng.standard_normal(n)
    clean = stall_screen(t)
    assert clean['tested'] and not clean['flagged']
    assert clean['gaps'] == 0 and clean['samples_lost'] == 0 and clean['late_share'] < 1e-4
    # 40 gaps of 60 samples each, lost: the stamps resume on the grid.
    drop = np.concatenate([np.arange(s, s + 60) for s in range(3000, 200_000, 5000)])
    lossy = stall_screen(np.delete(t, drop))
    assert lossy['tested'] and not lossy['flagged']
    assert lossy['gaps'] == 40 and lossy['samples_lost'] == drop.size
    assert stall_warning('record 1', lossy) is None
    assert sample_interval(np.delete(t, drop)) == pytest.approx(DT, rel=1e-9)


def test_too_short_or_broken_stamps_are_not_tested_and_say_why():
    short = stall_screen(DT * np.arange(MIN_SAMPLES - 1))
    assert not short['tested'] and 'need 64' in short['reason']
    t = DT * np.arange(1000)
    t[500] = np.nan
    assert not stall_screen(t)['tested']
    frozen = stall_screen(np.zeros(1000))
    assert not frozen['tested'] and 'do not advance' in frozen['reason']
    assert stall_warning('record 1', frozen) is None


def test_the_latency_trace_is_the_backlog_and_moves_the_stamps_back_to_their_instants():
    r, p, count = stalled()
    lat = stall_latency(r)
    truth = r - p
    back = truth > 6 * np.median(np.abs(truth))
    # Where the stamps are late the trace is their latency to the stamps' own jitter (the
    # grid is fitted, the jitter stays in both); elsewhere it is nothing.
    assert np.max(np.abs(lat[back] - truth[back])) < 6 * JITTER
    assert np.count_nonzero(lat[~back]) < 0.002 * r.size
    fixed = destalled(Recording(r, {'gyro_x': np.zeros(r.size)}), lat)
    assert np.max(np.abs(fixed.t - p)) < 6 * JITTER
    clean = DT * np.arange(200_000) + JITTER * np.random.default_rng(1).standard_normal(200_000)
    assert stall_latency(clean) is None
    rec = Recording(clean, {'gyro_x': np.zeros(clean.size)})
    assert destalled(rec, None) is rec


def test_a_latency_that_is_not_a_drained_backlog_gives_no_trace():
    # Two thirds of the run late by 3 ms of wandering latency beside the stalls (a playout
    # buffer): cut at the stamps' jitter the trace flickers on and off, and the stamps moved
    # back by it would leave their order, so there is none (the run is diagnosed as before).
    r, p, count = stalled()
    q = r.copy()
    q[100_000:] += 0.003 + 3e-4 * np.random.default_rng(3).standard_normal(q.size - 100_000)
    q = in_order(q, 0.1 * DT)
    assert stall_screen(q)['flagged'] and stall_latency(q) is None


def test_the_trace_goes_where_the_twin_swings_at_the_records_phase():
    # A record whose swing is 1.3 s into its cycle at its first sample: the twin (phase 0 at
    # its time 0) gets the latency 1.3 s later in its samples, the stall at the same angle.
    period, n = 5.0, 60_000
    t = DT * np.arange(n)
    lat = np.zeros(n)
    lat[20_000:20_050] = np.linspace(0.05, 0.001, 50)
    w = 2 * np.pi / period
    angle = 0.3 * np.sin(w * (t + 1.3)) + 0.002
    out = twin_latency(lat, t + lat, t, angle, period, 0.0, 0.0)
    assert np.flatnonzero(out)[0] == 20_000 + 1300
    assert out[21_300:21_350] == pytest.approx(lat[20_000:20_050])
    # Within half a period: 3.7 s into the cycle is 1.3 s before it.
    out = twin_latency(lat, t + lat, t, 0.3 * np.sin(w * (t + 3.7)), period, 0.0, 0.0)
    assert np.flatnonzero(out)[0] == 20_000 - 1300


def test_the_stall_form_puts_the_trace_into_the_stamps_in_order():
    cfg = BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': 1000.0}})
    n = 20_000
    trace = np.zeros(n)
    trace[5000:5050] = np.maximum(0.04 - DT * (1 - 1 / 8) * np.arange(50), 0.0)  # 8 a step
    fx = [{'name': 'time_delay', 'params': {'delay_s': 0.0, 'stall_gain': 1.0}}]
    plain = simulator.simulate_swing(cfg, duration=20.0, seed=3, channels=('gyro_x',))
    run = simulator.simulate_swing(cfg, duration=20.0, seed=3, channels=('gyro_x',),
                                   effects=fx, stamp_latency=trace)
    late = run.imu.t - plain.imu.t
    assert np.all(np.diff(run.imu.t) > 0)
    # The values are the samples' own; only the stamps move, by the trace, and no further
    # than the reader's order needs (a tenth of an interval) where the jitter crowds them.
    assert np.array_equal(run.imu.channels['gyro_x'], plain.imu.channels['gyro_x'])
    assert np.max(np.abs(late - trace)) < 0.1 * DT
    assert np.max(np.abs(late[5050:])) < 0.1 * DT
    with pytest.raises(InputError, match='stamp-latency trace'):
        simulator.simulate_swing(cfg, duration=2.0, seed=3, channels=('gyro_x',), effects=fx)


def test_in_order_holds_a_stamp_back_only_until_its_own_latency_allows():
    s = np.array([0.0, 1.0, 1.05, 1.1, 3.0, 4.0, 4.01, 5.0])
    assert in_order(s, 0.1) == pytest.approx([0.0, 1.0, 1.1, 1.2, 3.0, 4.0, 4.1, 5.0])
    # ``increasing`` carries each lengthened step into every later stamp.
    assert increasing(s, 0.1)[-1] == pytest.approx(5.19)


def _config():
    return BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': 1000.0},
                                                 'encoder': {'rate_hz': 1000.0}})


def _stalled_run(seed=5, duration=120.0):
    run = simulator.simulate_swing(_config(), duration=duration, seed=seed,
                                   channels=('gyro_x',))
    r, _ = read_late(run.imu.t, 2.0, 0.1, 8, first=0.7)
    return Recording(r, run.imu.channels, 'stalled'), run.encoder


def test_a_stalled_run_is_calibrated_on_its_instants_and_its_stall_form_closes_the_gap():
    imu, enc = _stalled_run()
    problem = diag_swing.swing_records_problem([(imu, enc, 5.0)])
    base = problem.context[0]
    assert base.stamp_latency is not None and base.stamp_latency.max() > 0.09
    # Calibrated at the samples' own instants: N is the preset gyro's, not raised by the
    # bursts (on the stamps as read it came out 2.2 times higher).
    preset_n = BenchConfig.from_preset('adis16405').noise['gyro_x']['N']
    assert base.N == pytest.approx(preset_n, rel=0.05)
    forms = [a for s in problem.spaces if s.name == 'time_delay' for a in s.alternatives
             if [p.name for p in a.params] == ['stall_gain']]
    assert len(forms) == 1
    stall = [('time_delay', {'delay_s': 0.0, 'lag_s': 0.0, 'stall_gain': 1.0})]
    before = engine.evaluate_model(problem, [], repeats=4, seed=3).gap
    after = engine.evaluate_model(problem, stall, repeats=4, seed=3).gap
    # 37.0 -> 3.6 at the trace's own gain (the record's 60 stalls of 100 ms read as the
    # twins' on 120 s: a gain of 1.05 gives 2.1; the search finds it).
    assert before > 10.0 and after < 0.15 * before
    run = simulator.simulate_swing(_config(), duration=120.0, seed=5, channels=('gyro_x',))
    clean = diag_swing.swing_records_problem([(run.imu, run.encoder, 5.0)])
    assert clean.context[0].stamp_latency is None
    # A model fitted on a stalling run, frozen and checked on a run without stalls (the
    # held-out check): its stall form carries that run's latency, none.
    same = engine.evaluate_model(clean, stall, repeats=4, seed=3).gap
    assert same == pytest.approx(engine.evaluate_model(clean, [], repeats=4, seed=3).gap,
                                 rel=1e-6)
    assert not any(p.name == 'stall_gain' for s in clean.spaces for a in s.alternatives
                   for p in a.params)
