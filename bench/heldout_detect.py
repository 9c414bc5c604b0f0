"""
Detectability arithmetic the held-out shape sets share (where their edge levels come from).

The sets themselves were written blind, one author each; these are the pieces of their
``detectability`` that came out the same: the Allan variance of a one-sided PSD and of a
first-order Gauss-Markov process, an Allan excess's z and a band's mean excess over white
(static), a matched
detector for a deterministic angle residual, the harmonic of a memoryless rate error and a
rate error averaged over the gyro's own noise (swing).
"""
from functools import lru_cache

from gyro_char.allan.expected import markov_avar
from gyro_char.sim.config import BenchConfig
import numpy as np


@lru_cache(maxsize=8)
def _grid(dt: float):
    return np.geomspace(1e-9, 0.5 / dt, 40000)


def psd_avar(psd, tau: np.ndarray, dt: float) -> np.ndarray:
    """Allan variance 2 int S(f) sin^4(pi f tau) / (pi f tau)^2 df of a one-sided PSD."""
    f = _grid(dt)
    s = psd(f)
    out = []
    for tt in np.atleast_1d(tau):
        x = np.pi * f * tt
        k = np.where(f * tt > 30, 3.0 / 8.0, np.sin(x) ** 4) / x ** 2
        out.append(2 * np.trapezoid(s * k, f))
    return np.array(out)


ALLAN_POINTS = 60       # averaging times of the static sets' Allan statistic (B-D: 200)


def allan_taus(dt: float, big_t: float, points: int = ALLAN_POINTS) -> np.ndarray:
    """Averaging times of the static sets' Allan statistic: 10 dt to T / 10, log-spaced."""
    return np.geomspace(10 * dt, big_t / 10, points)


def allan_z(excess: np.ndarray, tau: np.ndarray, nn: float, big_t: float) -> float:
    """
    Largest z of an Allan variance excess at ``tau`` over white noise's (N^2 = ``nn``).

    In units of white's spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau (T = ``big_t``).
    """
    z = excess / (nn / tau) * np.sqrt(1.5 * big_t / tau / 2)
    return float(z.max())


def gm_avar(tau, sigma, tc):
    """Allan variance of exponentially correlated noise of sd ``sigma`` (q^2 = 2 sigma^2 / tc)."""
    return markov_avar(tau, tc) * 2 * sigma ** 2 / tc


def matched_z(residual: np.ndarray, rate_hz: float, n_arw: float, floor: float) -> float:
    """
    Matched-detector z of a deterministic angle residual on a run's grid.

    Against the gyro's angle noise n_arw^2 / (2 pi f)^2 plus a white ``floor`` (encoder, stamps).
    """
    n = residual.size
    f = np.fft.fftfreq(n, 1.0 / rate_hz)
    s_n = n_arw ** 2 / np.maximum((2 * np.pi * f) ** 2, 1e-30) + floor
    return float(np.sqrt(np.sum(np.abs(np.fft.fft(residual)) ** 2 / (n * rate_hz * s_n))))


def fourier(err, amp: float, k: int, m: int = 20000) -> float:
    """Magnitude of harmonic ``k`` of the memoryless ``err(W cos(theta), theta)``, one period."""
    th = np.arange(m) * 2 * np.pi / m
    y = err(amp * np.cos(th), th)
    return float(2 * np.hypot(np.mean(y * np.cos(k * th)), np.mean(y * np.sin(k * th))))


def band_excess(psd, dt: float, sig: float):
    """
    Return the mean excess of the one-sided ``psd(f)`` over white in its band, and its width.

    White is 2 sig^2 dt; the band is where the excess is above half its peak; width in Hz.
    """
    f = np.linspace(0, 0.5 / dt, 200001)
    ex = psd(f) / (2 * sig ** 2 * dt)
    band = ex >= ex.max() / 2
    return float(ex[band].mean()), float(band.sum() * (f[1] - f[0]))


HERMITE = 64        # Gauss-Hermite nodes of the noise averages


def noise_mean(err, w, s_n: float) -> np.ndarray:
    """Mean of the memoryless ``err`` over the gyro's own noise (sd ``s_n``) at rates ``w``."""
    x, wt = np.polynomial.hermite_e.hermegauss(HERMITE)
    wt = wt / wt.sum()
    return np.sum(wt * err(np.asarray(w)[..., None] + s_n * x), axis=-1)


def noise_lines(err, amp_rate: float, s_n: float) -> float:
    """Norm of lines k >= 2 of the noise-averaged memoryless rate error at amp_rate cos(th)."""
    th = np.arange(4096) * 2 * np.pi / 4096
    c = np.fft.rfft(noise_mean(err, amp_rate * np.cos(th), s_n)) / th.size
    return float(2 * np.linalg.norm(c[2:61]))


def encoder_floor(enc, rate_hz: float, amp_rate: float = 0.0) -> float:
    """
    White floor (two-sided, per Hz) of the encoder angle on a run at ``rate_hz``.

    The ADC noise and the level and word steps; with ``amp_rate``, the preset's stamp jitter
    read through the swing's rms rate as well.
    """
    floor = (enc.adc_noise ** 2 + enc.level_step ** 2 / 12 + enc.word_step ** 2 / 12) / rate_hz
    return floor + (amp_rate ** 2 / 2 * enc.jitter_s ** 2 / rate_hz if amp_rate else 0.0)


def quadratic_z(s_r: np.ndarray, f: np.ndarray, n_arw: float, floor: float,
                duration: float) -> float:
    """
    Return the z of a quadratic detector for an added two-sided angle-noise PSD ``s_r``.

    Against the gyro's angle noise n_arw^2 / (2 pi f)^2 plus the white ``floor``:
    sqrt(T / 2 int (S_r / S_n)^2 df).
    """
    s_n = n_arw ** 2 / np.maximum((2 * np.pi * f) ** 2, 1e-30) + floor
    return float(np.sqrt(duration / 2 * np.trapezoid((s_r / s_n) ** 2, f)))


def stamp_z(stamp_psd, amp_rate: float, f0: float, n_arw: float, floor: float,
            duration: float, rate_hz: float, points: int) -> float:
    """
    Return the z of a stamp error of two-sided PSD ``stamp_psd(f)`` (s^2/Hz) on a swing run.

    Read through the swing's rate amp_rate cos(2 pi f0 t), the error adds angle noise
    amp_rate^2 / 4 (S(f - f0) + S(f + f0)), detected by ``quadratic_z`` on ``points``
    frequencies across the run's band.
    """
    f = np.linspace(-rate_hz / 2, rate_hz / 2, points)
    s_r = amp_rate ** 2 / 4 * (stamp_psd(f - f0) + stamp_psd(f + f0))
    return quadratic_z(s_r, f, n_arw, floor, duration)


def period_lines(err, w: float, kmin: int = 1) -> float:
    """Norm of lines kmin..60 of ``err(t)`` over one swing period (4096 points)."""
    t = np.arange(4096) * (2 * np.pi / w) / 4096
    c = np.fft.rfft(err(t)) / t.size
    return float(2 * np.linalg.norm(c[kmin:61]))


def step_of(t) -> float:
    """Return the median sample interval of the stamps ``t``."""
    return float(np.median(np.diff(t)))


def swing_scales(period_s: float, duration: float):
    """
    Return the swing sets' yardsticks from the adis16405 preset: (N, amplitude, encoder, w, s).

    s = N sqrt(2 / T) is the standard deviation of a sine fitted to a rate residual of length T.
    """
    cfg = BenchConfig.from_preset('adis16405')
    n_arw = cfg.noise['gyro_x']['N']
    w = 2 * np.pi / period_s
    return n_arw, cfg.stand.amplitude, cfg.encoder, w, n_arw * np.sqrt(2 / duration)


def solve_level(zof, z: float, guess: float, slope: float = 1.0, limit: float = np.inf,
                steps: int = 30) -> float:
    """
    Return the x at which ``zof(x)`` is z: a secant in log-log from ``guess``.

    ``slope`` is the first guess of d ln z / d ln x; ``limit`` caps each step's ratio (a z that
    is not monotonic far from the root, e.g. a delay's, would otherwise send a step astray).
    """
    def step(x, zx, s):
        return x * float(np.clip((z / zx) ** (1.0 / s), 1.0 / limit, limit))
    x0, z0 = guess, zof(guess)
    x1 = step(x0, z0, slope)
    z1 = zof(x1)
    for _ in range(steps):
        if abs(z1 / z - 1.0) < 1e-4:
            break
        s = np.log(z1 / z0) / np.log(x1 / x0)
        x0, z0, x1 = x1, z1, step(x1, z1, s)
        z1 = zof(x1)
    return float(x1)


def solved_levels(detectability, key: dict, guess: dict, targets, names=None, slope=None,
                  limit=None, digits: int = 3, steps: int = 30) -> dict:
    """
    Return a swing set's ``{name: [weak, strong, edge]}``: each level solved for z = targets.

    ``detectability(name, params)`` is the set's analytic z; ``key`` maps a name to its one
    parameter, ``guess`` to its starting value, ``slope`` / ``limit`` (optional, per name) to
    ``solve_level``'s; values rounded to ``digits`` significant digits.
    """
    slope, limit = slope or {}, limit or {}

    def level(name, z):
        x = solve_level(lambda v: detectability(name, {key[name]: v}), z, guess[name],
                        slope.get(name, 1.0), limit.get(name, np.inf), steps)
        return {key[name]: float(f'{x:.{digits}g}')}
    return {name: [level(name, z) for z in targets] for name in (names or key)}


def print_levels(levels: dict, detectability, periods=(5.0, 2.5)) -> None:
    """Print each level with its z at each swing period (a set's ``__main__``)."""
    for name, value in levels.items():
        print(name, value, *[[round(float(detectability(name, p, period_s=ps)), 2) for p in value]
                             for ps in periods])


def self_check(shapes, detectability, bias: float, n: int = 720000) -> None:
    """
    Build a held-out set's 27 records as the harness does and time them.

    White noise plus ``bias``, the shape, rounded to the LSB; prints each record's time,
    finiteness and analytic z (``detectability``). Shared by the sets' ``self_check``.
    """
    import time
    dt, n_arw, lsb = 0.01, 2.4 * np.pi / 180.0 / 60.0, 0.05 * np.pi / 180.0
    sig = n_arw / np.sqrt(dt)
    worst, finite = 0.0, True
    for name, (fn, levels) in shapes(dt, sig, n_arw).items():
        for level, p in zip(('weak', 'strong', 'edge'), levels):
            rng = np.random.default_rng(7)
            x = sig * rng.standard_normal(n) + bias
            start = time.perf_counter()
            y = fn(x, rng, **p)
            took = time.perf_counter() - start
            y = np.round(y / lsb) * lsb
            ok = y.shape == (n,) and bool(np.all(np.isfinite(y)))
            worst, finite = max(worst, took), finite and ok
            z = detectability(name, p, dt, sig, n_arw, n)
            print(f'{name:18s} {level:6s} {took:6.2f} s  finite {ok}  z {z:9.2f}')
    print(f'slowest generator {worst:.2f} s; all finite: {finite}')
