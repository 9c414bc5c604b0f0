# Data-driven starts of the noise-process searches, against records of known parameters.
from gyro_char.diagnosis.starts import markov_start
import numpy as np
from scipy import signal

DT, N_WHITE, T = 0.01, 7e-4, 7200.0


def _record(sigma, tc, seed):
    rng = np.random.default_rng(seed)
    n = int(T / DT)
    a = np.exp(-DT / tc)
    gm = signal.lfilter([sigma * np.sqrt(1 - a * a)], [1, -a], rng.standard_normal(n))
    return N_WHITE / np.sqrt(DT) * rng.standard_normal(n) + gm


def test_markov_start_finds_strength_and_correlation_time_of_a_gauss_markov_record():
    for sigma, tc, seed in ((2e-3, 20.0, 1), (1e-3, 2.0, 2), (4e-3, 150.0, 3)):
        s, t = markov_start(_record(sigma, tc, seed), DT, N_WHITE, 0.03, 450.0, 1e-6, 1e-1)
        assert abs(np.log(s / sigma)) < np.log(1.3) and abs(np.log(t / tc)) < np.log(1.5), \
            (sigma, tc, s, t)


def test_markov_start_is_none_on_white_noise():
    y = N_WHITE / np.sqrt(DT) * np.random.default_rng(4).standard_normal(int(T / DT))
    assert markov_start(y, DT, N_WHITE, 0.03, 450.0, 1e-6, 1e-1) is None
