"""The static twin the filter and read-out tests share: 100 Hz, an ADIS16405's step and noise."""
from gyro_char.diagnosis import expected, spread, static
from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis.spectra import model_spectrum
import numpy as np

DT = 0.01
LSB = 0.05 * np.pi / 180.0               # output step, 0.05 deg/s
N_ARW = 2.4 * np.pi / 180.0 / 60.0       # white rate noise, 2.4 deg/sqrt(h)
BASE = static.StaticBaseline(N=N_ARW, bias=0.0, drift=0.0, lsb=LSB, dt=DT)


def check_twin_means(effects, n=2 ** 14, reps=10, seed0=40):
    """
    Assert every observable block's closed-form mean is the twins' within 4.5 standard errors.

    ``reps`` twins of ``n`` samples (seeds from ``seed0``); the standard error from the wider
    of the twins' scatter and the closed-form spread. Returns (twins' observables, spreads).
    """
    lay = obs.static_layout(n, DT)
    spec = model_spectrum(N_ARW, LSB, DT, effects)
    mean, sd = expected.expected_blocks(spec, lay), spread.spreads(spec, lay)
    twins = [obs.static_observables(static.simulate_twin(BASE, n, effects, seed0 + k), lay)
             for k in range(reps)]
    for block in ('adev', 'psd', 'tone', 'acf', 'drift'):
        stack = np.array([t[block] for t in twins])
        tol = 4.5 * np.maximum(stack.std(axis=0, ddof=1), sd[block]) / np.sqrt(reps) + 1e-6
        assert np.all(np.abs(mean[block] - stack.mean(axis=0)) < tol), block
    return twins, sd
