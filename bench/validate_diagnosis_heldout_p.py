"""
Held-out set P of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_o.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]), with one more name, ``stale_samples``;
every shape is a physical form unlike the catalogue's, the development shapes
(``validate_diagnosis.py``) and held-out sets A-O, and the kinds of departure differ from
shape to shape:

- internal_lowpass: a load-shedding hub: the sensor hub's output stage passes each conversion
  as it is, but when its CPU is busy (an independent share q of the output slots: interrupt
  load from other sensors) it takes a cheap path that publishes the mean of the current and
  the previous conversion: y_k = x_k, or (x_k + x_(k-1)) / 2 in a busy slot: a two-tap FIR
  switched on and off at random (time-varying), lag-1 autocorrelation q / 2 on white input,
  zero beyond;
- vibration: a belt-driven compressor: a reciprocating pump driven through a stretching belt
  runs at 18 Hz, the belt's stretch modulating its speed at the belt-pass frequency 0.7 Hz:
  A cos(2 pi 18 Hz t + 6 sin(2 pi 0.7 Hz t + p) + p'): a tone frequency-modulated with index
  6 (peak deviation 4.2 Hz; a comb of Bessel sidebands 0.7 Hz apart, not one line);
- temperature_drift: a discharging battery: the board's switching regulator draws a current
  P / V from a battery whose voltage falls linearly, V = V0 (1 - t / 4 h), and its wiring
  loss R I^2 heats the die: bias A ((1 - t / T_BAT)^-2 - 1), t counted from full charge (the
  record starting 0-600 s after it): a convex, accelerating drift (3 A after 2 h);
- bias_instability: a parasitic interference: a spurious reflection in the sensing path
  interferes with the main wave and the bias goes as the sine of their phase difference,
  whose 1/f thermal wander (a Gaussian sum of thirteen first-order processes, three per
  decade, 0.1-1000 s, PHASE_SD = 1.5 rad sd) spans radians: bias b sin(phi) / sqrt(e^-s^2
  sinh s^2) (sd b), bounded (an arcsine-like marginal), autocovariance b^2 sinh(s^2 rho(u)) /
  sinh(s^2), rho the phase's correlation;
- rate_random_walk: a leakage through a degrading barrier: the barrier height random-walks,
  and the leakage current (the bias) goes as its exponential: D (e^(W / D) - 1), W a walk of
  intensity K, D = K sqrt(LOG_S) (LOG_S = 2 h): a log-normal walk whose steps grow as it rises
  (heteroscedastic, skewed upwards);
- gauss_markov: a cluster of identical traps: six identical defects switch independently
  between two states (symmetric random telegraphs, one time constant): their sum, an
  Ehrenfest birth-death chain on seven levels, autocovariance exactly sd^2 e^(-u / tc) (as a
  first-order Gauss-Markov) but a lattice, binomial marginal;
- quantization: a unit-converting gateway: the sensor's angle counter (step Q) is rescaled by
  a gateway to a unit R = 1.37 times larger and rounded again: double rounding, Q R round(Q
  round(theta / Q) / (Q R)): a white angle error of variance ~ Q^2 (1 + R^2) / 12 with a
  trapezoid-like marginal;
- resonance: a snubbed mount: a mount mode (19 Hz, q 12) rocks against soft plastic stops at
  +-1 sd of its angle: the angle is clipped, clip(phi, -L, L), the rate its difference (zero
  while on a stop): a narrow band cut by stops, reduced to the Bussgang gain erf(1 / sqrt 2)
  = 0.68 and spread into odd harmonics (57 Hz aliases to 43 Hz);
- stale_samples: a housekeeping freeze: the sensor's DSP refreshes its compensation
  coefficients once every period P (its own clock; random phase), and its output register is
  frozen for F seconds while it does; the host keeps reading at the output rate and publishes
  the frozen value (the last sample before the freeze) under new stamps: bursts of ~F / dt
  repeats, periodic (a share F / P of the samples; the samples read during a freeze are
  lost).

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- busy hub: lag-1 autocorrelation q / 2 against 1 / sqrt(n);
- belt compressor, battery: matched to the noise-free waveform (zero phases; the record 300 s
  after full charge), mean removed: |s - mean(s)| / sigma;
- interference, trap cluster: Allan variance excess over N^2 / tau in units of the white
  spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]: the
  interference from its autocovariance (``cov_avar``), the cluster as ``gm_avar``;
- barrier walk: the walk's Allan variance q^2 (2 m^2 + 1) / (6 m), q = K sqrt(dt), times the
  mean of the local intensity e^(2 W / D), e^(2 t / LOG_S) on average, over the record, in the
  same units (the exponential's upward drift ignored);
- gateway: a white angle error of variance v: relative Allan excess 3 v / (m dt N^2), at dt
  less at 10 dt, against sqrt(3 / n + 40 / (3 n)) (as set O);
- snubbed mount: the Bussgang part of the rate's PSD, erf(1 / sqrt 2)^2 times the free mode's,
  its mean excess over white in the band above half its peak, times sqrt(T B);
- freeze: the exact repeats of the harness's output (rounded to LSB = 0.05 deg/s): the share
  of zero first differences, q0 for white noise (two independent N(bias, sigma^2) samples on
  one LSB level), rises by p = F / P (1 - q0): z = p sqrt(n (1 - q0) / q0) (a run statistic,
  using the bursts' lengths, would do better).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
Physical scale: busy shares of 0.95 % (edge), 10 % and 50 %; compressors of 0.0027, 0.029 and
0.17 deg/s; batteries of A 0.0021, 0.0057 and 0.029 deg/s; interferences of 27, 72 and 290
deg/h sd; barrier walks of K 1.14e-6, 3e-6 and 1.5e-5 rad/s/sqrt(s); trap clusters of 0.0099,
0.057 and 0.14 deg/s sd (tc 2 s, 2 s and 20 s); gateway steps Q of 12, 40 and 120 urad; free
mode rates of 0.028, 0.069 and 0.34 deg/s sd; freezes of 20 ms every 22 s, 50 ms every 5 s and
200 ms every 2 s.
"""
from heldout_detect import allan_taus, allan_z, band_excess, gm_avar
import numpy as np
from scipy import signal, special
from validate_diagnosis_heldout_k import walk_avar
from validate_diagnosis_heldout_m import cov_avar
from validate_diagnosis_heldout_n import gauss_markov

PUMP_HZ, BELT_HZ, BELT_INDEX = 18.0, 0.7, 6.0       # pump speed; belt-pass; FM index (rad)
T_BAT = 14400.0                                     # s: the battery voltage's zero crossing
PHASE_SD = 1.5                                      # rad: the interference phase's sd
PHASE_TAUS = 0.1 * 10.0 ** (np.arange(13) / 3)      # s: the phase's Gauss-Markov times
LOG_S = 7200.0                                      # s: the walk reaches D in about this
TRAPS = 6                                           # identical traps in the cluster
GATE_R = 1.37                                       # gateway unit / sensor step
MOUNT_HZ, MOUNT_Q, STOP = 19.0, 12.0, 1.0           # mode; its q; stop at STOP angle sd
BIAS = 0.003                                        # rad/s: the static records' bias
LSB = 0.05 * np.pi / 180.0                          # rad/s: the harness's output step


def coalesce(x: np.ndarray, busy: np.ndarray) -> np.ndarray:
    """Return x_k, or (x_k + x_(k-1)) / 2 where ``busy`` (never at k = 0)."""
    y = np.array(x, float)
    k = np.flatnonzero(busy)
    k = k[k > 0]
    y[k] = (x[k] + x[k - 1]) / 2
    return y


def belt_tone(t, amplitude: float, phase: float = 0.0, fm_phase: float = 0.0) -> np.ndarray:
    """Return A cos(2 pi PUMP_HZ t + BELT_INDEX sin(2 pi BELT_HZ t + fm_phase) + phase)."""
    t = np.asarray(t, float)
    return amplitude * np.cos(2 * np.pi * np.mod(PUMP_HZ * t, 1.0)
                              + BELT_INDEX * np.sin(2 * np.pi * BELT_HZ * t + fm_phase) + phase)


def battery(t, amplitude: float) -> np.ndarray:
    """Return A ((1 - t / T_BAT)^-2 - 1), t from full charge."""
    return amplitude * ((1 - np.asarray(t, float) / T_BAT) ** -2 - 1)


def phase_rho(u) -> np.ndarray:
    """Correlation of the unit interference phase at lag u."""
    return np.mean(np.exp(-np.abs(np.asarray(u, float))[..., None] / PHASE_TAUS), axis=-1)


def interference(n: int, dt: float, rng) -> np.ndarray:
    """Unit-sd sin(phi), phi = PHASE_SD times a unit 1/f sum of PHASE_TAUS processes."""
    phi = sum(gauss_markov(n, tau, dt, rng) for tau in PHASE_TAUS) / np.sqrt(PHASE_TAUS.size)
    s2 = PHASE_SD ** 2
    return np.sin(PHASE_SD * phi) / np.sqrt(np.exp(-s2) * np.sinh(s2))


def interference_cov(u, b: float) -> np.ndarray:
    """Autocovariance b^2 sinh(s^2 rho(u)) / sinh(s^2), s = PHASE_SD."""
    s2 = PHASE_SD ** 2
    return b * b * np.sinh(s2 * phase_rho(u)) / np.sinh(s2)


def barrier_walk(n: int, k: float, dt: float, rng) -> tuple:
    """Return (bias, walk): D (e^(W / D) - 1), W a walk of intensity k, D = k sqrt(LOG_S)."""
    d = k * np.sqrt(LOG_S)
    walk = np.cumsum(rng.standard_normal(n)) * k * np.sqrt(dt)
    return d * np.expm1(walk / d), walk


def trap_cluster(n: int, sd: float, tc: float, dt: float, rng) -> np.ndarray:
    """Sum of TRAPS symmetric two-state traps (lag-m correlation e^(-m dt / tc)), sd ``sd``."""
    flip = (1 - np.exp(-dt / tc)) / 2
    start = np.where(rng.uniform(size=(TRAPS, 1)) < 0.5, -1.0, 1.0)
    flips = np.cumsum(rng.uniform(size=(TRAPS, n)) < flip, axis=1)
    states = start * (1 - 2 * (flips % 2))
    return sd * states.sum(axis=0) / np.sqrt(TRAPS)


def gateway(theta, q: float) -> np.ndarray:
    """Double rounding: Q R round(Q round(theta / Q) / (Q R)), R = GATE_R."""
    first = q * np.round(np.asarray(theta, float) / q)
    return q * GATE_R * np.round(first / (q * GATE_R))


def gateway_var(q: float) -> float:
    """Angle error variance of ``gateway`` on a fast-moving angle: Q^2 (1 + R^2) / 12."""
    return q * q * (1 + GATE_R ** 2) / 12


def mode_coeffs(dt: float):
    """Return (a, angle variance per unit drive, lag-1 correlation) of the MOUNT mode."""
    th = 2 * np.pi * MOUNT_HZ * dt * np.sqrt(1 - 1 / (4 * MOUNT_Q ** 2))
    r = np.exp(-np.pi * MOUNT_HZ * dt / MOUNT_Q)
    a = np.array([1.0, -2 * r * np.cos(th), r * r])
    var = (1 + r * r) / ((1 - r * r) * (1 - 2 * r * r * np.cos(2 * th) + r ** 4))
    return a, var, 2 * r * np.cos(th) / (1 + r * r)


def drive_gain(sigma: float, dt: float) -> float:
    """Drive sd that gives the free mode's rate (angle difference / dt) sd ``sigma``."""
    _, var, rho1 = mode_coeffs(dt)
    return sigma * dt / np.sqrt(2 * var * (1 - rho1))


def mode_angle(n: int, sigma: float, dt: float, rng) -> tuple:
    """Return (phi, L): n + 1 angles of the free mode (rate sd ``sigma``), the stop STOP sd."""
    a, var, _ = mode_coeffs(dt)
    burn = int(20 * MOUNT_Q / (np.pi * MOUNT_HZ * dt)) + 1
    g = drive_gain(sigma, dt)
    return signal.lfilter([g], a, rng.standard_normal(n + 1 + burn))[burn:], STOP * g * np.sqrt(
        var)


def snubbed(n: int, sigma: float, dt: float, rng) -> np.ndarray:
    """Rate of the mode's angle clipped at +-STOP sd: diff(clip(phi)) / dt."""
    phi, lim = mode_angle(n, sigma, dt, rng)
    return np.diff(np.clip(phi, -lim, lim)) / dt


def snubbed_psd(f, sigma: float, dt: float) -> np.ndarray:
    """One-sided Bussgang PSD erf(STOP / sqrt 2)^2 S_free(f) of ``snubbed``."""
    a, _, _ = mode_coeffs(dt)
    z1 = np.exp(-2j * np.pi * np.asarray(f, float) * dt)
    g = drive_gain(sigma, dt)
    den = np.abs(a[0] + a[1] * z1 + a[2] * z1 * z1) ** 2
    free = 2 * dt * g * g * np.abs(1 - z1) ** 2 / dt ** 2 / den
    return special.erf(STOP / np.sqrt(2)) ** 2 * free


def frozen(n: int, freeze: float, period: float, dt: float, start: float) -> np.ndarray:
    """Flag the samples read while the register is frozen: (t - start) mod P < F, t >= start."""
    t = np.arange(n) * dt
    held = (t >= start) & (np.mod(t - start, period) < freeze - 1e-9 * dt)
    held[0] = False
    return held


def hold(x: np.ndarray, held: np.ndarray) -> np.ndarray:
    """Replace every held sample by the last sample not held before it."""
    src = np.maximum.accumulate(np.where(held, 0, np.arange(x.size)))
    return x[src]


def repeat_share(sig: float) -> float:
    """Return q0: the chance that two white samples N(BIAS, sig^2) round to one LSB level."""
    j = np.arange(np.floor((BIAS - 12 * sig) / LSB), np.ceil((BIAS + 12 * sig) / LSB) + 1)
    p = np.diff(special.ndtr((np.r_[j - 0.5, j[-1] + 0.5] * LSB - BIAS) / sig))
    return float(np.sum(p * p))


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def hub(x, rng, q):
        return coalesce(x, rng.uniform(size=x.size) < q)

    def compressor(x, rng, amplitude):
        t = np.arange(x.size) * dt
        return x + belt_tone(t, amplitude, rng.uniform(0, 2 * np.pi), rng.uniform(0, 2 * np.pi))

    def discharge(x, rng, amplitude):
        return x + battery(np.arange(x.size) * dt + rng.uniform(0, 600), amplitude)

    def reflection(x, rng, b):
        return x + b * interference(x.size, dt, rng)

    def barrier(x, rng, k):
        return x + barrier_walk(x.size, k, dt, rng)[0]

    def cluster(x, rng, sd, tc):
        return x + trap_cluster(x.size, sd, tc, dt, rng)

    def converted(x, rng, q):
        theta = gateway(np.cumsum(x) * dt, q)
        return np.diff(np.r_[0.0, theta]) / dt

    def mount(x, rng, sigma):
        return x + snubbed(x.size, sigma, dt, rng)

    def housekeeping(x, rng, freeze, period):
        return hold(x, frozen(x.size, freeze, period, dt, rng.uniform(0, period)))

    return {
        'internal_lowpass': (hub, [{'q': 0.1}, {'q': 0.5}, {'q': 0.0095}]),
        'vibration': (compressor, [{'amplitude': 5e-4}, {'amplitude': 3e-3},
                                   {'amplitude': 4.7e-5}]),
        'temperature_drift': (discharge, [{'amplitude': 1e-4}, {'amplitude': 5e-4},
                                          {'amplitude': 3.67e-5}]),
        'bias_instability': (reflection, [{'b': 3.5e-4}, {'b': 1.4e-3}, {'b': 1.29e-4}]),
        'rate_random_walk': (barrier, [{'k': 3e-6}, {'k': 1.5e-5}, {'k': 1.14e-6}]),
        'gauss_markov': (cluster, [{'sd': 1e-3, 'tc': 2.0}, {'sd': 2.5e-3, 'tc': 20.0},
                                   {'sd': 1.72e-4, 'tc': 2.0}]),
        'quantization': (converted, [{'q': 4e-5}, {'q': 1.2e-4}, {'q': 1.21e-5}]),
        'resonance': (mount, [{'sigma': 1.2e-3}, {'sigma': 6e-3}, {'sigma': 4.97e-4}]),
        'stale_samples': (housekeeping, [{'freeze': 0.05, 'period': 5.0},
                                         {'freeze': 0.2, 'period': 2.0},
                                         {'freeze': 0.02, 'period': 22.0}]),
    }


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn, p = n * dt, n_arw ** 2, params
    t = np.arange(n) * dt
    if name == 'internal_lowpass':
        return float(p['q'] / 2 * np.sqrt(n))
    if name in ('vibration', 'temperature_drift'):
        s = (belt_tone(t, p['amplitude']) if name == 'vibration'
             else battery(t + 300.0, p['amplitude']))
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        rel = [3 * gateway_var(p['q']) / (m * dt * nn) for m in (1, 10)]
        return float(abs(rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n)))
    if name == 'resonance':
        ex, width = band_excess(lambda f: snubbed_psd(f, p['sigma'], dt), dt, sig)
        return float(ex * np.sqrt(big_t * width))
    if name == 'stale_samples':
        q0 = repeat_share(sig)
        return float(p['freeze'] / p['period'] * np.sqrt(n * (1 - q0) / q0))
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = cov_avar(lambda u: interference_cov(u, p['b']), tau)
    elif name == 'rate_random_walk':
        x = 2 * big_t / LOG_S
        excess = walk_avar(np.round(tau / dt), p['k'] * np.sqrt(dt)) * np.expm1(x) / x
    else:
        excess = gm_avar(tau, p['sd'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
