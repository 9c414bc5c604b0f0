"""Streaming Allan accumulator: batch-equal sums, bounded memory, checkpoint / restore."""
from gyro_char.allan.edf import alpha_from_slope
from gyro_char.allan.kernel import overlapping_avar
from gyro_char.allan.stream import AllanAccumulator
from gyro_char.errors import InputError
from gyro_char.sim.noise_gen import generate
import numpy as np
import pytest

DT = 0.01


def _data(n, seed=0):
    rng = np.random.default_rng(seed)
    a = 0.7 + generate(n, DT, N=1e-3, B=2e-4, K=1e-4, R=1e-6, rng=rng)
    b = -2.0 + generate(n, DT, N=5e-3, Q=1e-3, rng=rng)
    return np.stack([a, b], axis=1)


def test_equals_batch_for_every_covered_tau():
    data = _data(60_000)
    acc = AllanAccumulator(DT, 2, m_max=4096, channels=('gyro_x', 'gyro_y'))
    rng = np.random.default_rng(1)
    i = 0
    while i < data.shape[0]:  # ragged chunks, some shorter than 2 m_max, some longer
        k = int(rng.integers(1, 20_000))
        acc.add(data[i:i + k])
        i += k
    res = acc.result()
    assert res.m.max() == 4096 and acc.tail.shape[0] <= 2 * 4096 + 1
    _, avar, counts = overlapping_avar(data, DT, m=res.m)
    assert counts.tolist() == res.counts.tolist()
    assert np.max(np.abs(res.avar / avar - 1.0)) < 1e-9
    assert res.channels == ('gyro_x', 'gyro_y') and res.adev_lo is not None
    assert np.all(res.adev_lo < res.adev) and np.all(res.adev < res.adev_hi)


def test_early_result_covers_only_what_exists():
    data = _data(300)
    acc = AllanAccumulator(DT, 2, m_max=1024)
    with pytest.raises(InputError, match='too few samples'):
        acc.result()
    acc.add(data[:1])
    acc.add(data[1:300])
    res = acc.result(confidence=False)
    assert res.m.max() == 147  # largest paper-grid m with 2m <= 300
    _, avar, _ = overlapping_avar(data, DT, m=res.m)
    assert np.allclose(res.avar, avar, rtol=1e-10, atol=0)


def test_checkpoint_restore_continues_identically(tmp_path):
    data = _data(20_000, seed=4)
    whole = AllanAccumulator(DT, 2, m_max=512)
    whole.add(data[:7000])
    np.savez(tmp_path / 'state.npz', **whole.state_dict())
    restored = AllanAccumulator.from_state(np.load(tmp_path / 'state.npz'))
    for acc in (whole, restored):
        acc.add(data[7000:])
    assert np.array_equal(whole.sums, restored.sums)
    assert np.array_equal(whole.counts, restored.counts)
    assert restored.channels == whole.channels


def test_bad_chunks():
    acc = AllanAccumulator(DT, 2, m_max=64)
    with pytest.raises(InputError, match='chunk must be'):
        acc.add(np.zeros((10, 3)))
    with pytest.raises(InputError, match='NaN'):
        acc.add(np.array([[0.0, np.nan]]))
    with pytest.raises(InputError):
        AllanAccumulator(0.0, 1)
    with pytest.raises(InputError):
        AllanAccumulator(DT, 1, m_max=8, m=[1, 16])


def test_slope_noise_id():
    tau = np.logspace(-2, 3, 60)
    for mu, alpha in ((-2.0, 0), (-1.0, 0), (0.0, -1), (1.0, -2)):
        assert np.all(alpha_from_slope(tau, tau ** mu) == alpha)


def test_stream_result_feeds_the_fit():
    from gyro_char.allan.fit import fit_result
    rate = generate(100_000, DT, N=2e-3, rng=np.random.default_rng(9))
    acc = AllanAccumulator(DT, 1, m_max=8192, channels=('gyro_z',))
    for chunk in np.array_split(rate, 37):
        acc.add(chunk[:, None])
    fit = fit_result(acc.result(), n_boot=10)['gyro_z']
    assert fit.terms['N'].resolved
    assert fit.terms['N'].value == pytest.approx(2e-3, rel=0.03)
