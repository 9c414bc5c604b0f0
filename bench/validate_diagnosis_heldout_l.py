"""
Held-out set L of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_k.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out sets A-K, and
the kinds of departure differ from shape to shape:

- internal_lowpass: dielectric absorption: the rate converter's integrating capacitor soaks a
  fraction eps of each sample's charge into its dielectric and gives it back later through a
  spread of relaxation times (1, 10, 100 and 1000 samples, equal shares): y = (1 - eps) x +
  eps mean_i R_i(x), R_i a one-pole that releases from the next sample on; DC gain 1, a
  spike at lag 0 on a long multi-exponential tail (memory over decades, not one time);
- vibration: passing traffic: forklifts or trucks pass at Poisson times (one a minute on
  average), each shaking the floor for a few seconds: the floor's band noise (12-30 Hz,
  fourth-order Butterworth band-pass) under a Gaussian envelope of sd 2.5 s per pass, peak
  rms A: non-stationary random vibration, silent most of the time (a Gaussian scale mixture);
- temperature_drift: a duty-cycled transmitter: a telemetry radio on the same board sends for
  30 s every 300 s, heating the die through its 60 s thermal lag: the periodic steady state
  of a one-pole driven by a rectangular pulse train, A the shift continuous transmission would
  give (the ripple spans 0.39 A), random phase: a deterministic exponential sawtooth;
- bias_instability: one hopping trap: a single bistable defect whose barrier is re-drawn at
  every hop from an exponential (Boltzmann-like) distribution, so its dwell times have density
  ~ tau^-2 on 0.02 s-2e4 s; the bias is +-b, started from the stationary law (first dwell
  length-biased, log-uniform): two levels only, yet a 1/f spectrum from 1e-4 to ~5 Hz;
- rate_random_walk: slip avalanches: Gaussian slips of the die attach whose times form a
  self-exciting (Hawkes) process, each slip triggering 0.8 further slips on average after an
  exponential delay of 3 s (0.1 slips a second overall): a walk whose steps come in clusters
  (count Fano factor up to 1 / (1 - 0.8)^2 = 25) yet with uncorrelated increments;
- gauss_markov: a Pearson diffusion: X' = c X + sqrt((1 - c^2)(alpha + beta X^2)) xi, c =
  exp(-dt / tc), beta = 1/8: the agitation grows with the excursion (state-dependent noise,
  convective heat transfer that rises with the temperature difference); the linear drift keeps
  the autocorrelation exactly exp(-|tau| / tc), the multiplicative noise gives power-law tails
  (kurtosis 4.2);
- quantization: alternating counters: the host reads, on alternate samples, two fringe
  counters whose detectors sit half a step apart, read = Q floor((theta - o_k) / Q) + o_k,
  o_k = 0, Q / 2, 0, ...: a periodically time-varying quantizer, its angle error correlated
  with alternating sign at odd lags once the step exceeds the angle's walk per sample;
- resonance: a clamp that chatters: a mount mode whose fixing clamp opens and closes at Poisson
  times (mean 45 s each way), so its frequency switches between 31 Hz (open, q 25) and 36.5 Hz
  (closed, same damping rate) with its state carried over: one line at a time, two lines on
  average (regime switching, non-stationary).

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- dielectric absorption: the autocorrelations r_j of the kernel h against their white spread
  1 / sqrt(n), all lags together: z = sqrt(n sum_j r_j^2) (lag 1 alone for one-lag kernels);
- traffic, clamp: mean excess PSD / white over the band above half its peak, times sqrt(T B)
  (as sets H-K): traffic E[env^2] 2 dt |H|^2 / rms^2, E[env^2] = A^2 (lam s sqrt(pi) + (lam s
  sqrt(2 pi))^2) (Campbell); the clamp the two modes' PSDs, half each;
- transmitter: matched to its own noise-free waveform, mean removed: |s - mean(s)| / sigma;
- hopping trap, avalanches, Pearson: Allan variance excess over N^2 / tau in units of the white
  spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]: the trap
  from the alternating-renewal PSD 8 b^2 / (mu w^2) Re[(1 - psi) / (1 + psi)] (psi the dwell
  law's transform by sine and cosine integrals, mu its mean), the avalanches q^2 (2 m^2 + 1) /
  (6 m), q^2 = K^2 dt (exact: independent zero-mean slips, whatever their timing), the
  diffusion the first-order Gauss-Markov formula;
- alternating counters: the angle error's autocovariance c(m) = 2 sum_h (Q / 2 pi h)^2 (-1)^(h
  m) cos(2 pi h b m dt / Q) exp(-2 pi^2 h^2 m dt N^2 / Q^2) (the angle walking by the white
  noise and drifting with the records' bias b = 0.003 rad/s): relative Allan excess (3 c0 - 4
  c_m + c_2m) / (m dt N^2) at dt less at 10 dt, against sqrt(3 / n + 40 / (3 n)).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
Physical scale: absorbed fractions of 2.1 % (edge), 12 % and 40 %; passes of 0.094, 0.34 and
1.15 deg/s peak rms; transmitter shifts of 0.017, 0.086 and 0.29 deg/s (1.3-21 degC at 0.0135
(deg/s)/degC, ripples 0.39 of that); traps of +-21, 82 and 206 deg/h; avalanche walks of K
2e-6, 6e-6 and 2e-5 rad/s/sqrt(s); diffusions of 0.0078, 0.057 and 0.115 deg/s sd (tc 5 s,
5 s and 40 s); counter steps of 4.2, 43 and 115 arcsec; chattering modes of 0.022, 0.11 and
0.34 deg/s sd.
"""
from heldout_detect import allan_taus, allan_z, band_excess, gm_avar, psd_avar
import numpy as np
from scipy import signal, special
from validate_diagnosis_heldout_k import walk_avar

SOAK_TAUS = np.array([1.0, 10.0, 100.0, 1000.0])   # samples: the dielectric's release times
SOAK_LAGS = 12000                                  # kernel length kept for the correlations
TRAFFIC_S, BURST_S = 60.0, 2.5                     # mean s between passes, envelope sd (s)
FLOOR_HZ = (12.0, 30.0)                            # the floor's band (4th-order Butterworth)
RADIO_S, TX_S, DIE_S = 300.0, 30.0, 60.0           # transmit cycle, burst, die thermal lag
HOP_S = (0.02, 2.0e4)                              # s: the trap's shortest and longest dwell
AVALANCHE = (0.1, 0.8, 3.0)                        # slips per s, branching ratio, kernel (s)
PEARSON = 0.125                                    # state-dependent part of the diffusion
BIAS = 0.003                                       # rad/s: the static records' bias
CLAMP_HZ, CLAMP_Q, CLAMP_S = (31.0, 36.5), 25.0, 45.0   # open / clamped mode, q open, dwell


def soak_kernel(eps: float, lags: int = SOAK_LAGS) -> np.ndarray:
    """h_0 = 1 - eps, h_j = eps mean_i (1 - c_i) c_i^(j-1): absorbed now, released later."""
    c = np.exp(-1.0 / SOAK_TAUS)[:, None]
    j = np.arange(1, lags)[None, :]
    return np.r_[1 - eps, eps * np.mean((1 - c) * c ** (j - 1), axis=0)]


def soak(x: np.ndarray, eps: float) -> np.ndarray:
    """Return (1 - eps) x plus eps times x released through the one-poles SOAK_TAUS (DC gain 1)."""
    out = (1 - eps) * x
    for tau in SOAK_TAUS:
        c = np.exp(-1.0 / tau)
        b, a = [0.0, 1 - c], [1.0, -c]
        out += eps / SOAK_TAUS.size * signal.lfilter(b, a, x, zi=signal.lfilter_zi(b, a) * x[0])[0]
    return out


def kernel_corr(h: np.ndarray) -> np.ndarray:
    """Autocorrelation r_j (j >= 1) of white noise through the FIR ``h``."""
    m = 1 << int(np.ceil(np.log2(2 * h.size)))
    s = np.fft.irfft(np.abs(np.fft.rfft(h, m)) ** 2, m)[:h.size]
    return s[1:] / s[0]


def floor_band(dt: float):
    """SOS of the floor's band-pass and the rms of its unit-white response."""
    sos = signal.butter(2, FLOOR_HZ, 'bandpass', fs=1 / dt, output='sos')
    imp = signal.sosfilt(sos, np.r_[1.0, np.zeros(2 ** 14)])
    return sos, float(np.sqrt(np.sum(imp ** 2)))


def envelope_power(amplitude: float) -> float:
    """E[env^2] of Gaussian envelopes (sd BURST_S, peak ``amplitude``) at Poisson times."""
    mean = BURST_S / TRAFFIC_S
    return amplitude ** 2 * (mean * np.sqrt(np.pi) + (mean * np.sqrt(2 * np.pi)) ** 2)


def traffic(n: int, amplitude: float, dt: float, rng) -> np.ndarray:
    """Floor-band noise under Gaussian envelopes at Poisson pass times."""
    sos, rms = floor_band(dt)
    carrier = signal.sosfilt(sos, rng.standard_normal(n + 4096))[4096:] / rms
    span = int(5 * BURST_S / dt)
    t0 = rng.uniform(-span, n + span, rng.poisson((n + 2 * span) * dt / TRAFFIC_S))
    env = np.zeros(n + 4 * span + 1)
    k = np.arange(-span, span + 1)
    for c in t0:
        at = int(np.floor(c))
        env[at + span:at + 3 * span + 1] += np.exp(-0.5 * ((k + at - c) * dt / BURST_S) ** 2)
    return amplitude * env[2 * span:2 * span + n] * carrier


def traffic_psd(f, amplitude: float, dt: float) -> np.ndarray:
    """One-sided mean PSD: E[env^2] times the unit-variance floor band's 2 dt |H|^2 / rms^2."""
    sos, rms = floor_band(dt)
    _, h = signal.sosfreqz(sos, worN=np.asarray(f, float), fs=1 / dt)
    return envelope_power(amplitude) * 2 * dt * np.abs(h) ** 2 / rms ** 2


def radio_heat(t, amplitude: float) -> np.ndarray:
    """Periodic steady state of a DIE_S one-pole driven by TX_S on every RADIO_S (peak A = 1)."""
    u = np.mod(np.asarray(t, float), RADIO_S)
    lo = np.exp(-(RADIO_S - TX_S) / DIE_S) * (1 - np.exp(-TX_S / DIE_S)) / (
        1 - np.exp(-RADIO_S / DIE_S))
    hi = 1 - (1 - lo) * np.exp(-TX_S / DIE_S)
    return amplitude * np.where(u < TX_S, 1 - (1 - lo) * np.exp(-u / DIE_S),
                                hi * np.exp(-(u - TX_S) / DIE_S))


def hop_dwells(size: int, rng) -> np.ndarray:
    """Dwell times of density ~ tau^-2 on HOP_S (inverse CDF)."""
    a, b = HOP_S
    return 1 / (1 / a - rng.uniform(size=size) * (1 / a - 1 / b))


def hopper(n: int, b: float, dt: float, rng) -> np.ndarray:
    """One two-level trap (+-b), dwells ~ tau^-2, started from its stationary law."""
    a, top = HOP_S
    first = a * (top / a) ** rng.uniform() * rng.uniform()       # length-biased, residual
    edges = [np.array([first])]
    total, mean = first, np.log(top / a) / (1 / a - 1 / top)
    while total < n * dt:
        d = hop_dwells(int(2 * (n * dt - total) / mean) + 100, rng)
        edges.append(d)
        total += d.sum()
    ends = np.cumsum(np.concatenate(edges))
    state = np.searchsorted(ends, np.arange(n) * dt, side='right')
    return b * np.where(state % 2 == 0, 1.0, -1.0) * rng.choice([-1.0, 1.0])


def hopper_psd(f, b: float) -> np.ndarray:
    """One-sided PSD (8 b^2 / (mu w^2)) Re[(1 - psi) / (1 + psi)], psi the dwell's transform."""
    w = 2 * np.pi * np.maximum(np.asarray(f, float), 1e-12)
    a, top = HOP_S
    norm = 1 / a - 1 / top
    si_t, ci_t = special.sici(w * top)
    si_a, ci_a = special.sici(w * a)
    re = (2 * np.sin(w * a / 2) ** 2 / a - 2 * np.sin(w * top / 2) ** 2 / top
          + w * (si_t - si_a)) / norm                               # int (1 - cos) p
    im = -(np.sin(w * a) / a - np.sin(w * top) / top + w * (ci_t - ci_a)) / norm   # -int sin p
    mu = np.log(top / a) / norm
    ratio = (re * (2 - re) - im * im) / ((2 - re) ** 2 + im * im)
    return 8 * b * b / (mu * w * w) * ratio


def avalanche(n: int, k: float, dt: float, rng) -> np.ndarray:
    """Gaussian slips at the times of a Hawkes process (exponential kernel), summed into a walk."""
    lam, eta, kern = AVALANCHE
    burn = 30 * kern / (1 - eta)
    gen = rng.uniform(-burn, n * dt, rng.poisson(lam * (1 - eta) * (n * dt + burn)))
    times = [gen]
    while gen.size:
        kids = rng.poisson(eta, gen.size)
        gen = np.repeat(gen, kids) + rng.exponential(kern, kids.sum())
        gen = gen[gen < n * dt]
        times.append(gen)
    t = np.concatenate(times)
    t = t[t >= 0]
    steps = np.bincount((t / dt).astype(int), rng.standard_normal(t.size), minlength=n)[:n]
    return np.cumsum(steps) * k / np.sqrt(lam)


def pearson(n: int, sd: float, tc: float, dt: float, rng) -> np.ndarray:
    """Return X' = c X + sqrt((1 - c^2)(alpha + beta X^2)) xi: exponential correlation."""
    c = np.exp(-dt / tc)
    alpha, g = sd * sd * (1 - PEARSON), np.sqrt(1 - c * c)
    burn = int(5 * tc / dt)
    xi = rng.standard_normal(n + burn).tolist()
    out = np.empty(n + burn)
    v = sd * xi[0]
    for i, e in enumerate(xi):
        v = c * v + g * np.sqrt(alpha + PEARSON * v * v) * e
        out[i] = v
    return out[burn:]


def pearson_kurtosis(c: float, beta: float = PEARSON) -> float:
    """Stationary kurtosis of ``pearson`` (unit variance): the fourth-moment recursion solved."""
    alpha, g = 1 - beta, 1 - c * c
    num = 6 * c * c * g * alpha + 3 * g * g * (alpha ** 2 + 2 * alpha * beta)
    return num / (1 - c ** 4 - 6 * c * c * g * beta - 3 * g * g * beta ** 2)


def pair_excess(m: int, step: float, dt: float, n_arw: float) -> float:
    """Relative Allan excess (3 c0 - 4 c_m + c_2m) / (m dt N^2) of the alternating counters."""
    h = np.arange(1, 4001)

    def c(lag):
        if lag == 0:
            return step ** 2 / 12
        sign = (-1.0) ** (h * (lag % 2))                       # offsets Q / 2 apart
        drift = np.cos(2 * np.pi * h * BIAS * lag * dt / step)
        return 2 * np.sum((step / (2 * np.pi * h)) ** 2 * sign * drift * np.exp(
            -2 * np.pi ** 2 * h ** 2 * lag * dt * n_arw ** 2 / step ** 2))
    return (3 * c(0) - 4 * c(m) + c(2 * m)) / (m * dt * n_arw ** 2)


def clamp_coeffs(state: int, dt: float):
    """(a1, a2, variance) of the mode open (0) or clamped (1): same damping rate."""
    gamma = np.pi * CLAMP_HZ[0] / CLAMP_Q
    r = np.exp(-gamma * dt)
    a1, a2 = 2 * r * np.cos(2 * np.pi * CLAMP_HZ[state] * dt), -r * r
    return a1, a2, (1 - a2) / ((1 + a2) * ((1 - a2) ** 2 - a1 * a1))


def clamp_mode(n: int, sigma: float, dt: float, rng) -> np.ndarray:
    """Return a mode whose frequency toggles at Poisson times, its state carried over."""
    burn = int(2.0 / dt)
    out, prev, state, at = np.zeros(n + burn), [0.0, 0.0], int(rng.integers(2)), 0
    while at < n + burn:
        end = min(n + burn, at + 1 + int(rng.exponential(CLAMP_S) / dt))
        a1, a2, var = clamp_coeffs(state, dt)
        zi = signal.lfiltic([1.0], [1.0, -a1, -a2], prev)
        out[at:end] = signal.lfilter([1.0], [1.0, -a1, -a2],
                                     rng.standard_normal(end - at) / np.sqrt(var), zi=zi)[0]
        prev = [out[end - 1], out[end - 2]]
        at, state = end, 1 - state
    return sigma * out[burn:]


def clamp_psd(f, sigma: float, dt: float) -> np.ndarray:
    """One-sided mean PSD: half the time each mode, each of variance sigma^2."""
    z1 = np.exp(-2j * np.pi * np.asarray(f, float) * dt)
    total = 0.0
    for state in (0, 1):
        a1, a2, var = clamp_coeffs(state, dt)
        total = total + 0.5 * 2 * dt / var / np.abs(1 - a1 * z1 - a2 * z1 * z1) ** 2
    return sigma ** 2 * total


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def absorb(x, rng, eps):
        return soak(x, eps)

    def trucks(x, rng, amplitude):
        return x + traffic(x.size, amplitude, dt, rng)

    def radio(x, rng, amplitude):
        return x + radio_heat(np.arange(x.size) * dt + rng.uniform(0, RADIO_S), amplitude)

    def trap(x, rng, b):
        return x + hopper(x.size, b, dt, rng)

    def slips(x, rng, k):
        return x + avalanche(x.size, k, dt, rng)

    def diffusion(x, rng, sd, tc):
        return x + pearson(x.size, sd, tc, dt, rng)

    def counters(x, rng, step):
        start = rng.uniform(0, step)
        theta = start + np.cumsum(x) * dt
        off = (np.arange(x.size) % 2) * step / 2
        err = np.mod(theta - off, step)                          # read = theta - err
        return x - np.diff(np.r_[0.0, err]) / dt

    def clamp(x, rng, sigma):
        return x + clamp_mode(x.size, sigma, dt, rng)

    return {
        'internal_lowpass': (absorb, [{'eps': 0.12}, {'eps': 0.4}, {'eps': 0.0214}]),
        'vibration': (trucks, [{'amplitude': 6e-3}, {'amplitude': 2e-2},
                               {'amplitude': 1.64e-3}]),
        'temperature_drift': (radio, [{'amplitude': 1.5e-3}, {'amplitude': 5e-3},
                                      {'amplitude': 3.05e-4}]),
        'bias_instability': (trap, [{'b': 4e-4}, {'b': 1e-3}, {'b': 1.0e-4}]),
        'rate_random_walk': (slips, [{'k': 6e-6}, {'k': 2e-5}, {'k': 2.03e-6}]),
        'gauss_markov': (diffusion, [{'sd': 1e-3, 'tc': 5.0}, {'sd': 2e-3, 'tc': 40.0},
                                     {'sd': 1.37e-4, 'tc': 5.0}]),
        'quantization': (counters, [{'step': 3 * n_arw * np.sqrt(dt)},
                                    {'step': 8 * n_arw * np.sqrt(dt)},
                                    {'step': 0.291 * n_arw * np.sqrt(dt)}]),
        'resonance': (clamp, [{'sigma': 2e-3}, {'sigma': 6e-3}, {'sigma': 3.77e-4}]),
    }


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn, p = n * dt, n_arw ** 2, params
    if name == 'internal_lowpass':
        return float(np.sqrt(n * np.sum(kernel_corr(soak_kernel(p['eps'])) ** 2)))
    if name == 'temperature_drift':
        s = radio_heat(np.arange(n) * dt, p['amplitude'])
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        rel = [pair_excess(m, p['step'], dt, n_arw) for m in (1, 10)]
        return float(abs(rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n)))
    if name in ('vibration', 'resonance'):
        psd = ((lambda f: traffic_psd(f, p['amplitude'], dt)) if name == 'vibration' else
               (lambda f: clamp_psd(f, p['sigma'], dt)))
        ex, width = band_excess(psd, dt, sig)
        return float(ex * np.sqrt(big_t * width))
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = psd_avar(lambda f: hopper_psd(f, p['b']), tau, dt)
    elif name == 'rate_random_walk':
        excess = walk_avar(np.round(tau / dt), p['k'] * np.sqrt(dt))
    else:
        excess = gm_avar(tau, p['sd'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
