"""
Held-out set K of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_j.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out sets A-J, and
the kinds of departure differ from shape to shape:

- internal_lowpass: a jitter gate: the sensor hub smooths only what it takes for jitter; a new
  sample within s of the current output moves it a quarter of the way, y_k = y_(k-1) +
  0.25 (x_k - y_(k-1)), a larger change passes at once, y_k = x_k: a nonlinear, data-selective
  smoother with memory, heavy smoothing of small changes, none of large ones (a one-pole of
  0.75 as s grows, the identity as s falls);
- vibration: a shaker test next door: a sine sweep 10 -> 40 -> 10 Hz at one octave a minute
  (logarithmic, continuous phase, IEC 60068-2-6 style), held at constant acceleration, so the
  bench's rocking rate falls as 1 / f (A at 10 Hz, A / 4 at 40 Hz): a deterministic waveform
  whose power is spread over a band, density ~ f^-3, no line;
- temperature_drift: a fan-interrupted warm-up: the die warms with a 600 s lag toward T_hot
  until the board reaches the fan's thermostat at 0.6 T_hot (550 s after power-on); the fan
  then cools it, with a 200 s lag, toward 0.3 T_hot: a rise, a kink (the slope jumps from
  +A / 1500 s to -A / 667 s) and a settling to a lower level; the record starts 0-60 s after
  power-on;
- bias_instability: nulled flicker: the quadrature error has flicker noise, the quadrature
  loop (an integrator, time constant 200 s) nulls its slow part and the demodulation phase
  error leaks the rest into the rate: white noise of sd b through (1 - z^-1)^-1/2 and the
  loop's residual (1 - z^-1) / (1 - (1 - dt / 200 s) z^-1): PSD b^2 / (pi f) above the 8e-4
  Hz corner, rising as f below it (no power at DC);
- rate_random_walk: a ratchet: the die attach slips under a steady stress at Poisson times
  (one per 20 s), always the same way, by exponentially distributed amounts, and creeps back
  between slips at the steady rate that balances them: sudden steps up, straight ramps down,
  a walk with independent, skewed increments (skewness 2.1 / sqrt(lambda tau)), K^2 = 2
  lambda beta^2;
- gauss_markov: a blower-modulated Markov process: convective temperature noise with the
  package's correlation time tc, driven by turbulence whose intensity follows the HVAC blower,
  1 + 0.9 sin(2 pi t / 900 s): cyclostationary (its variance swings 0.1-1.9 x, lagged by tc),
  a Gaussian scale mixture overall, time-averaged autocorrelation exactly exp(-|tau| / tc);
- quantization: interpolator fallback: an interpolated fringe read-out drops to whole-fringe
  counting (the floor quantizer of step Q) whenever its interpolator loses lock, in spells of
  mean 60 s between locked spells of mean 300 s (a two-state Markov chain, 1/6 of the time):
  intermittent angle quantization, the read angle stepping by the floor error at each switch;
- resonance: an aliased mode: a mount mode above the output Nyquist frequency, the output
  read from an internal stream 10 x faster by taking every 10th sample (no anti-alias
  filter): the line folds to |f0 - k / dt| (137 Hz to 37 Hz, 172 Hz mirrored to 28 Hz),
  its skirts folded too (the mirrored one steep side down), and all images add a floor.

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- jitter gate: lag-1 autocorrelation against 1 / sqrt(n); the output is a Markov chain whose
  stationary law is solved on a grid, E[y y'] from the exact conditional mean (1 - a)(y A -
  M) (A, M the input's mass and first moment within s of y): r1 grows as s^3 at first;
- shaker, aliased mode: mean excess PSD / white over the band above half its peak, times
  sqrt(T B) (as sets H-J): the sweep's mean PSD (A f1 / f)^2 / (2 f ln 4) on 10-40 Hz (time
  share 1 / (f ln 4) per Hz), the mode's internal PSD summed over its ten images;
- fan warm-up: matched to its own noise-free waveform, mean removed: |s - mean(s)| / sigma;
- nulled flicker, ratchet, blower: Allan variance excess over N^2 / tau in units of the white
  spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]: the
  flicker from its exact PSD, the ratchet q^2 (2 m^2 + 1) / (6 m) with q^2 = K^2 dt (a walk of
  independent steps, m samples a block), the blower the first-order Gauss-Markov formula (its
  time-averaged autocorrelation over whole blower cycles);
- fallback: the angle error e = s u, s the fallback state and u = theta mod Q (theta walking
  by the white noise), c(m) = R_s(m) E[u_k u_(k+m)] - d^2 Q^2 / 4, R_s(m) = d^2 + d (1 - d)
  rho^m, E[u u'] = Q^2 / 4 + 2 sum_h (Q / 2 pi h)^2 exp(-2 pi^2 h^2 m dt N^2 / Q^2): relative
  Allan excess (3 c0 - 4 c_m + c_2m) / (m dt N^2) at dt less at 10 dt, against sqrt(3 / n +
  40 / (3 n)).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
Physical scale: gate thresholds of 0.16 (edge), 0.4 and 1.2 deg/s; sweeps of 0.060, 0.17 and
0.57 deg/s at 10 Hz; warm-ups to 0.032, 0.14 and 0.34 deg/s (2.3-25 degC at 0.0135
(deg/s)/degC); nulled flicker b of 16, 41 and 124 deg/h; ratchets of K 2e-6 to 2e-5
rad/s/sqrt(s) (mean slips of 0.00037-0.0036 deg/s); blower-driven noise of 0.0089, 0.057
and 0.11 deg/s sd (tc 3 s, 3 s and 30 s); fallback fringes of 10, 43 and 115 arcsec; aliased
modes of 0.028, 0.11 and 0.34 deg/s sd, 137 Hz (width 6.9 Hz) and 172 Hz (width 11.5 Hz).
"""
from heldout_detect import allan_taus, allan_z, band_excess, gm_avar, psd_avar
import numpy as np
from scipy import signal, stats

GATE_GAIN = 0.25                     # fraction of a small change the gated smoother passes
SWEEP_HZ, OCTAVE_S = (10.0, 40.0), 60.0          # shaker sweep band, s per octave
CYCLE = 2 * OCTAVE_S * np.log2(SWEEP_HZ[1] / SWEEP_HZ[0])   # one sweep up and down, s
WARM_TAU, FAN_TAU = 600.0, 200.0     # s: warming lag, and the lag once the fan runs
FAN_ON, FAN_LEVEL = 0.6, 0.3         # fan thermostat and fan-cooled equilibrium, of T_hot
POWER_ON = 60.0                      # s: the record starts up to this long after power-on
NULLING_TAU = 200.0                  # s: the quadrature-nulling loop's time constant
SLIPS_PER_S = 1 / 20.0               # mean slip rate of the ratchet
HVAC_S, HVAC_DEPTH = 900.0, 0.9      # blower cycle and the swing of the turbulent intensity
LOCKED_S, COARSE_S = 300.0, 60.0     # mean locked and fallback episodes of the interpolator
OVER = 10                            # internal samples per output sample (mode simulated there)


def gated_smoother(x: np.ndarray, s: float, a: float = GATE_GAIN) -> np.ndarray:
    """y_k = y_(k-1) + a (x_k - y_(k-1)) if |x_k - y_(k-1)| < s, else x_k (y_0 = x_0)."""
    y = np.empty_like(x)
    prev = y[0] = x[0]
    for k, v in enumerate(x[1:].tolist(), 1):
        d = v - prev
        prev = prev + a * d if -s < d < s else v
        y[k] = prev
    return y


def gate_lag1(s_rel: float, a: float = GATE_GAIN, nodes: int = 1401) -> float:
    """
    Lag-1 autocorrelation of ``gated_smoother`` on unit white noise, threshold s_rel sigma.

    The output is a Markov chain: its stationary law is solved on a grid (a pass spreads the
    mass as the input's normal density, a gated step maps it through (1 - a) y + a x, x by
    Gauss-Legendre), and E[y y'] taken from the exact conditional mean (1 - a)(y A - M), A and
    M the normal mass and first moment within s of y.
    """
    yg = np.linspace(-7.0, 7.0, nodes)
    h = yg[1] - yg[0]
    gl, gw = np.polynomial.legendre.leggauss(48)
    inside = stats.norm.cdf(yg + s_rel) - stats.norm.cdf(yg - s_rel)
    moment = stats.norm.pdf(yg - s_rel) - stats.norm.pdf(yg + s_rel)
    far = (np.abs(yg[:, None] - yg[None, :]) >= s_rel) * stats.norm.pdf(yg)[None, :] * h
    trans = far * ((1 - inside) / np.maximum(far.sum(axis=1), 1e-300))[:, None]
    xq = yg[:, None] + s_rel * gl[None, :]
    wq = s_rel * gw[None, :] * stats.norm.pdf(xq)
    u = ((1 - a) * yg[:, None] + a * xq - yg[0]) / h
    j = np.clip(np.floor(u).astype(int), 0, nodes - 2)
    frac = u - j
    gated = np.zeros_like(trans)
    rows = np.repeat(np.arange(nodes), gl.size)
    np.add.at(gated, (rows, j.ravel()), (wq * (1 - frac)).ravel())
    np.add.at(gated, (rows, j.ravel() + 1), (wq * frac).ravel())
    trans += gated * (inside / np.maximum(gated.sum(axis=1), 1e-300))[:, None]
    p = stats.norm.pdf(yg) / stats.norm.pdf(yg).sum()
    for _ in range(400):
        p = p @ trans
    return float(np.sum(p * yg * (1 - a) * (yg * inside - moment)) / np.sum(p * yg * yg))


def sweep_freq(t) -> np.ndarray:
    """Frequency of the shaker's log sweep, up and down between SWEEP_HZ at OCTAVE_S/octave."""
    tri = 1 - np.abs(2 * np.mod(np.asarray(t, float) / CYCLE, 1.0) - 1)
    return SWEEP_HZ[0] * (SWEEP_HZ[1] / SWEEP_HZ[0]) ** tri


def sweep_psd(f, amplitude: float) -> np.ndarray:
    """One-sided mean PSD: time share 1 / (f ln(f2 / f1)) per Hz at power (A f1 / f)^2 / 2."""
    f = np.asarray(f, float)
    lo, hi = SWEEP_HZ
    band = (f >= lo) & (f <= hi)
    fs = np.where(band, f, lo)
    return np.where(band, (amplitude * lo / fs) ** 2 / 2 / (fs * np.log(hi / lo)), 0.0)


def fan_warmup(t, amplitude: float) -> np.ndarray:
    """Bias A T / T_hot of a die warming with WARM_TAU until the fan starts at FAN_ON."""
    t = np.asarray(t, float)
    t_on = -WARM_TAU * np.log(1 - FAN_ON)
    warm = 1 - np.exp(-t / WARM_TAU)
    cool = FAN_LEVEL + (FAN_ON - FAN_LEVEL) * np.exp(-np.maximum(t - t_on, 0) / FAN_TAU)
    return amplitude * np.where(t < t_on, warm, cool)


def flicker_kernel(n: int) -> np.ndarray:
    """Coefficients of (1 - z^-1)^-1/2: h_0 = 1, h_k = h_(k-1) (k - 1/2) / k."""
    k = np.arange(1, n)
    return np.r_[1.0, np.cumprod((k - 0.5) / k)]


def nulled_flicker(n: int, b: float, dt: float, rng) -> np.ndarray:
    """Flicker of sd-b drive, less what an integrating nulling loop (NULLING_TAU) removes."""
    q = signal.fftconvolve(rng.standard_normal(n) * b, flicker_kernel(n))[:n]
    c = 1 - dt / NULLING_TAU
    return signal.lfilter([1.0, -1.0], [1.0, -c], q)


def nulled_flicker_psd(f, b: float, dt: float) -> np.ndarray:
    """One-sided PSD: 2 dt b^2 / |2 sin(pi f dt)| |(1 - z^-1) / (1 - c z^-1)|^2."""
    f = np.asarray(f, float)
    z1 = np.exp(-2j * np.pi * f * dt)
    loop = np.abs((1 - z1) / (1 - (1 - dt / NULLING_TAU) * z1)) ** 2
    return 2 * dt * b * b / np.abs(2 * np.sin(np.pi * f * dt)) * loop


def ratchet(n: int, k: float, dt: float, rng) -> np.ndarray:
    """Bias of one-sided slips (Poisson, exponential sizes) and a steady creep back."""
    beta = k / np.sqrt(2 * SLIPS_PER_S)              # mean slip: variance rate 2 lam beta^2
    count = rng.poisson(SLIPS_PER_S * dt, n)
    slips = np.zeros(n)
    hit = count > 0
    slips[hit] = rng.gamma(count[hit], beta)
    return np.cumsum(slips - SLIPS_PER_S * dt * beta)


def walk_avar(m, q: float) -> np.ndarray:
    """Allan variance of a walk of iid steps (sd q), m-sample blocks: q^2 (2 m^2 + 1) / (6 m)."""
    m = np.asarray(m, float)
    return q * q * (2 * m * m + 1) / (6 * m)


def hvac_gm(n: int, sd: float, tc: float, dt: float, rng) -> np.ndarray:
    """First-order Markov whose drive intensity follows the blower: 1 + depth sin(2 pi t / P)."""
    a = np.exp(-dt / tc)
    t = np.arange(n) * dt + rng.uniform(0, HVAC_S)
    g = np.sqrt(1 + HVAC_DEPTH * np.sin(2 * np.pi * t / HVAC_S))
    w = rng.standard_normal(n) * g * np.sqrt(1 - a * a)
    w[0] /= np.sqrt(1 - a * a)
    return sd * signal.lfilter([1.0], [1.0, -a], w)


def two_state(n: int, dt: float, mean_on: float, mean_off: float, rng) -> np.ndarray:
    """1 / 0 episodes of exponential length (means in s), started from the stationary law."""
    on = rng.uniform() < mean_on / (mean_on + mean_off)
    mask, at = np.zeros(n), 0
    while at < n:
        length = int(np.ceil(rng.exponential(mean_on if on else mean_off) / dt))
        mask[at:at + length] = on
        at, on = at + length, not on
    return mask


def fallback_excess(m: int, step: float, dt: float, n_arw: float) -> float:
    """Relative Allan excess (3 c0 - 4 c_m + c_2m) / (m dt N^2) of the fallback angle error."""
    d = COARSE_S / (LOCKED_S + COARSE_S)
    rho = np.exp(-dt * (1 / COARSE_S + 1 / LOCKED_S))
    h = np.arange(1, 4001)

    def c(lag):
        walk = 2 * np.sum((step / (2 * np.pi * h)) ** 2 * np.exp(
            -2 * np.pi ** 2 * h ** 2 * lag * dt * n_arw ** 2 / step ** 2))
        same = step ** 2 / 4 + (walk if lag else step ** 2 / 12)
        return (d * d + d * (1 - d) * rho ** lag) * same - d * d * step ** 2 / 4
    return (3 * c(0) - 4 * c(m) + c(2 * m)) / (m * dt * n_arw ** 2)


def mode_coeffs(freq: float, q: float, dt_in: float):
    """(a1, a2, variance) of x_j = a1 x_(j-1) + a2 x_(j-2) + w_j, a mode at ``freq``, ``q``."""
    r = np.exp(-np.pi * freq * dt_in / q)
    a1, a2 = 2 * r * np.cos(2 * np.pi * freq * dt_in), -r * r
    return a1, a2, (1 - a2) / ((1 + a2) * ((1 - a2) ** 2 - a1 * a1))


def aliased_mode(n: int, sigma: float, freq: float, q: float, dt: float, rng) -> np.ndarray:
    """Return a mode run at OVER x the output rate, read every OVER-th sample (no anti-alias)."""
    a1, a2, var = mode_coeffs(freq, q, dt / OVER)
    burn = int(20 * q / (np.pi * freq * dt)) + 10                 # output samples
    zi, out, chunk = np.zeros(2), [], 2 ** 16
    for at in range(0, n + burn, chunk):
        w = rng.standard_normal(min(chunk, n + burn - at) * OVER)
        y, zi = signal.lfilter([1.0], [1.0, -a1, -a2], w, zi=zi)
        out.append(y[OVER - 1::OVER])
    return sigma * np.concatenate(out)[burn:] / np.sqrt(var)


def aliased_psd(f, sigma: float, freq: float, q: float, dt: float) -> np.ndarray:
    """One-sided PSD at the output: the internal mode's two-sided PSD summed over its images."""
    a1, a2, var = mode_coeffs(freq, q, dt / OVER)
    f = np.asarray(f, float)
    total = 0.0
    for k in range(-(OVER // 2), OVER - OVER // 2):
        z1 = np.exp(-2j * np.pi * (f + k / dt) * dt / OVER)
        total = total + dt / OVER / np.abs(1 - a1 * z1 - a2 * z1 * z1) ** 2
    return 2 * sigma ** 2 / var * total


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def gate(x, rng, s):
        return gated_smoother(x, s)

    def shaker(x, rng, amplitude):
        t = np.arange(x.size) * dt + rng.uniform(0, CYCLE)
        f = sweep_freq(t)
        phase = rng.uniform(0, 2 * np.pi) + 2 * np.pi * np.cumsum(f) * dt
        return x + amplitude * SWEEP_HZ[0] / f * np.sin(phase)

    def fan(x, rng, amplitude):
        return x + fan_warmup(np.arange(x.size) * dt + rng.uniform(0, POWER_ON), amplitude)

    def nulled(x, rng, b):
        return x + nulled_flicker(x.size, b, dt, rng)

    def slips(x, rng, k):
        return x + ratchet(x.size, k, dt, rng)

    def blower(x, rng, sd, tc):
        return x + hvac_gm(x.size, sd, tc, dt, rng)

    def fallback(x, rng, step):
        start = rng.uniform(0, step)
        mask = two_state(x.size, dt, COARSE_S, LOCKED_S, rng)
        err = mask * np.mod(start + np.cumsum(x) * dt, step)     # read = theta - err
        return x - np.diff(np.r_[mask[0] * start, err]) / dt

    def mode(x, rng, sigma, freq, q):
        return x + aliased_mode(x.size, sigma, freq, q, dt, rng)

    return {
        'internal_lowpass': (gate, [{'s': 1.0 * sig}, {'s': 3.0 * sig}, {'s': 0.41 * sig}]),
        'vibration': (shaker, [{'amplitude': 3e-3}, {'amplitude': 1e-2}, {'amplitude': 1.05e-3}]),
        'temperature_drift': (fan, [{'amplitude': 2.5e-3}, {'amplitude': 6e-3},
                                    {'amplitude': 5.5e-4}]),
        'bias_instability': (nulled, [{'b': 2e-4}, {'b': 6e-4}, {'b': 7.7e-5}]),
        'rate_random_walk': (slips, [{'k': 6e-6}, {'k': 2e-5}, {'k': 2.03e-6}]),
        'gauss_markov': (blower, [{'sd': 1e-3, 'tc': 3.0}, {'sd': 2e-3, 'tc': 30.0},
                                  {'sd': 1.55e-4, 'tc': 3.0}]),
        'quantization': (fallback, [{'step': 3 * n_arw * np.sqrt(dt)},
                                    {'step': 8 * n_arw * np.sqrt(dt)},
                                    {'step': 0.713 * n_arw * np.sqrt(dt)}]),
        'resonance': (mode, [{'sigma': 2e-3, 'freq': 137.0, 'q': 20.0},
                             {'sigma': 6e-3, 'freq': 172.0, 'q': 15.0},
                             {'sigma': 4.8e-4, 'freq': 137.0, 'q': 20.0}]),
    }


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn, p = n * dt, n_arw ** 2, params
    if name == 'internal_lowpass':
        return float(gate_lag1(p['s'] / sig) * np.sqrt(n))
    if name == 'temperature_drift':
        s = fan_warmup(np.arange(n) * dt, p['amplitude'])
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        rel = [fallback_excess(m, p['step'], dt, n_arw) for m in (1, 10)]
        return float(abs(rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n)))
    if name in ('vibration', 'resonance'):
        psd = ((lambda f: sweep_psd(f, p['amplitude'])) if name == 'vibration' else
               (lambda f: aliased_psd(f, p['sigma'], p['freq'], p['q'], dt)))
        ex, width = band_excess(psd, dt, sig)
        return float(ex * np.sqrt(big_t * width))
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = psd_avar(lambda f: nulled_flicker_psd(f, p['b'], dt), tau, dt)
    elif name == 'rate_random_walk':
        excess = walk_avar(np.round(tau / dt), p['k'] * np.sqrt(dt))
    else:
        excess = gm_avar(tau, p['sd'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
