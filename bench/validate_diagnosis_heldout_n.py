"""
Held-out set N of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_m.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out sets A-M, and
the kinds of departure differ from shape to shape:

- internal_lowpass: an idle-mode averager: the robot's power manager puts the IMU into its
  low-power mode during idle spells (a two-state Markov chain, mean idle spell 20 s, a share
  d of the time), where the sensor outputs the mean of its last 4 conversions; awake, it
  passes them unchanged: smoothing that comes and goes (regime switching, DC gain 1);
- vibration: aliased transformer hum: a transformer on the bench hums at twice the grid
  frequency, 100 Hz + 2 df(t), and the 100 Hz output samples it without averaging, so the hum
  folds to 2 df(t), the grid's deviation (a Gauss-Markov process, sd 0.02 Hz, 60 s): a
  constant-amplitude oscillation A cos(phi) whose frequency wanders about zero, its power
  folded into the lowest decade (autocovariance A^2 / 2 exp(-Var[dphi(u)] / 2));
- temperature_drift: a chamber staircase: the bench sits in a thermal chamber running a
  calibration profile of equal temperature steps every 1200 s, the die following each step
  through its 300 s lag: A sum_j (1 - exp(-(t' - 1200 j) / 300)) over the steps taken, t' = t
  + t0, t0 in 600-1800 s (the record starts mid-profile, one step still settling): repeated
  exponential settlings, a staircase that never returns;
- bias_instability: a comparator-switched trim: the ASIC switches a bias trim of +-b by a
  comparator on a reference node that sits at its threshold and carries 1/f noise (a
  Gaussian sum of eleven first-order processes, two per decade, 0.1-10^4 s): b sign(g), two
  levels, clustered (non-renewal) switching, autocovariance b^2 (2 / pi) asin(rho);
- rate_random_walk: stress-proportional creep: the bias follows a die-attach stress that
  creeps with a noise proportional to itself, dS = sigma S dW (Ito, sigma^2 = 1 / 14400 s):
  b = s0 (exp(sigma W - sigma^2 t / 2) - 1), zero-mean uncorrelated increments whose intensity
  sigma^2 (s0 + b)^2 follows the excursion, K^2 e^(sigma^2 t) on average (skewed, log-normal);
- gauss_markov: an amphoteric trap: a defect with three charge states (neutral, +, -), the
  charged states decaying to neutral at rate 1 / tc, neutral 80 % of the time and charged to
  either sign alike: three levels, bursts of either sign between neutral pauses, E[X_t | X_0] =
  X_0 e^(-t / tc) exactly (excess kurtosis 2);
- quantization: a two-register read with latch skew: the angle is a coarse count (Q = 5e-4
  rad) and a fine interpolation (Q / 256); the coarse register is latched s before the fine
  one, so whenever the angle crosses a coarse edge in between (probability |w| s / Q a sample),
  the read is off by a whole coarse step, -sign(w) Q, for that sample: sparse angle glitches;
- resonance: a tuned mount: the mount's 26 Hz rocking mode carries a tuned-mass absorber (mass
  ratio 0.05, tuned to 26 / 1.05 Hz, both damping ratios 0.01), white-forced; the gyro senses
  the primary's rate: two peaks either side of an anti-resonance (a zero pair at the
  absorber's frequency), a zero at DC.

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- idle averager: pooled lag-1 autocorrelation (d (m - 1) / m^2 + nu / m) / (d / m + 1 - d)
  (m = 4, nu = d dt / 20 s the entries into idle a sample) against 1 / sqrt(n);
- hum, comparator trim, amphoteric trap: Allan variance excess over N^2 / tau in units of the
  white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]: the
  hum and the trim from their autocovariances, AVAR(tau) = tau^-2 int_0^(2 tau) R(u) k(u) du
  (set M's kernel), Var[dphi(u)] = 2 (4 pi sd)^2 tc^2 (u / tc - 1 + e^(-u / tc)); the trap
  the first-order Gauss-Markov formula;
- creep: q^2 (2 m^2 + 1) / (6 m), q^2 = K^2 dt times the intensity's mean over the record,
  (e^(sigma^2 T) - 1) / (sigma^2 T) (exact for uncorrelated increments, on average);
- chamber: matched to its own noise-free waveform (t0 = 1200 s), mean removed:
  |s - mean(s)| / sigma;
- latch skew: the glitch g_k correlates with the sample's own increment, E[x g] = -s E[x^2],
  so the angle error's variance c0 = Q s E|x| + Q^2 / (12 256^2) and its covariance with the
  angle kappa = -s E[x^2] dt (x ~ N(b, sigma^2), b = 0.003 rad/s the records' bias) give the
  relative Allan excess 3 (c0 + kappa) / (m dt N^2): at dt less at 10 dt, against
  sqrt(3 / n + 40 / (3 n));
- tuned mount: mean excess PSD / white over the band above half its peak, times sqrt(T B).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
Physical scale: idle shares of 2.5 % (edge), 30 % and 80 %; hum of 0.0099, 0.034 and 0.086
deg/s peak; chamber steps of 0.0011, 0.011 and 0.057 deg/s a step (0.08, 0.85 and 4.2 degC
at 0.0135 (deg/s)/degC); trims of +-24, 62 and 206 deg/h; creep of K 1.8e-6, 6e-6 and 2e-5
rad/s/sqrt(s) at the start (s0 0.012-0.14 deg/s); traps of 0.0089, 0.057 and 0.11 deg/s sd
(tc 3 s, 3 s and 30 s); latch skews of 14 us, 0.3 ms and 2 ms; tuned mounts of 0.018, 0.069
and 0.34 deg/s sd.
"""
from heldout_detect import allan_taus, allan_z, band_excess, gm_avar
import numpy as np
from scipy import signal, special
from validate_diagnosis_heldout_k import walk_avar
from validate_diagnosis_heldout_m import cov_avar

IDLE_AVG, IDLE_S = 4, 20.0                          # conversions averaged; mean idle spell (s)
HUM_HZ, GRID_SD, GRID_TC = 100.0, 0.02, 60.0        # hum; grid deviation sd (Hz), its time (s)
STEP_S, CHAMBER_LAG = 1200.0, 300.0                 # s: chamber step period, the die's lag
TRIM_TAUS = 0.1 * 10.0 ** (np.arange(11) / 2)       # s: the reference's Gauss-Markov times
CREEP = 1.0 / 14400.0                               # 1/s: sigma^2 of the stress creep
NEUTRAL = 0.8                                       # share of time the trap is neutral
BIAS = 0.003                                        # rad/s: the static records' bias
COARSE, FINE = 5e-4, 256                            # rad: coarse step; fine steps per coarse
MOUNT_HZ, ABSORBER, ZETA = 26.0, 0.05, 0.01         # mount mode, absorber mass ratio, damping


def dwell_states(n: int, dt: float, means, first: int, rng) -> np.ndarray:
    """States 0..len(means)-1 visited in turn with exponential dwells, state per sample."""
    k = len(means)
    total, pieces = 0.0, []
    while total < n * dt:
        d = rng.exponential(1.0, k * (int((n * dt - total) / sum(means)) + 20))
        d *= np.resize(np.roll(np.asarray(means, float), -first), d.size)
        pieces.append(d)
        total += d.sum()
    ends = np.cumsum(np.concatenate(pieces))
    return (np.searchsorted(ends, np.arange(n) * dt, side='right') + first) % k


def idle_spells(n: int, share: float, dt: float, rng) -> np.ndarray:
    """Return True while idle: a two-state Markov chain, mean idle spell IDLE_S, a ``share``."""
    means = [IDLE_S * (1 - share) / share, IDLE_S]       # awake, idle
    return dwell_states(n, dt, means, int(rng.uniform() < share), rng) == 1


def idle_average(x: np.ndarray, idle: np.ndarray) -> np.ndarray:
    """Return the mean of the last IDLE_AVG samples where ``idle`` (x_0 before), x elsewhere."""
    pad = np.r_[np.full(IDLE_AVG - 1, x[0]), x]
    box = np.convolve(pad, np.full(IDLE_AVG, 1.0 / IDLE_AVG), mode='valid')
    return np.where(idle, box, x)


def idle_r1(share: float, dt: float) -> float:
    """Pooled lag-1 autocorrelation of the idle-mode averager on unit white input."""
    m, nu = IDLE_AVG, share * dt / IDLE_S
    return (share * (m - 1) / m ** 2 + nu / m) / (share / m + 1 - share)


def gauss_markov(n: int, tc: float, dt: float, rng) -> np.ndarray:
    """Unit-variance first-order Markov process of time ``tc`` (stationary start)."""
    c = np.exp(-dt / tc)
    w = rng.standard_normal(n) * np.sqrt(1 - c * c)
    return signal.lfilter([1.0], [1.0, -c], w, zi=[c * rng.standard_normal()])[0]


def hum(n: int, amplitude: float, dt: float, rng) -> np.ndarray:
    """Return A cos(2 pi (HUM_HZ t + 2 int df dt) + p) sampled at dt; df the grid's deviation."""
    df = GRID_SD * gauss_markov(n, GRID_TC, dt, rng)
    cycles = np.mod(HUM_HZ * dt * np.arange(n), 1.0) + 2 * np.cumsum(df) * dt
    return amplitude * np.cos(2 * np.pi * cycles + rng.uniform(0, 2 * np.pi))


def hum_cov(u, amplitude: float) -> np.ndarray:
    """Autocovariance A^2 / 2 exp(-Var[dphi(u)] / 2) of the folded hum."""
    u = np.abs(np.asarray(u, float)) / GRID_TC
    var = 2 * (4 * np.pi * GRID_SD * GRID_TC) ** 2 * (u - 1 + np.exp(-u))
    return amplitude ** 2 / 2 * np.exp(-var / 2)


def staircase(t, amplitude: float) -> np.ndarray:
    """Return A sum over steps j >= 1 of (1 - exp(-(t - STEP_S j) / CHAMBER_LAG)) after each."""
    t = np.asarray(t, float)
    out = np.zeros_like(t)
    for j in range(1, int(t.max() // STEP_S) + 1):
        late = np.maximum(t - j * STEP_S, 0.0)
        out += 1 - np.exp(-late / CHAMBER_LAG)
    return amplitude * out


def reference(n: int, dt: float, rng) -> np.ndarray:
    """Unit-variance Gaussian 1/f-like sum of TRIM_TAUS first-order processes (stationary)."""
    return sum(gauss_markov(n, tau, dt, rng) for tau in TRIM_TAUS) / np.sqrt(TRIM_TAUS.size)


def trim_cov(u, b: float) -> np.ndarray:
    """Autocovariance b^2 (2 / pi) asin(rho(u)) of the comparator-switched trim."""
    rho = np.mean(np.exp(-np.abs(np.asarray(u, float))[..., None] / TRIM_TAUS), axis=-1)
    return b * b * 2 / np.pi * np.arcsin(np.minimum(rho, 1.0))


def creep(n: int, k: float, dt: float, rng) -> np.ndarray:
    """Return s0 (exp(sigma W - sigma^2 t / 2) - 1), s0 = k / sigma: initial intensity K = k."""
    sigma = np.sqrt(CREEP)
    t = np.arange(1, n + 1) * dt
    w = np.cumsum(rng.standard_normal(n)) * np.sqrt(dt)
    return k / sigma * np.expm1(sigma * w - CREEP * t / 2)


def creep_mean_intensity(big_t: float) -> float:
    """Mean of e^(sigma^2 t) over a record of length T: the walk's intensity relative to K^2."""
    return float(np.expm1(CREEP * big_t) / (CREEP * big_t))


def amphoteric(n: int, sd: float, tc: float, dt: float, rng) -> np.ndarray:
    """Return a neutral (0) / charged (+-1) trap: charged dwell tc, neutral a NEUTRAL share."""
    pairs = dwell_states(n, dt, [tc * NEUTRAL / (1 - NEUTRAL), tc],
                         int(rng.uniform() > NEUTRAL), rng)
    start = np.r_[True, np.diff(pairs) != 0]
    signs = rng.choice([-1.0, 1.0], int(start.sum()))[np.cumsum(start) - 1]
    return sd * pairs * signs / np.sqrt(1 - NEUTRAL)


def split_read(theta, lead) -> np.ndarray:
    """Coarse count of theta - lead (latched early) plus the fine count of theta."""
    theta = np.asarray(theta, float)
    q = COARSE / FINE
    return (COARSE * np.floor((theta - lead) / COARSE)
            + q * np.floor(np.mod(theta, COARSE) / q))


def skew_excess(s: float, dt: float, sig: float, n_arw: float, m: int) -> float:
    """Relative Allan excess 3 (c0 + kappa) / (m dt N^2) of the latch-skewed read."""
    z = BIAS / sig
    abs_mean = sig * np.sqrt(2 / np.pi) * np.exp(-z * z / 2) + BIAS * (1 - 2 * special.ndtr(-z))
    c0 = COARSE * s * abs_mean - (s * BIAS) ** 2 + (COARSE / FINE) ** 2 / 12
    kappa = -s * (sig ** 2 + BIAS ** 2) * dt
    return 3 * (c0 + kappa) / (m * dt * n_arw ** 2)


def tmd_filter(dt: float):
    """(b, a, unit-drive variance) of the primary's rate for white force, matched z-transform."""
    w1 = 2 * np.pi * MOUNT_HZ
    mu, w2 = ABSORBER, w1 / (1 + ABSORBER)
    k1, k2, c1, c2 = w1 * w1, mu * w2 * w2, 2 * ZETA * w1, 2 * ZETA * mu * w2
    absorber = np.array([mu, c2, k2])
    den = np.polysub(np.polymul([1.0, c1 + c2, k1 + k2], absorber),
                     np.polymul([c2, k2], [c2, k2]))
    num = np.polymul([1.0, 0.0], absorber)
    b = np.real(np.poly(np.exp(np.roots(num) * dt)))
    a = np.real(np.poly(np.exp(np.roots(den) * dt)))
    h = signal.lfilter(b, a, np.r_[1.0, np.zeros(int(60.0 / dt))])
    return b, a, float(np.sum(h * h))


def tuned_mount(n: int, sigma: float, dt: float, rng) -> np.ndarray:
    """White force through ``tmd_filter``, total sd ``sigma`` (run in for 30 s)."""
    b, a, var = tmd_filter(dt)
    burn = int(30.0 / dt)
    return sigma / np.sqrt(var) * signal.lfilter(b, a, rng.standard_normal(n + burn))[burn:]


def tmd_psd(f, sigma: float, dt: float) -> np.ndarray:
    """One-sided PSD 2 dt sigma^2 |B / A|^2 / var of ``tuned_mount``."""
    b, a, var = tmd_filter(dt)
    z1 = np.exp(-2j * np.pi * np.asarray(f, float) * dt)
    return 2 * dt * sigma ** 2 / var * np.abs(np.polyval(b[::-1], z1)
                                              / np.polyval(a[::-1], z1)) ** 2


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def idle(x, rng, share):
        return idle_average(x, idle_spells(x.size, share, dt, rng))

    def hummed(x, rng, amplitude):
        return x + hum(x.size, amplitude, dt, rng)

    def chamber(x, rng, amplitude):
        return x + staircase(np.arange(x.size) * dt + rng.uniform(600, 1800), amplitude)

    def trimmed(x, rng, b):
        return x + b * np.sign(reference(x.size, dt, rng))

    def crept(x, rng, k):
        return x + creep(x.size, k, dt, rng)

    def trap(x, rng, sd, tc):
        return x + amphoteric(x.size, sd, tc, dt, rng)

    def skewed(x, rng, s):
        theta0 = rng.uniform(0, 1000 * COARSE)
        theta = theta0 + np.cumsum(x) * dt
        read = split_read(np.r_[theta0, theta], np.r_[0.0, s * x])
        return np.diff(read) / dt

    def mount(x, rng, sigma):
        return x + tuned_mount(x.size, sigma, dt, rng)

    return {
        'internal_lowpass': (idle, [{'share': 0.3}, {'share': 0.8}, {'share': 0.025}]),
        'vibration': (hummed, [{'amplitude': 6e-4}, {'amplitude': 1.5e-3},
                               {'amplitude': 1.73e-4}]),
        'temperature_drift': (chamber, [{'amplitude': 2e-4}, {'amplitude': 1e-3},
                                        {'amplitude': 1.91e-5}]),
        'bias_instability': (trimmed, [{'b': 3e-4}, {'b': 1e-3}, {'b': 1.17e-4}]),
        'rate_random_walk': (crept, [{'k': 6e-6}, {'k': 2e-5}, {'k': 1.78e-6}]),
        'gauss_markov': (trap, [{'sd': 1e-3, 'tc': 3.0}, {'sd': 2e-3, 'tc': 30.0},
                                {'sd': 1.55e-4, 'tc': 3.0}]),
        'quantization': (skewed, [{'s': 3e-4}, {'s': 2e-3}, {'s': 1.4e-5}]),
        'resonance': (mount, [{'sigma': 1.2e-3}, {'sigma': 6e-3}, {'sigma': 3.09e-4}]),
    }


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn, p = n * dt, n_arw ** 2, params
    if name == 'internal_lowpass':
        return float(idle_r1(p['share'], dt) * np.sqrt(n))
    if name == 'temperature_drift':
        s = staircase(np.arange(n) * dt + 1200.0, p['amplitude'])
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        rel = [skew_excess(p['s'], dt, sig, n_arw, m) for m in (1, 10)]
        return float(abs(rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n)))
    if name == 'resonance':
        ex, width = band_excess(lambda f: tmd_psd(f, p['sigma'], dt), dt, sig)
        return float(ex * np.sqrt(big_t * width))
    tau = allan_taus(dt, big_t)
    if name == 'vibration':
        excess = cov_avar(lambda u: hum_cov(u, p['amplitude']), tau)
    elif name == 'bias_instability':
        excess = cov_avar(lambda u: trim_cov(u, p['b']), tau)
    elif name == 'rate_random_walk':
        excess = walk_avar(np.round(tau / dt), p['k'] * np.sqrt(dt)) * creep_mean_intensity(big_t)
    else:
        excess = gm_avar(tau, p['sd'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
