"""
Held-out set I of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_h.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out sets A-H, and
the kinds of departure differ from shape to shape:

- internal_lowpass: batched zero-phase smoothing: a sensor hub collects FIFO frames of 32
  samples and runs a one-pole IIR forward and then backward over each frame before handing it
  on (no phase lag, kernel ~ a^|k|): a non-causal smoother that is reset at every frame edge,
  so block-periodic (pairs across a frame edge stay independent);
- vibration: a three-speed fan: a thermostat steps a fan between 14.7, 19.6 and 24.5 Hz at
  Poisson times (mean 240 s, a new speed each time), the rotor following through a 3 s speed
  lag with a continuous phase; its unbalance force, and the rocking with it, grows as the
  speed squared: one tone at a time, hopping among three lines of different amplitudes;
- temperature_drift: diffusive warming: the heat of the powered board reaches the die through
  a thick base plate by conduction (a slab, one-dimensional), so the bias rises from zero as
  A erfc(sqrt(t_d / (t + t0))) (t_d = 400 s, the record starting t0 <= 60 s after power-on):
  a dead time, then a slow approach with a 1 / sqrt(t) tail, no time constant;
- bias_instability: thermal-diffusion flicker (Voss-Clarke): random heat flux at the mount's
  surface diffuses into a slab held at a fixed temperature at its back; the die on the surface
  follows the surface temperature, the sum of the slab's 160 diffusion modes (rates
  lambda_1 (2k - 1)^2, lambda_1 = 2 pi 2e-4 Hz) all driven by the SAME flux: surface impedance
  1 / sqrt(i w) gives PSD ~ b^2 / (pi f) from 2e-4 to ~20 Hz, flat below, 1 / f^2 above;
- rate_random_walk: a walk with auto-zero: the bias random-walks but the sensor's automatic
  bias update re-zeroes it every 900 s (a fixed cadence, random phase): Brownian pieces that
  each start from zero; the re-zeroing steps double the walk's Allan variance, 2 K^2 tau / 3
  up to ~P / 10, which bends over beyond;
- gauss_markov: a demodulation product: the bias is a wandering quadrature error times a
  wandering demodulator phase error, two independent first-order Gauss-Markov processes with
  correlation times 1.5 tc and 3 tc: a symmetric, leptokurtic (excess kurtosis 6) marginal,
  continuous paths and an autocorrelation exactly exp(-|tau| / tc);
- quantization: a vernier read-out with a gain error: a coarse angle counter of step Q and a
  fine interpolator splitting each step in 16, whose gain is off by g, so the angle error is a
  sawtooth g (theta mod Q) with a jump at every coarse edge, on top of the fine staircase;
- resonance: a demodulated sense mode: the sense mode's own noise, at a split of f0 from the
  drive, is demodulated to baseband as one complex pole (z_k = r e^(i 2 pi f0 dt) z_(k-1) +
  w_k, output Re z): a Lorentzian at f0 PLUS its mirror (a real second-order mode: their
  product), so first-order skirts and a plateau down to DC (2.3 times a real mode's of the same
  variance at 1-10 Hz for 35 Hz, width 3 Hz).

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- frame smoother: lag-1 autocorrelation r1 = sum_i C_(i,i+1) / trace C, C = M M^T of the
  frame's exact linear map M, against 1 / sqrt(n);
- fan: every speed's line in a Welch bin (Hann, L = 16384) as sets B and G, present a third of
  the time: z_k = g_k^2 A_k^2 sqrt(n L) / (18 sigma^2), in quadrature;
- diffusive warming: matched to its own noise-free waveform, mean removed: |s - mean(s)| /
  sigma;
- diffusion flicker, auto-zeroed walk, product: Allan variance excess over N^2 / tau in units
  of the white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]:
  the flicker from the exact PSD of its sampled modes, the walk from its phase-averaged
  autocovariance q^2 (P - l - 1)(P - l) / (2 P) (P samples between re-zeroings), the product
  the first-order Gauss-Markov formula;
- vernier: the periodic angle error's autocovariance c(m) = 2 sum_h |c_h|^2 exp(-2 pi^2 h^2 m
  dt N^2 / Q^2) (the angle walking by the white noise, as sets E and F): relative Allan excess
  (3 c0 - 4 c_m + c_2m) / (m dt N^2) at dt less at 10 dt, against sqrt(3 / n + 40 / (3 n));
- demodulated mode: mean excess PSD / white over the band above half its peak, times
  sqrt(T B) (as set H's rattle).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
Physical scale: frame poles a of 0.0025 (edge, a corner above Nyquist), 0.15 and 0.5; fan
lines of 0.0064, 0.057 and 0.23 deg/s at the middle speed; diffusive warmings of 0.010, 0.086
and 0.23 deg/s (0.8-17 degC at 0.0135 (deg/s)/degC); flicker b of 4.5e-5, 2e-4 and 6e-4 rad/s;
walks driven by 2.25e-7, 6e-7 and 2e-6 rad/s a sample (K of 2.25e-6 to 2e-5 rad/s/sqrt(s));
products of 0.0093, 0.057 and 0.17 deg/s sd (tc 2.5 s, 2.5 s and 40 s); vernier coarse steps
of 36, 55 and 110 arcsec with fine gains 10 %, 15 % and 25 % off; demodulated modes of 0.023,
0.11 and 0.34 deg/s sd at 35 Hz (width 3 Hz) and 28 Hz (width 5 Hz).
"""
from heldout_detect import allan_taus, allan_z, band_excess, gm_avar, psd_avar
import numpy as np
from scipy import signal, special

FRAME = 32                           # samples per FIFO frame of the zero-phase smoother
FAN_HZ = (14.7, 19.6, 24.5)          # the fan's three speeds (rotation frequency)
FAN_DWELL, FAN_LAG = 240.0, 3.0      # s: mean time at one speed; the rotor's speed lag
WELCH_L = 16384
DIFFUSE_T, POWER_ON = 400.0, 60.0    # s: diffusion time t_d; record starts <= POWER_ON late
MODES, LOW_HZ = 160, 2e-4            # slab diffusion modes; lowest mode rate / (2 pi)
AUTOZERO = 900.0                     # s between automatic bias updates
PRODUCT_TC = (1.5, 3.0)              # the two factors' correlation times, in units of tc
FINE = 16                            # fine interpolation cells per coarse step


def frame_smooth(x: np.ndarray, a: float, start: int = 0) -> np.ndarray:
    """One-pole (pole a, DC gain 1) forward, then backward, over each FRAME from ``start``."""
    def fb(rows):
        f = signal.lfilter([1 - a], [1, -a], rows, axis=1, zi=a * rows[:, :1])[0]
        r = f[:, ::-1]
        return signal.lfilter([1 - a], [1, -a], r, axis=1, zi=a * r[:, :1])[0][:, ::-1]
    y = np.empty_like(x)
    head = start % FRAME
    body = (x.size - head) // FRAME * FRAME
    if head:
        y[:head] = fb(x[None, :head])[0]
    y[head:head + body] = fb(x[head:head + body].reshape(-1, FRAME)).ravel()
    if head + body < x.size:
        y[head + body:] = fb(x[None, head + body:])[0]
    return y


def frame_lag1(a: float) -> float:
    """Lag-1 autocorrelation of unit white noise after ``frame_smooth`` (whole frames)."""
    m = frame_smooth(np.eye(FRAME).ravel(), a).reshape(FRAME, FRAME).T   # y = m x, a frame
    c = m @ m.T
    return float(np.trace(c, 1) / np.trace(c))


def fan_speeds(n: int, dt: float, rng) -> np.ndarray:
    """Rotation frequency per sample: Poisson speed changes, a new speed each, a 3 s lag."""
    k = rng.poisson(n * dt / FAN_DWELL) + 1
    at = np.sort(rng.integers(0, n, k - 1))
    idx = [int(rng.integers(3))]
    for _ in at:
        idx.append((idx[-1] + int(rng.integers(1, 3))) % 3)
    target = np.repeat(np.take(FAN_HZ, idx), np.diff(np.r_[0, at, n]))
    c = np.exp(-dt / FAN_LAG)
    return signal.lfilter([1 - c], [1, -c], target, zi=[c * target[0]])[0]


def fan_lines(amplitude: float):
    """Each speed's line amplitude: the middle speed's ``amplitude`` times (f / f_mid)^2."""
    f = np.array(FAN_HZ)
    return f, amplitude * (f / FAN_HZ[1]) ** 2


def scalloping(f, dt: float) -> np.ndarray:
    """Amplitude gain of a Hann window of WELCH_L for lines at ``f`` (offset from their bin)."""
    b = np.asarray(f) * dt * WELCH_L
    delta = b - np.round(b)
    w = np.hanning(WELCH_L)
    ph = np.exp(2j * np.pi * np.outer(delta, np.arange(WELCH_L)) / WELCH_L)
    return np.abs(ph @ w) / w.sum()


def diffusive(t: np.ndarray, amplitude: float) -> np.ndarray:
    """Surface-heated slab: amplitude erfc(sqrt(t_d / t)), 0 at t = 0."""
    with np.errstate(divide='ignore'):
        return amplitude * special.erfc(np.sqrt(DIFFUSE_T / np.asarray(t, float)))


def slab_modes(b: float, dt: float):
    """(a_j, beta_j, var u) of the sampled modes m_j = a_j m_j + beta_j u, y = sum m_j."""
    lam = 2 * np.pi * LOW_HZ * (2 * np.arange(1, MODES + 1) - 1.0) ** 2
    a = np.exp(-lam * dt)
    return a, (1 - a) / lam, 16 * lam[0] * b * b / np.pi ** 2 / dt


def slab_flicker(n: int, b: float, dt: float, rng) -> np.ndarray:
    """Surface temperature of the slab under white flux, modes started stationary (jointly)."""
    a, beta, var = slab_modes(b, dt)
    cov = np.outer(beta, beta) * var / (1 - np.outer(a, a))
    w, v = np.linalg.eigh(cov)
    m0 = v @ (np.sqrt(np.clip(w, 0, None)) * rng.standard_normal(a.size))
    u = rng.standard_normal(n) * np.sqrt(var)
    y = np.zeros(n)
    for aj, bj, mj in zip(a, beta, m0):
        y += signal.lfilter([bj], [1, -aj], u, zi=[aj * mj])[0]
    return y


def slab_psd(f, b: float, dt: float) -> np.ndarray:
    """Exact one-sided PSD of ``slab_flicker``: 2 dt var(u) |sum beta_j / (1 - a_j z^-1)|^2."""
    a, beta, var = slab_modes(b, dt)
    z1 = np.exp(-2j * np.pi * np.asarray(f, float)[..., None] * dt)
    return 2 * dt * var * np.abs(np.sum(beta / (1 - a * z1), axis=-1)) ** 2


def autozero_walk(n: int, q: float, period: int, start: int, rng) -> np.ndarray:
    """Random walk (sd q a sample) re-zeroed at samples start, start + period, ..."""
    c = np.cumsum(rng.standard_normal(n) * q)
    k = np.arange(n)
    last = start + (k - start) // period * period       # the latest re-zeroing
    base = np.where(last >= 0, c[np.clip(last, 0, n - 1)], 0.0)
    return c - base


def autozero_cov(lag: np.ndarray, q: float, period: int) -> np.ndarray:
    """Phase-averaged autocovariance of ``autozero_walk``: q^2 (P - l - 1)(P - l) / (2 P)."""
    lag = np.abs(lag)
    return np.where(lag < period, q * q * (period - lag - 1.0) * (period - lag) / (2 * period),
                    0.0)


def cov_avar(cov, m: int) -> float:
    """Allan variance of block means of m samples of a stationary sequence (covariance cov)."""
    ell = np.arange(-(m - 1), m)
    w = m - np.abs(ell)
    return float((np.sum(w * cov(ell)) - np.sum(w * cov(m + ell))) / (m * m))


def ou(n: int, tc: float, dt: float, rng) -> np.ndarray:
    """Unit-variance first-order Gauss-Markov sequence, stationary from the first sample."""
    a = np.exp(-dt / tc)
    w = rng.standard_normal(n) * np.sqrt(1 - a * a)
    w[0] = rng.standard_normal()
    return signal.lfilter([1.0], [1, -a], w)


def vernier_error(theta, step: float, gain: float) -> np.ndarray:
    """Read minus true angle: coarse floor, fine cells of step / FINE read with gain (1 + g)."""
    r = np.mod(theta, step)
    cell = step / FINE
    return cell * np.round((1 + gain) * r / cell) - r


def vernier_excess(m: int, step: float, gain: float, dt: float, n_arw: float) -> float:
    """Relative Allan excess (3 c0 - 4 c_m + c_2m) / (m dt N^2) of the walking vernier error."""
    r = np.arange(2 ** 16) * step / 2 ** 16
    ch = np.abs(np.fft.rfft(vernier_error(r, step, gain)) / r.size)[1:]
    h = np.arange(1, ch.size + 1)

    def c(k):
        return 2 * np.sum(ch ** 2 * np.exp(-2 * np.pi ** 2 * h ** 2 * k * dt * n_arw ** 2
                                           / step ** 2))
    return (3 * c(0) - 4 * c(m) + c(2 * m)) / (m * dt * n_arw ** 2)


def complex_pole(n: int, freq: float, q: float, dt: float, rng) -> np.ndarray:
    """Re z of z_k = r e^(i 2 pi f dt) z_(k-1) + w_k, E|z|^2 = 1, times sqrt 2 (unit sd)."""
    p = np.exp(-np.pi * freq * dt / q + 2j * np.pi * freq * dt)
    w = (rng.standard_normal(n) + 1j * rng.standard_normal(n)) * np.sqrt((1 - abs(p) ** 2) / 2)
    z0 = (rng.standard_normal() + 1j * rng.standard_normal()) / np.sqrt(2)
    return np.sqrt(2) * signal.lfilter([1.0], [1, -p], w, zi=[p * z0])[0].real


def complex_pole_psd(f, sigma: float, freq: float, q: float, dt: float) -> np.ndarray:
    """One-sided PSD of sigma x ``complex_pole``: sigma^2 (S_z(f) + S_z(-f))."""
    p = np.exp(-np.pi * freq * dt / q + 2j * np.pi * freq * dt)
    f = np.asarray(f, float)

    def s_z(g):
        return (1 - abs(p) ** 2) * dt / np.abs(1 - p * np.exp(-2j * np.pi * g * dt)) ** 2
    return sigma ** 2 * (s_z(f) + s_z(-f))


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def frames(x, rng, a):
        return frame_smooth(x, a, int(rng.integers(FRAME)))

    def fan(x, rng, amplitude):
        f = fan_speeds(x.size, dt, rng)
        phase = 2 * np.pi * np.cumsum(f) * dt + rng.uniform(0, 2 * np.pi)
        return x + amplitude * (f / FAN_HZ[1]) ** 2 * np.sin(phase)

    def warming(x, rng, amplitude):
        return x + diffusive(np.arange(x.size) * dt + rng.uniform(0, POWER_ON), amplitude)

    def diffusion(x, rng, b):
        return x + slab_flicker(x.size, b, dt, rng)

    def autozero(x, rng, q):
        period = int(round(AUTOZERO / dt))
        return x + autozero_walk(x.size, q, period, -int(rng.integers(period)), rng)

    def product(x, rng, amplitude, tc):
        return x + amplitude * ou(x.size, PRODUCT_TC[0] * tc, dt, rng) * ou(
            x.size, PRODUCT_TC[1] * tc, dt, rng)

    def vernier(x, rng, step, gain):
        theta = rng.uniform(0, step) + np.cumsum(x) * dt
        e = vernier_error(np.r_[theta[0] - x[0] * dt, theta], step, gain)
        return x + np.diff(e) / dt

    def demodulated(x, rng, sigma, freq, q):
        return x + sigma * complex_pole(x.size, freq, q, dt, rng)

    arcsec = np.pi / 180 / 3600
    return {
        'internal_lowpass': (frames, [{'a': 0.15}, {'a': 0.5}, {'a': 0.0025}]),
        'vibration': (fan, [{'amplitude': 1e-3}, {'amplitude': 4e-3}, {'amplitude': 1.12e-4}]),
        'temperature_drift': (warming, [{'amplitude': 1.5e-3}, {'amplitude': 4e-3},
                                        {'amplitude': 1.82e-4}]),
        'bias_instability': (diffusion, [{'b': 2e-4}, {'b': 6e-4}, {'b': 4.45e-5}]),
        'rate_random_walk': (autozero, [{'q': 6e-7}, {'q': 2e-6}, {'q': 2.25e-7}]),
        'gauss_markov': (product, [{'amplitude': 1e-3, 'tc': 2.5},
                                   {'amplitude': 3e-3, 'tc': 40.0},
                                   {'amplitude': 1.63e-4, 'tc': 2.5}]),
        'quantization': (vernier, [{'step': 55 * arcsec, 'gain': 0.15},
                                   {'step': 110 * arcsec, 'gain': 0.25},
                                   {'step': 36 * arcsec, 'gain': 0.1}]),
        'resonance': (demodulated, [{'sigma': 2e-3, 'freq': 35.0, 'q': 35.0 / 3},
                                    {'sigma': 6e-3, 'freq': 28.0, 'q': 28.0 / 5},
                                    {'sigma': 4e-4, 'freq': 35.0, 'q': 35.0 / 3}]),
    }


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn, p = n * dt, n_arw ** 2, params
    if name == 'internal_lowpass':
        return frame_lag1(p['a']) * np.sqrt(n)
    if name == 'vibration':
        f, amp = fan_lines(p['amplitude'])
        z = scalloping(f, dt) ** 2 * amp ** 2 * np.sqrt(n * WELCH_L) / (18 * sig ** 2)
        return float(np.sqrt(np.sum(z ** 2)))
    if name == 'temperature_drift':
        s = diffusive(np.arange(n) * dt, p['amplitude'])
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        rel = [vernier_excess(m, p['step'], p['gain'], dt, n_arw) for m in (1, 10)]
        return abs(rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n))
    if name == 'resonance':
        ex, width = band_excess(lambda f: complex_pole_psd(f, p['sigma'], p['freq'], p['q'], dt),
                                dt, sig)
        return ex * np.sqrt(big_t * width)
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = psd_avar(lambda f: slab_psd(f, p['b'], dt), tau, dt)
    elif name == 'rate_random_walk':
        period = int(round(AUTOZERO / dt))
        excess = np.array([cov_avar(lambda ell: autozero_cov(ell, p['q'], period),
                                    int(round(t / dt))) for t in tau])
    else:
        excess = gm_avar(tau, p['amplitude'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
