"""
Held-out set M of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_l.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out sets A-L, and
the kinds of departure differ from shape to shape:

- internal_lowpass: a warming switched-capacitor pole: the output one-pole's clock comes from
  an on-chip RC oscillator that speeds up as the die warms after power-on, so its pole relaxes
  from a towards 0, y_k = a_k y_(k-1) + (1 - a_k) x_k, a_k = a exp(-t' / 900 s), t' = t + t0,
  t0 in 0-60 s: smoothing that fades through the record (non-stationary; DC gain 1);
- vibration: buffeting by a draught: an air-conditioning vent blows on the bench and the
  mount transmits the turbulence's von Karman spectrum above its 3 Hz high-pass, one-sided
  PSD ~ f^2 / (f^2 + 3^2) (1 + (f / 2 Hz)^2)^(-5 / 6), rms A: a broad, Gaussian, power-law
  (f^-5/3) continuum over decades of frequency, no line (FFT synthesis);
- temperature_drift: radial spreading: a regulator on a large board heats it from a point,
  the heat spreads in two dimensions and the die at distance r follows the line-source
  solution A E1(t_d / (t + t0)) (t_d = r^2 / 4 alpha = 300 s, t0 in 0-60 s): a dead time,
  then a logarithmic rise that never settles (A the bias per e-fold of time);
- bias_instability: log-normal flicker: a leakage current across a junction whose barrier
  height carries 1/f noise (a Gaussian sum of eleven first-order processes, two per decade,
  0.03-3000 s, unit variance) grows exponentially with it: b (exp(s g) - e^(s^2 / 2)) /
  sqrt(e^(s^2) (e^(s^2) - 1)), s = 0.8: sd b, skewed (skew 3.7), large upward excursions;
- rate_random_walk: crackling slips: the die attach's epoxy releases stress in micro-cracks at
  Poisson times (2 a second), symmetric sizes with a Pareto tail of index 3 (Gutenberg-Richter
  like: finite variance, infinite kurtosis): a walk with heavy-tailed increments, K^2 = lambda
  E[size^2];
- gauss_markov: asymmetric popcorn: a defect whose charged state is rare (occupied 10 % of the
  time) switches at exponential times, correlation time tc = 1 / (rate up + rate down): bursts
  of +Delta from a baseline (skew 2.7), autocorrelation exactly exp(-|tau| / tc), mean removed;
- quantization: a float32 angle: the sensor integrates the rate in double precision and
  publishes its angle since power-on as float32; the host differences it: the angle is rounded
  to the float's spacing, 2^(floor(log2 theta) - 23), which is set by how much angle the bias
  has accumulated (theta0, days of uptime) and doubles as theta passes a power of two;
- resonance: a dangling cable: the IMU's cable hangs as a taut string whose first four modes
  (9.5, 19, 28.5 and 38 Hz, one damping rate, width 0.475 Hz) are driven by air currents, mode
  n with variance ~ 1 / n^2: a harmonic comb of lines.

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- warming pole: the pooled lag-1 autocorrelation sum_k a_(k+1) v_k / sum_k v_k (v_k the output
  variance, v_k = a_k^2 v_(k-1) + (1 - a_k)^2, t0 = 30 s) against 1 / sqrt(n);
- buffeting, cable: mean excess PSD / white over the band above half its peak, times
  sqrt(T B) (as sets H-L);
- radial spreading: matched to its own noise-free waveform (t0 = 30 s), mean removed:
  |s - mean(s)| / sigma;
- log-normal flicker, crackling, popcorn: Allan variance excess over N^2 / tau in units of the
  white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]: the
  flicker from its autocovariance b^2 (e^(s^2 rho) - 1) / (e^(s^2) - 1) (rho the Gaussian's),
  AVAR(tau) = tau^-2 int_0^(2 tau) R(u) k(u) du, k = 2 tau - 3 u below tau and u - 2 tau
  above; the slips q^2 (2 m^2 + 1) / (6 m), q^2 = K^2 dt (exact: independent zero-mean steps);
  the popcorn the first-order Gauss-Markov formula;
- float32 angle: the rounding error's autocovariance per binade c(m) = 2 sum_h (q / 2 pi h)^2
  cos(2 pi h b m dt / q) exp(-2 pi^2 h^2 m dt N^2 / q^2) (the angle walking by the white noise
  and drifting with the records' bias b = 0.003 rad/s), weighted by the time spent in each
  binade: relative Allan excess (3 c0 - 4 c_m + c_2m) / (m dt N^2) at dt less at 10 dt, against
  sqrt(3 / n + 40 / (3 n)).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
Physical scale: warming poles of 0.040 (edge; a corner above Nyquist), 0.5 and 0.9 (11 and 1.7
Hz) at power-on; buffeting of 0.027, 0.11 and 0.46 deg/s rms; spreading of 0.0027, 0.029 and
0.11 deg/s per e-fold (0.0072-0.30 deg/s after 2 h, 0.5-22 degC at 0.0135 (deg/s)/degC);
log-normal flicker of sd 22, 83 and 206 deg/h; crackling walks of K 2e-6, 6e-6 and 2e-5
rad/s/sqrt(s); popcorn of 0.0099, 0.057 and 0.11 deg/s sd (bursts 0.033-0.38 deg/s high; tc
2 s, 2 s and 20 s); float32 angles of 240, 2000 and 20000 rad (0.9, 7.7 and 77 days of the
bias; spacings 3.1 -> 6.3, 25 and 403 arcsec); cable modes of 0.017, 0.11 and 0.34 deg/s sd.
"""
from heldout_detect import allan_taus, allan_z, band_excess, gm_avar
import numpy as np
from scipy import signal, special
from validate_diagnosis_heldout_k import walk_avar

WARM_S = 900.0                                     # s: the oscillator's warm-up
GUST_HZ = (3.0, 2.0)                               # mount high-pass, turbulence scale (Hz)
SPREAD_S = 300.0                                   # s: r^2 / (4 alpha), the heat's arrival
FLICKER_TAUS = 0.03 * 10.0 ** (np.arange(11) / 2)  # s: the barrier's Gauss-Markov times
LOGNORMAL = 0.8                                    # s: the exponent's sd
CRACK_RATE, CRACK_TAIL = 2.0, 3.0                  # slips per s, Pareto tail index
POP_UP = 0.1                                       # share of time in the charged state
BIAS = 0.003                                       # rad/s: the static records' bias
MANTISSA = 23                                      # float32 fraction bits
CABLE_HZ, CABLE_Q = 9.5 * np.arange(1, 5), 20.0    # string modes; q of the first


def pole_track(a: float, n: int, dt: float, t0: float) -> np.ndarray:
    """Pole a_k = a exp(-(k dt + t0) / WARM_S) of the warming one-pole."""
    return a * np.exp(-(np.arange(n) * dt + t0) / WARM_S)


def warming_pole(x: np.ndarray, a: float, dt: float, t0: float) -> np.ndarray:
    """Return y_k = a_k y_(k-1) + (1 - a_k) x_k (y_(-1) = x_0), the pole relaxing as it warms."""
    ak = pole_track(a, x.size, dt, t0)
    live = int(np.searchsorted(-ak, -1e-15))          # where the pole has faded to nothing
    out = x.astype(float).copy()
    prev = float(x[0])
    for k, (c, v) in enumerate(zip(ak[:live].tolist(), x[:live].tolist())):
        prev = c * prev + (1 - c) * v
        out[k] = prev
    return out


def pooled_r1(a: float, n: int, dt: float, t0: float = 30.0) -> float:
    """Pooled lag-1 autocorrelation of the warming pole's output for unit white input."""
    ak = pole_track(a, n, dt, t0)
    v, prev = np.empty(n), 1.0
    for k, c in enumerate(ak.tolist()):
        prev = c * c * prev + (1 - c) ** 2
        v[k] = prev
    return float(np.sum(ak[1:] * v[:-1]) / np.sum(v))


def gust_shape(f) -> np.ndarray:
    """Unnormalised one-sided PSD: mount high-pass times the von Karman (1 + (f/fL)^2)^(-5/6)."""
    f = np.abs(np.asarray(f, float))
    hp, scale = GUST_HZ
    return f * f / (f * f + hp * hp) * (1 + (f / scale) ** 2) ** (-5.0 / 6.0)


def gust_psd(f, amplitude: float, dt: float) -> np.ndarray:
    """One-sided PSD of the buffeting of rms ``amplitude`` (its shape integrates to A^2)."""
    g = np.linspace(0, 0.5 / dt, 200001)
    return amplitude ** 2 * gust_shape(f) / np.trapezoid(gust_shape(g), g)


def buffeting(n: int, amplitude: float, dt: float, rng) -> np.ndarray:
    """Gaussian noise of PSD ``gust_psd`` by one FFT (rms ``amplitude``)."""
    f = np.fft.rfftfreq(n, dt)
    full = gust_shape(np.fft.fftfreq(n, dt))
    gain = np.sqrt(gust_shape(f) / full.mean())
    return amplitude * np.fft.irfft(np.fft.rfft(rng.standard_normal(n)) * gain, n)


def spreading(t, amplitude: float) -> np.ndarray:
    """Line-source heating A E1(SPREAD_S / t) (t from power-on, s; 0 at t = 0)."""
    t = np.maximum(np.asarray(t, float), 1e-9)
    return amplitude * special.exp1(SPREAD_S / t)


def barrier(n: int, dt: float, rng) -> np.ndarray:
    """Unit-variance Gaussian 1/f-like sum of FLICKER_TAUS first-order processes (stationary)."""
    out = np.zeros(n)
    for tau in FLICKER_TAUS:
        c = np.exp(-dt / tau)
        w = rng.standard_normal(n) * np.sqrt(1 - c * c)
        out += signal.lfilter([1.0], [1.0, -c], w, zi=[c * rng.standard_normal()])[0]
    return out / np.sqrt(FLICKER_TAUS.size)


def lognormal_flicker(n: int, b: float, dt: float, rng, s: float = LOGNORMAL) -> np.ndarray:
    """Return b (exp(s g) - e^(s^2/2)) / sd, g the unit barrier noise: sd b, mean 0."""
    sd = np.sqrt(np.exp(s * s) * (np.exp(s * s) - 1))
    return b * (np.exp(s * barrier(n, dt, rng)) - np.exp(s * s / 2)) / sd


def cov_avar(cov, tau) -> np.ndarray:
    """Allan variance tau^-2 int_0^(2 tau) R(u) k(u) du of a stationary autocovariance ``cov``."""
    v = np.geomspace(1e-7, 1.0, 4000)
    grid = np.unique(np.r_[0.0, v, 1 + v])
    kern = np.where(grid < 1, 2 - 3 * grid, grid - 2)
    return np.array([np.trapezoid(cov(grid * tt) * kern, grid)
                     for tt in np.atleast_1d(tau)])


def flicker_cov(u, b: float, s: float = LOGNORMAL) -> np.ndarray:
    """Autocovariance b^2 (e^(s^2 rho(u)) - 1) / (e^(s^2) - 1) of ``lognormal_flicker``."""
    rho = np.mean(np.exp(-np.abs(np.asarray(u, float))[..., None] / FLICKER_TAUS), axis=-1)
    return b * b * np.expm1(s * s * rho) / np.expm1(s * s)


def crackle(n: int, k: float, dt: float, rng) -> np.ndarray:
    """Symmetric Pareto(CRACK_TAIL) slips at Poisson times, summed into a walk of intensity K."""
    a = CRACK_TAIL
    xm = k / np.sqrt(CRACK_RATE * a / (a - 2))
    count = rng.poisson(CRACK_RATE * n * dt)
    at = rng.integers(0, n, count)
    size = xm * rng.uniform(size=count) ** (-1 / a) * rng.choice([-1.0, 1.0], count)
    return np.cumsum(np.bincount(at, size, minlength=n))


def popcorn(n: int, sd: float, tc: float, dt: float, rng, p: float = POP_UP) -> np.ndarray:
    """Two-level switching, up a share p of the time, correlation tc; sd ``sd``, mean 0."""
    up = rng.uniform() < p
    dwell = [tc / p, tc / (1 - p)]                     # mean time down, up
    first = rng.exponential(dwell[int(up)])
    total, pieces = first, [np.array([first])]
    while total < n * dt:
        d = rng.exponential(1.0, 2 * (int((n * dt - total) / tc) + 50))
        d[0::2] *= dwell[1 - int(up)]
        d[1::2] *= dwell[int(up)]
        pieces.append(d)
        total += d.sum()
    ends = np.cumsum(np.concatenate(pieces))
    state = (np.searchsorted(ends, np.arange(n) * dt, side='right') + int(up)) % 2
    return sd * (state - p) / np.sqrt(p * (1 - p))


def float_spacing(theta) -> np.ndarray:
    """Spacing of float32 numbers at |theta| (normal range): 2^(floor(log2 |theta|) - 23)."""
    return 2.0 ** (np.floor(np.log2(np.abs(np.asarray(theta, float)))) - MANTISSA)


def float_excess(m: int, theta0: float, dt: float, n_arw: float, n: int = 720000) -> float:
    """Relative Allan excess (3 c0 - 4 c_m + c_2m) / (m dt N^2) of the float32 angle."""
    q_all = float_spacing(theta0 + BIAS * np.arange(n) * dt)
    qs, counts = np.unique(q_all, return_counts=True)
    h = np.arange(1, 4001)

    def c(lag):
        total = 0.0
        for q, w in zip(qs, counts / n):
            if lag == 0:
                total += w * q * q / 12
                continue
            total += w * 2 * np.sum((q / (2 * np.pi * h)) ** 2 * np.cos(
                2 * np.pi * h * BIAS * lag * dt / q) * np.exp(
                -2 * np.pi ** 2 * h ** 2 * lag * dt * n_arw ** 2 / q ** 2))
        return total
    return (3 * c(0) - 4 * c(m) + c(2 * m)) / (m * dt * n_arw ** 2)


def cable_coeffs(mode: int, dt: float):
    """(a1, a2, unit-drive variance) of string mode ``mode`` (0-based), one damping rate."""
    r = np.exp(-np.pi * CABLE_HZ[0] / CABLE_Q * dt)
    a1, a2 = 2 * r * np.cos(2 * np.pi * CABLE_HZ[mode] * dt), -r * r
    return a1, a2, (1 - a2) / ((1 + a2) * ((1 - a2) ** 2 - a1 * a1))


def cable_shares() -> np.ndarray:
    """Variance shares of the modes, ~ 1 / n^2, summing to 1."""
    w = 1.0 / np.arange(1, CABLE_HZ.size + 1) ** 2
    return w / w.sum()


def cable(n: int, sigma: float, dt: float, rng) -> np.ndarray:
    """Sum of the string's modes, each white-driven, total sd ``sigma``."""
    burn = int(20.0 / dt)
    out = np.zeros(n)
    for mode, share in enumerate(cable_shares()):
        a1, a2, var = cable_coeffs(mode, dt)
        e = rng.standard_normal(n + burn) * np.sqrt(share / var)
        out += signal.lfilter([1.0], [1.0, -a1, -a2], e)[burn:]
    return sigma * out


def cable_psd(f, sigma: float, dt: float) -> np.ndarray:
    """One-sided PSD of ``cable``: each mode's 2 dt share / (var |1 - a1 z^-1 - a2 z^-2|^2)."""
    z1 = np.exp(-2j * np.pi * np.asarray(f, float) * dt)
    total = 0.0
    for mode, share in enumerate(cable_shares()):
        a1, a2, var = cable_coeffs(mode, dt)
        total = total + 2 * dt * share / var / np.abs(1 - a1 * z1 - a2 * z1 * z1) ** 2
    return sigma ** 2 * total


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def warming(x, rng, a):
        return warming_pole(x, a, dt, rng.uniform(0, 60))

    def draught(x, rng, amplitude):
        return x + buffeting(x.size, amplitude, dt, rng)

    def spread(x, rng, amplitude):
        return x + spreading(np.arange(x.size) * dt + rng.uniform(0, 60), amplitude)

    def leakage(x, rng, b):
        return x + lognormal_flicker(x.size, b, dt, rng)

    def cracks(x, rng, k):
        return x + crackle(x.size, k, dt, rng)

    def pops(x, rng, sd, tc):
        return x + popcorn(x.size, sd, tc, dt, rng)

    def float_angle(x, rng, theta0):
        theta = theta0 + np.cumsum(x) * dt
        err = theta - theta.astype(np.float32).astype(float)
        return x - np.diff(np.r_[theta0 - float(np.float32(theta0)), err]) / dt

    def strings(x, rng, sigma):
        return x + cable(x.size, sigma, dt, rng)

    return {
        'internal_lowpass': (warming, [{'a': 0.5}, {'a': 0.9}, {'a': 0.040}]),
        'vibration': (draught, [{'amplitude': 2e-3}, {'amplitude': 8e-3},
                                {'amplitude': 4.76e-4}]),
        'temperature_drift': (spread, [{'amplitude': 5e-4}, {'amplitude': 2e-3},
                                       {'amplitude': 4.72e-5}]),
        'bias_instability': (leakage, [{'b': 4e-4}, {'b': 1e-3}, {'b': 1.08e-4}]),
        'rate_random_walk': (cracks, [{'k': 6e-6}, {'k': 2e-5}, {'k': 2.03e-6}]),
        'gauss_markov': (pops, [{'sd': 1e-3, 'tc': 2.0}, {'sd': 2e-3, 'tc': 20.0},
                                {'sd': 1.72e-4, 'tc': 2.0}]),
        'quantization': (float_angle, [{'theta0': 2000.0}, {'theta0': 20000.0},
                                       {'theta0': 240.0}]),
        'resonance': (strings, [{'sigma': 2e-3}, {'sigma': 6e-3}, {'sigma': 3.0e-4}]),
    }


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn, p = n * dt, n_arw ** 2, params
    if name == 'internal_lowpass':
        return float(pooled_r1(p['a'], n, dt) * np.sqrt(n))
    if name == 'temperature_drift':
        s = spreading(np.arange(n) * dt + 30.0, p['amplitude'])
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        rel = [float_excess(m, p['theta0'], dt, n_arw, n) for m in (1, 10)]
        return float(abs(rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n)))
    if name in ('vibration', 'resonance'):
        psd = ((lambda f: gust_psd(f, p['amplitude'], dt)) if name == 'vibration' else
               (lambda f: cable_psd(f, p['sigma'], dt)))
        ex, width = band_excess(psd, dt, sig)
        return float(ex * np.sqrt(big_t * width))
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = cov_avar(lambda u: flicker_cov(u, p['b']), tau)
    elif name == 'rate_random_walk':
        excess = walk_avar(np.round(tau / dt), p['k'] * np.sqrt(dt))
    else:
        excess = gm_avar(tau, p['sd'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
