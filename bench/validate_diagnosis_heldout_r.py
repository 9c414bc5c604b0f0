"""
Held-out set R of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_p.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]; the nine names of set P, with
``stale_samples``); every shape is a physical form unlike the catalogue's, the development
shapes (``validate_diagnosis.py``) and held-out sets A-Q, and the kinds of departure differ
from shape to shape:

- internal_lowpass: a tracking filter in the driver: the robot's IMU driver publishes the rate
  estimate of a steady-state two-state (rate and its slope) tracking filter instead of the raw
  reading, the fading-memory g-h form (g = 1 - theta^2, h = (1 - theta)^2: a double pole at
  theta, DC gain 1, no lag on a ramp): H(z) = (1 - theta) ((1 + theta) - 2 theta z^-1) /
  (1 - theta z^-1)^2, a zero and a critically damped pole pair, its gain ABOVE 1 in a middle
  band (up to 1.1) and below 1 towards Nyquist; lag-1 autocorrelation ~ 2 theta^2 on white
  input;
- vibration: bus crosstalk locked to the sample clock: the host polls a magnetometer in every
  MAG_EVERY = 4th slot and a barometer in every BARO_EVERY = 5th slot over the gyro's SPI bus;
  each transfer disturbs the gyro conversion under way (digital crosstalk into its front end)
  by a, BARO_RATIO a for the barometer's: one-sample spikes of fixed size at fixed slot
  phases, lines at exactly k / (4 dt) and k / (5 dt) (20, 25, 40 and 50 Hz: one of them at
  Nyquist), no width, and a bias shift a / 4 + 0.6 a / 5;
- temperature_drift: stress relaxation after power-on: the die warms within seconds, and the
  thermal-mismatch stress it sets up in the die-attach adhesive (a polymer) relaxes
  viscoelastically by the Kohlrausch-Williams-Watts law, the bias following it: A (1 -
  exp(-(t' / KWW_S)^KWW_BETA)), t' = t + t0, t0 in 0-60 s, KWW_S = 900 s, KWW_BETA = 0.4: a
  stretched exponential, infinitely steep at power-on, its tail far slower than an exponential
  (63 % at 900 s, 90 % only at ~7200 s);
- bias_instability: adsorption-desorption: gas molecules land on the resonator at Poisson times
  and each stays for a residence time of density ~ L^-2 on ADS_MIN = 0.02 s to ADS_MAX = 2e4 s
  (a broad spread of binding energies), each adding the same small bias while it sits: the
  number present is an M/G/infinity queue, Poisson (mean ADS_MEAN = 6: a lattice of levels,
  skew 0.41), bias a (N - 6), autocovariance a^2 lambda E[(L - |u|)+] = b^2 (ln(ADS_MAX / u)
  - 1 + u / ADS_MAX) / ln(ADS_MAX / ADS_MIN) for u >= ADS_MIN: logarithmic in the lag (1/f),
  the slow part carried by a few long stays (non-Gaussian at low frequency);
- rate_random_walk: a loosening screw: at an unknown moment t_on (uniform over the first
  ONSET = 50 % of the record) vibration has undone the mounting screw's preload, and from then
  on micro-slips of the mount let the package stress, and the bias, walk freely (Gaussian,
  intensity K): flat before t_on, a random walk after it (a change point, not a stationary
  walk);
- gauss_markov: charging and micro-discharges: the proof mass charges at a steady rate (a
  leakage current) and sheds a fraction 1 - DROP = 1/2 of its charge in each micro-discharge
  at Poisson times (rate 2 / tc); the bias follows the charge, mean removed: linear ramps up,
  sudden proportional drops (a growth-collapse process: skewed, bounded below), the generator's
  linear drift making the autocovariance exactly sd^2 e^(-|u| / tc);
- quantization: a single-track interpolator: the angle read-out's period is Q and its fine
  part comes from the sine track alone (the cosine track reduced to its sign, a
  cost-reduced or half-failed head): psi = asin(clip(sin psi + n)) on the branch that the
  cosine's sign picks, the track noise n of sd TRACK_NOISE = 0.05 of the track's amplitude
  magnified by 1 / |cos psi| near the track's extremes: a white angle error whose size, and
  mean, are periodic in the angle (heteroscedastic, heavy near two points a period), no
  staircase;
- resonance: a pulsating-flow bracket: a reciprocating pump's discharge strokes (period PUMP_S
  = 0.5 s, STROKE = 1/3 of it, random phase) blow turbulence on a bracket whose mode (MODE_HZ
  = 24.3 Hz, q 20) carries the gyro: white drive gated on for a third of each cycle, the mode
  ringing up during each stroke and down (0.26 s) between them: cyclostationary, its mean PSD
  that of the free mode of the same rms;
- stale_samples: a latest-value recorder: the sensor publishes a sample every dt and each
  message crosses the robot's network with latency BASE_S + an exponential excess (mean mu,
  a busy link); the logger samples, at its own ticks LAG_S after each publication, the most
  recently ARRIVED message: a late message makes the logger record the previous one again (a
  repeat), the late one is then lost or recorded out of order (an older sample after a newer
  one): repeats, losses and reorderings; a tick repeats iff no message arrived since the
  last tick, p = prod_i (1 - P(D in (LAG_S + (i - 1) dt, LAG_S + i dt])).

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- tracking filter: lag-1 autocorrelation of the output on white input, sum h_j h_(j+1) /
  sum h_j^2, against 1 / sqrt(n);
- bus crosstalk, stress relaxation: matched to the noise-free waveform (slot phases 0; t0 =
  30 s), mean removed: |s - mean(s)| / sigma;
- adsorption, loosening screw, micro-discharges: Allan variance excess over N^2 / tau in units
  of the white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]:
  the adsorption from its autocovariance (``cov_avar``), the screw's walk q^2 (2 m^2 + 1) /
  (6 m), q = K sqrt(dt), times its mean active share 1 - ONSET / 2 = 0.75, the discharges as
  ``gm_avar``;
- single track: the angle error's conditional mean m(psi) and variance v(psi) over the track
  noise (psi uniform); autocovariance c0 = E v + Var m, c_l = 2 sum_h |m_h|^2 exp(-2 pi^2 h^2
  l dt N^2 / Q^2) for l >= 1 (the mean's Fourier coefficients, the angle walking by the white
  noise, as sets E, F, I and J): relative Allan excess (3 c0 - 4 c_l + c_2l) / (l dt N^2) at
  dt less at 10 dt, against sqrt(3 / n + 40 / (3 n));
- pulsating bracket: the mean PSD (the free mode's of the same rms), its mean excess over
  white in the band above half its peak, times sqrt(T B);
- recorder: the exact repeats of the harness's output (rounded to LSB = 0.05 deg/s): the
  share of zero first differences rises from q0 to q0 + p (1 - q0), z = p sqrt(n (1 - q0) /
  q0) (as set P; the reorderings not counted).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
Physical scale: tracking filters of theta 0.05 (edge), 0.3 and 0.7 (memories -dt / ln theta of
3.3, 8.3 and 28 ms); crosstalk spikes a of 0.0038, 0.029 and 0.17 deg/s; stress relaxations of
A 0.015, 0.086 and 0.29 deg/s (1.1, 6.4 and 21 degC equivalent at 0.0135 (deg/s)/degC);
adsorption noise of 21, 72 and 290 deg/h sd; screws of K 2.34e-6, 6e-6 and 3e-5 rad/s/sqrt(s)
after t_on; discharges of 0.0099, 0.057 and 0.14 deg/s sd (tc 2 s, 2 s and 20 s); read-out
periods Q of 0.34, 1.5 and 5 mrad (71, 310 and 1030 arcsec); brackets of 0.018, 0.069 and 0.34
deg/s rms; latency excesses mu of 0.71 (edge), 2 and 6 ms.
"""
from heldout_detect import allan_taus, allan_z, band_excess, gm_avar
import numpy as np
from scipy import signal
from validate_diagnosis_heldout_k import walk_avar
from validate_diagnosis_heldout_m import cov_avar
from validate_diagnosis_heldout_p import repeat_share

MAG_EVERY, BARO_EVERY, BARO_RATIO = 4, 5, 0.6     # polling slots; barometer spike / magnetometer's
KWW_S, KWW_BETA = 900.0, 0.4                     # s; stretch exponent
ADS_MIN, ADS_MAX, ADS_MEAN = 0.02, 2e4, 6.0      # s, s: residence times; mean number adsorbed
ONSET = 0.5                                      # t_on uniform over this share of the record
DROP = 0.5                                       # charge kept in a micro-discharge
TRACK_NOISE = 0.05                               # sine track's noise / its amplitude
PUMP_S, STROKE = 0.5, 1.0 / 3.0                  # s: pump cycle; share of it the flow blows
MODE_HZ, MODE_Q = 24.3, 20.0                     # the bracket's mode
BASE_S, LAG_S = 0.001, 0.006                     # s: fixed latency; logger tick after publication


def tracker_coeffs(theta: float):
    """Return (b, a) of the fading-memory g-h filter's rate output, double pole at theta."""
    return ((1 - theta) * np.array([1 + theta, -2 * theta]),
            np.array([1.0, -2 * theta, theta * theta]))


def tracker(x: np.ndarray, theta: float) -> np.ndarray:
    """Filter x by the tracker, started settled on x[0] (DC gain 1)."""
    b, a = tracker_coeffs(theta)
    if theta == 0:
        return np.array(x, float)
    return signal.lfilter(b, a, x, zi=signal.lfilter_zi(b, a) * x[0])[0]


def tracker_r1(theta: float, m: int = 4000) -> float:
    """Lag-1 autocorrelation of the tracker's output on white input."""
    h = signal.lfilter(*tracker_coeffs(theta), np.r_[1.0, np.zeros(m - 1)])
    return float(np.sum(h[:-1] * h[1:]) / np.sum(h * h))


def crosstalk(n: int, a: float, mag_slot: int = 0, baro_slot: int = 0) -> np.ndarray:
    """Spikes a in every MAG_EVERY-th slot, BARO_RATIO a in every BARO_EVERY-th."""
    k = np.arange(n)
    return a * ((k % MAG_EVERY == mag_slot) + BARO_RATIO * (k % BARO_EVERY == baro_slot))


def kww(t, amplitude: float) -> np.ndarray:
    """Return A (1 - exp(-(t / KWW_S)^KWW_BETA)), t from power-on."""
    return amplitude * -np.expm1(-(np.asarray(t, float) / KWW_S) ** KWW_BETA)


def residence_norm() -> float:
    """Return c of the residence density c L^-2 on [ADS_MIN, ADS_MAX]."""
    return 1.0 / (1.0 / ADS_MIN - 1.0 / ADS_MAX)


def mean_residence() -> float:
    """Return E[L] = c ln(ADS_MAX / ADS_MIN)."""
    return residence_norm() * np.log(ADS_MAX / ADS_MIN)


def adsorbed(n: int, dt: float, rng) -> np.ndarray:
    """Return the number of molecules present at each sample (M/G/infinity, stationary)."""
    c = residence_norm()
    lam = ADS_MEAN / mean_residence()
    count = rng.poisson(lam * (ADS_MAX + n * dt))
    start = rng.uniform(-ADS_MAX, n * dt, count)
    stay = 1.0 / (1.0 / ADS_MIN - rng.uniform(size=count) / c)
    i0 = np.clip(np.ceil(start / dt), 0, n).astype(int)
    i1 = np.clip(np.ceil((start + stay) / dt), 0, n).astype(int)
    keep = i0 < i1
    d = (np.bincount(i0[keep], minlength=n + 1) - np.bincount(i1[keep], minlength=n + 1))
    return np.cumsum(d)[:n]


def adsorption_cov(u, b: float) -> np.ndarray:
    """Autocovariance b^2 E[(L - |u|)+] / E[L] of ``adsorbed`` scaled to sd b."""
    u = np.abs(np.asarray(u, float))
    c = residence_norm()
    uu = np.clip(u, ADS_MIN, ADS_MAX)
    tail = np.where(u < ADS_MIN, mean_residence() - u,
                    c * (np.log(ADS_MAX / uu) - 1 + uu / ADS_MAX))
    return b * b * np.maximum(tail, 0.0) / mean_residence()


def loose_walk(n: int, k: float, dt: float, rng) -> np.ndarray:
    """Zero up to t_on (uniform over the first ONSET share), a Gaussian walk of K after it."""
    on = int(rng.uniform(0, ONSET) * n)
    steps = rng.standard_normal(n) * k * np.sqrt(dt)
    steps[:on] = 0.0
    return np.cumsum(steps)


def charging(n: int, sd: float, tc: float, dt: float, rng) -> np.ndarray:
    """Growth-collapse charge, mean removed: slope m / tc, times DROP at Poisson times (2 / tc)."""
    lam = 1.0 / (tc * (1 - DROP))
    mean = sd * np.sqrt((1 + DROP) / (1 - DROP))
    slope = mean / tc
    burn = 30 * tc
    count = rng.poisson(lam * (burn + n * dt))
    at = np.sort(rng.uniform(-burn, n * dt, count))
    gaps = np.diff(np.r_[-burn, at])
    after = signal.lfilter([1.0], [1.0, -DROP], DROP * slope * gaps, zi=[DROP * mean])[0]
    t = np.arange(n) * dt
    j = np.searchsorted(at, t, side='right') - 1
    level = np.where(j >= 0, after[np.maximum(j, 0)] + slope * (t - at[np.maximum(j, 0)]),
                     mean + slope * (t + burn))
    return level - mean


def single_track(theta, q: float, noise) -> np.ndarray:
    """Read angle minus true angle: asin of the noisy sine track on the cosine's branch."""
    psi = np.mod(2 * np.pi * np.asarray(theta, float) / q, 2 * np.pi)
    s = np.clip(np.sin(psi) + noise, -1.0, 1.0)
    est = np.where(np.cos(psi) >= 0, np.arcsin(s), np.pi - np.arcsin(s))
    return q / (2 * np.pi) * np.angle(np.exp(1j * (est - psi)))


def track_moments(q: float, points: int = 2048, nodes: int = 1601):
    """Return (psi grid, conditional mean, conditional variance) of the angle error."""
    psi = np.arange(points) * 2 * np.pi / points
    z = np.linspace(-8, 8, nodes)
    w = np.exp(-z * z / 2)
    w /= w.sum()
    e = single_track(psi[:, None] * q / (2 * np.pi), q, TRACK_NOISE * z[None, :])
    m = e @ w
    return psi, m, (e * e) @ w - m * m


def track_excess(q: float, dt: float, n_arw: float) -> tuple:
    """Return the relative Allan excess of the single-track error at dt and at 10 dt."""
    _, m, v = track_moments(q)
    c = np.fft.rfft(m) / m.size
    h = np.arange(c.size)
    c0 = v.mean() + np.var(m)

    def cl(lag):
        rate = 2 * np.pi ** 2 * lag * dt * n_arw ** 2 / q ** 2
        return 2 * np.sum(np.abs(c[1:]) ** 2 * np.exp(-rate * h[1:] ** 2))
    return tuple((3 * c0 - 4 * cl(lag) + cl(2 * lag)) / (lag * dt * n_arw ** 2)
                 for lag in (1, 10))


def mode_coeffs(dt: float):
    """Return (a, angle variance per unit drive, lag-1 correlation) of the bracket's mode."""
    th = 2 * np.pi * MODE_HZ * dt * np.sqrt(1 - 1 / (4 * MODE_Q ** 2))
    r = np.exp(-np.pi * MODE_HZ * dt / MODE_Q)
    a = np.array([1.0, -2 * r * np.cos(th), r * r])
    var = (1 + r * r) / ((1 - r * r) * (1 - 2 * r * r * np.cos(2 * th) + r ** 4))
    return a, var, 2 * r * np.cos(th) / (1 + r * r)


def drive_gain(sigma: float, dt: float) -> float:
    """Drive sd (continuous drive) that gives the mode's rate (angle difference / dt) sd sigma."""
    _, var, rho1 = mode_coeffs(dt)
    return sigma * dt / np.sqrt(2 * var * (1 - rho1))


def pump_gate(n: int, dt: float, phase: float) -> np.ndarray:
    """Flag the samples while the pump's stroke blows: (t / PUMP_S + phase) mod 1 < STROKE."""
    return np.mod(np.arange(n) * dt / PUMP_S + phase, 1.0) < STROKE


def pulsating(n: int, sigma: float, dt: float, rng) -> np.ndarray:
    """Rate of the mode driven by white noise gated by the pump; mean rate variance sigma^2."""
    a, _, _ = mode_coeffs(dt)
    burn = int(20 * MODE_Q / (np.pi * MODE_HZ * dt)) + 1
    phase = rng.uniform()
    gate = pump_gate(n + 1 + burn, dt, phase - (burn + 1) * dt / PUMP_S)
    drive = rng.standard_normal(n + 1 + burn) * gate * drive_gain(sigma, dt) / np.sqrt(STROKE)
    return np.diff(signal.lfilter([1.0], a, drive)[burn:]) / dt


def mode_psd(f, sigma: float, dt: float) -> np.ndarray:
    """One-sided PSD of the free mode's rate (sd sigma), the pulsating bracket's mean PSD."""
    a, _, _ = mode_coeffs(dt)
    z1 = np.exp(-2j * np.pi * np.asarray(f, float) * dt)
    g = drive_gain(sigma, dt)
    den = np.abs(a[0] + a[1] * z1 + a[2] * z1 * z1) ** 2
    return 2 * dt * g * g * np.abs(1 - z1) ** 2 / dt ** 2 / den


def recorded(n: int, mu: float, dt: float, rng) -> np.ndarray:
    """Index of the message each logger tick records: the latest ARRIVED by the tick."""
    arrive = np.arange(n) * dt + BASE_S + rng.exponential(mu, n)
    order = np.argsort(arrive, kind='stable')
    ticks = np.arange(n) * dt + LAG_S
    i = np.searchsorted(arrive[order], ticks, side='right') - 1
    return np.where(i >= 0, order[np.maximum(i, 0)], 0)


def latency_cdf(x, mu: float) -> np.ndarray:
    """P(D <= x) for D = BASE_S + Exp(mu)."""
    x = np.asarray(x, float) - BASE_S
    if mu == 0:
        return (x >= 0).astype(float)
    return np.where(x >= 0, -np.expm1(-np.maximum(x, 0) / mu), 0.0)


def repeat_probability(mu: float, dt: float, terms: int = 400) -> float:
    """P(no arrival between two ticks) = prod_i (1 - P(D in (LAG + (i - 1) dt, LAG + i dt]))."""
    i = np.arange(terms)
    hi = latency_cdf(LAG_S + i * dt, mu)
    lo = np.where(i > 0, latency_cdf(LAG_S + (i - 1) * dt, mu), 0.0)
    return float(np.prod(1 - (hi - lo)))


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def track(x, rng, theta):
        return tracker(x, theta)

    def bus(x, rng, a):
        return x + crosstalk(x.size, a, rng.integers(MAG_EVERY), rng.integers(BARO_EVERY))

    def relax(x, rng, amplitude):
        return x + kww(np.arange(x.size) * dt + rng.uniform(0, 60), amplitude)

    def adsorption(x, rng, b):
        return x + b * (adsorbed(x.size, dt, rng) - ADS_MEAN) / np.sqrt(ADS_MEAN)

    def screw(x, rng, k):
        return x + loose_walk(x.size, k, dt, rng)

    def discharge(x, rng, sd, tc):
        return x + charging(x.size, sd, tc, dt, rng)

    def one_track(x, rng, q):
        theta = np.cumsum(x) * dt
        read = theta + single_track(theta, q, TRACK_NOISE * rng.standard_normal(x.size))
        return np.diff(np.r_[0.0, read]) / dt

    def bracket(x, rng, sigma):
        return x + pulsating(x.size, sigma, dt, rng)

    def logger(x, rng, mu):
        return x[recorded(x.size, mu, dt, rng)]

    return {
        'internal_lowpass': (track, [{'theta': 0.3}, {'theta': 0.7}, {'theta': 0.05}]),
        'vibration': (bus, [{'a': 5e-4}, {'a': 3e-3}, {'a': 6.6e-5}]),
        'temperature_drift': (relax, [{'amplitude': 1.5e-3}, {'amplitude': 5e-3},
                                      {'amplitude': 2.65e-4}]),
        'bias_instability': (adsorption, [{'b': 3.5e-4}, {'b': 1.4e-3}, {'b': 1.0e-4}]),
        'rate_random_walk': (screw, [{'k': 6e-6}, {'k': 3e-5}, {'k': 2.34e-6}]),
        'gauss_markov': (discharge, [{'sd': 1e-3, 'tc': 2.0}, {'sd': 2.5e-3, 'tc': 20.0},
                                     {'sd': 1.72e-4, 'tc': 2.0}]),
        'quantization': (one_track, [{'q': 1.5e-3}, {'q': 5e-3}, {'q': 3.44e-4}]),
        'resonance': (bracket, [{'sigma': 1.2e-3}, {'sigma': 6e-3}, {'sigma': 3.2e-4}]),
        'stale_samples': (logger, [{'mu': 0.002}, {'mu': 0.006}, {'mu': 0.000713}]),
    }


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn, p = n * dt, n_arw ** 2, params
    if name == 'internal_lowpass':
        return float(tracker_r1(p['theta']) * np.sqrt(n))
    if name in ('vibration', 'temperature_drift'):
        s = (crosstalk(n, p['a']) if name == 'vibration'
             else kww(np.arange(n) * dt + 30.0, p['amplitude']))
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        rel = track_excess(p['q'], dt, n_arw)
        return float(abs(rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n)))
    if name == 'resonance':
        ex, width = band_excess(lambda f: mode_psd(f, p['sigma'], dt), dt, sig)
        return float(ex * np.sqrt(big_t * width))
    if name == 'stale_samples':
        q0 = repeat_share(sig)
        return float(repeat_probability(p['mu'], dt) * np.sqrt(n * (1 - q0) / q0))
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = cov_avar(lambda u: adsorption_cov(u, p['b']), tau)
    elif name == 'rate_random_walk':
        excess = walk_avar(np.round(tau / dt), p['k'] * np.sqrt(dt)) * (1 - ONSET / 2)
    else:
        excess = gm_avar(tau, p['sd'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
