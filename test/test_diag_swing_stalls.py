"""The swing stall screen and the sample interval of stalled stamps: a backlog is not a loss."""
from gyro_char.diagnosis.swing_baseline import sample_interval, sample_numbers
from gyro_char.diagnosis.swing_stalls import MIN_SAMPLES, stall_screen, stall_warning
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
    r = p.copy()
    starts = np.arange(1.0, p[-1], every)
    ends = starts + length
    j = np.searchsorted(starts, p, side='right') - 1
    inside = (j >= 0) & (p < ends[np.maximum(j, 0)])
    r[inside] = ends[j[inside]]
    for k in range(1, n):                       # the catch-up: r_k >= r_(k-1) + dt / drain
        if r[k] < r[k - 1] + DT / drain:
            r[k] = r[k - 1] + DT / drain
    return r, p, starts.size


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
