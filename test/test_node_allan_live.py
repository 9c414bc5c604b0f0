"""AllanLive (what allan_node runs): equal to the batch path, resumable, bounded, honest."""
import resource

from gyro_char.allan.compute import compute
from gyro_char.errors import InputError
from gyro_char.live.allan_live import AllanLive
from gyro_char.live.checkpoint import load_checkpoint, save_checkpoint
from gyro_char.records import IMU_CHANNELS, Recording
import numpy as np
import pytest

DT = 1e-3


def _static(n, seed=0):
    rng = np.random.default_rng(seed)
    x = rng.normal(0.0, 0.01, (n, 6))
    x[:, 5] += 9.81
    return 1000.0 + np.arange(n) * DT, x


def _feed(live, t, x, keep=None, chunk=100):
    keep = np.ones(t.size, bool) if keep is None else keep
    for i in range(0, t.size, chunk):
        s = slice(i, i + chunk)
        live.add(t[s][keep[s]], x[s][keep[s]])


def _same_curve(a, b):
    common = np.intersect1d(a.m, b.m)
    ia, ib = np.searchsorted(a.m, common), np.searchsorted(b.m, common)
    assert common.size > 20
    assert np.array_equal(a.counts[ia], b.counts[ib])
    np.testing.assert_allclose(a.avar[ia], b.avar[ib], rtol=1e-9)


def test_gaps_and_nan_rows_pool_segments_like_the_batch_path():
    t, x = _static(60_000)
    keep = np.ones(t.size, bool)
    keep[20_000:20_050] = False
    keep[41_234] = False
    x[30_000, 2] = np.nan
    live = AllanLive(m_max=2 ** 12, feed_chunk=3000)
    _feed(live, t, x, keep)
    ok = keep & np.isfinite(x).all(axis=1)
    batch = compute(Recording(t[ok], {c: x[ok, i] for i, c in enumerate(IMU_CHANNELS)}),
                    m_max=2 ** 12)
    _same_curve(live.result(), batch)
    s = live.summary()
    assert s['gaps'] == 3 and s['segments'] == 4 and s['dropped_non_finite'] == 1
    assert s['gap_time_s'] == pytest.approx(0.052, abs=1e-6)
    assert s['samples'] == int(ok.sum())
    assert any('pooled over 4' in n for n in live.result().notes)


def test_checkpoint_resume_is_bit_for_bit(tmp_path):
    t, x = _static(30_000, seed=1)
    whole = AllanLive(m_max=2 ** 11, feed_chunk=1000)
    _feed(whole, t, x)
    first = AllanLive(m_max=2 ** 11, feed_chunk=1000)
    _feed(first, t[:17_000], x[:17_000])
    save_checkpoint(tmp_path / 'ck.npz', {'live': first.state_dict()})
    second = AllanLive(m_max=2 ** 11, feed_chunk=1000)
    second.load_state(load_checkpoint(tmp_path / 'ck.npz')['live'])
    # A source that replays what was already accumulated is not counted twice.
    _feed(second, t[16_000:], x[16_000:])
    assert second.stale == 1000
    a, b = whole.result(), second.result()
    assert a.n_samples == b.n_samples == t.size
    np.testing.assert_allclose(a.avar, b.avar, rtol=1e-12)


def test_checkpoint_of_another_setup_is_refused():
    live = AllanLive(m_max=2 ** 11)
    _feed(live, *_static(3000))
    other = AllanLive(m_max=2 ** 12)
    with pytest.raises(InputError, match='m_max'):
        other.load_state(live.state_dict())
    fixed = AllanLive(m_max=2 ** 11, rate_hz=500.0)
    with pytest.raises(InputError, match='Hz'):
        fixed.load_state(live.state_dict())


def test_rate_change_is_held_out_and_reported():
    t, x = _static(20_000, seed=2)
    live = AllanLive(m_max=2 ** 11)
    _feed(live, t, x)
    n_before = live.n_samples
    t2 = t[-1] + 2 * DT * np.arange(1, 5001)  # the sensor drops to 500 Hz
    _feed(live, t2, x[:5000])
    assert live.n_samples == n_before
    assert live.off_rate_samples >= 4900
    assert live.off_rate_hz == pytest.approx(500.0)
    assert any('500 Hz' in n for n in live.notes())
    live.reset()
    _feed(live, t2, x[:5000])
    assert live.summary()['rate_hz'] == pytest.approx(500.0)


def test_stamp_restart_starts_a_new_segment():
    t, x = _static(10_000, seed=3)
    live = AllanLive(m_max=2 ** 10)
    _feed(live, t, x)
    live.restart_stamps()
    _feed(live, t - 900.0, x)  # the publisher restarted its clock
    assert live.n_samples == 20_000 and live.segments == 2 and live.stale == 0


def test_motion_during_static_record_is_detected():
    t, x = _static(120_000, seed=4)
    k = np.arange(80_000, 80_300)
    x[k, 0] += 0.3 * np.exp(-(k - k[0]) * DT / 0.05) * np.sin(2 * np.pi * 15 * (k - k[0]) * DT)
    live = AllanLive(m_max=2 ** 12)
    _feed(live, t, x)
    s = live.summary()
    assert s['motion_events'] == 1
    assert 1079.5 <= s['motion_last_start_s'] <= 1080.0 <= s['motion_last_end_s']


def test_memory_is_bounded_short():
    """Short version of bench/bench_node_memory.py: RSS stops growing once the tail is full."""
    rng = np.random.default_rng(5)
    live = AllanLive(m_max=2 ** 14, feed_chunk=20_000)
    chunk = 20_000
    t0 = 0.0

    def feed(n_chunks):
        nonlocal t0
        for _ in range(n_chunks):
            t = t0 + np.arange(1, chunk + 1) * DT
            live.add(t, rng.normal(0.0, 0.01, (chunk, 6)))
            t0 = t[-1]

    feed(10)
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    feed(60)  # 20 more minutes at 1 kHz
    grown_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss0
    assert live.n_samples == 70 * chunk
    assert grown_kb < 20_000, f'max RSS grew by {grown_kb} kB'
