"""
Held-out set O of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_n.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out sets A-N, and
the kinds of departure differ from shape to shape:

- internal_lowpass: an emitter-follower output stage: the sensor's analog output buffer drives
  its anti-alias capacitor through a follower that sources current easily and sinks it through
  a weaker pull-down, so the held value rises with a time tau / 4 and falls with tau:
  y_k = y_(k-1) + (1 - a_up) (x_k - y_(k-1)) when x_k > y_(k-1), (1 - a_dn) (...) otherwise,
  a = exp(-dt / time): an asymmetric (attack / release) smoother, nonlinear, which rectifies
  noise (the output's mean moves up, its marginal is skewed) besides correlating it;
- vibration: a spindle coasting down: a centrifuge on the next bench runs at 30 Hz and is
  switched off at a time t_off in 30-50 % of the record; viscous drag slows it exponentially,
  f(t) = 30 Hz e^(-(t - t_off) / 150 s), and its unbalance force, and the rocking with it,
  goes as the speed squared, A e^(-2 (t - t_off) / 150 s), the phase continuous: a tone, then
  one deterministic down-chirp that dies out (f0 150 s = 4500 revolutions after switch-off);
- temperature_drift: a phase-change heat sink: the die warms towards T_hot with a 600 s lag
  from power-on (the record starting t0 in 0-60 s after it) until the package's wax heat sink
  reaches its melting point at 0.4 T_hot; the latent heat then holds the temperature there for
  1800 s, after which the warming resumes where it left off: A (1 - e^(-t_w / 600 s)), t_w
  the warming time with the melting spell cut out: a rise, a plateau (a thermal arrest) with
  two kinks, and a second rise;
- bias_instability: an envelope detector's flicker: the amplitude detector of the sense
  pick-off responds to the magnitude of the quadrature signal, |I + iQ|, whose in-phase and
  quadrature parts carry independent 1/f noise (Gaussian sums of sixteen first-order
  processes, three per decade, 0.05-5000 s, unit variance each); the magnitude leaks into the
  rate: b (R - sqrt(pi / 2)) / sqrt(2 - pi / 2), R the Rayleigh envelope: sd b, skewed (skew
  0.63), bounded below, autocovariance b^2 (pi / 2) (2F1(-1/2, -1/2; 1; rho^2) - 1) /
  (2 - pi / 2);
- rate_random_walk: a walk through a trim DAC: the stress that sets the bias random-walks
  (coefficient K), but it reaches the output through the ASIC's stress compensation, whose trim
  is written continuously in whole LSBs of D = K sqrt(100 s): b = D round((W + c) / D), c a
  uniform offset: a lattice of levels, chattering between neighbours each time the walk
  crosses a half-LSB (most level changes undo the previous one), K^2 tau / 3 at long tau;
- gauss_markov: fan-gated convection: convective temperature noise (a first-order Gauss-Markov
  process of time tc) reaches the die only while a thermostat runs the cooling fan, 30 % of
  the time in on spells of mean 60 s (a two-state Markov chain): silent, then Gaussian,
  intermittently; autocovariance sd^2 (p^2 e^(-u / tc) + p (1 - p) e^(-u (1 / tc + 1 / ts))),
  p = 0.3, 1 / ts = 1 / 60 s + 1 / 140 s (excess kurtosis 3 / p - 3 = 7);
- quantization: logarithmic DPCM: a narrow telemetry link sends each sample's angle increment
  as a sign and a logarithm with K codes per octave, Q(v) = sign(v) 2^(round(K log2 |v|) / K),
  the sender tracking the receiver's reconstruction (error feedback), so the angle error stays
  bounded: e_k = Q(v_k) - v_k, v_k = x_k dt - e_(k-1): a relative, signal-dependent angle error
  (multiplicative: large for large increments, nil for small ones), no fixed step;
- resonance: a loaded mount: a hopper on the bench fills through the record, so the mount
  mode's modal mass grows linearly and its frequency falls, f(t) = 32 Hz / sqrt(1 + 1.56 t /
  T) (32 Hz to 20 Hz), at a fixed damping ratio (q = 20) and a fixed rms: a white-driven mode
  whose line sweeps once down through 12 Hz (nonstationary; the record's mean spectrum a broad
  band falling as f^-3, the time the line spends per hertz, not a line).

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- follower: lag-1 autocorrelation, to first order in a: (a_up + a_dn) / 2 (half the
  increments rise, half fall), against 1 / sqrt(n);
- coast-down, phase-change sink: matched to the noise-free waveform (t_off = 0.4 T, zero
  phase; t0 = 30 s), mean removed: |s - mean(s)| / sigma;
- envelope flicker, gated convection: Allan variance excess over N^2 / tau in units of the
  white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]: the
  flicker from its autocovariance (``cov_avar``), the convection as two first-order terms
  (``gm_avar``) of variances sd^2 p^2 and sd^2 p (1 - p);
- DAC walk: the walk's own Allan variance q^2 (2 m^2 + 1) / (6 m), q = K sqrt(dt), in the same
  units (the rounding's own excess, D^2 / 12 spread over ~100 s, adds a little);
- log DPCM: a white angle error e, correlated with its own sample's increment (the coder's
  small gain, as set N's latch skew), c = E[e^2] + E[e v], v ~ N(b dt, sigma^2 dt^2 + Var e)
  (b = 0.003 rad/s the records' bias; the feedback's spread by iteration): relative Allan
  excess 3 c / (m dt N^2), at dt less at 10 dt, against sqrt(3 / n + 40 / (3 n));
- loaded mount: the record's mean PSD (the mean over the sweep of the instantaneous mode's),
  its mean excess over white in the band above half its peak, times sqrt(T B).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
Physical scale: follower fall times of 2.15 ms (edge), 20 and 100 ms; coast-downs of 0.0042,
0.029 and 0.17 deg/s peak at 30 Hz; phase-change sinks of A 0.0069, 0.057 and 0.29 deg/s
(plateaus at 0.4 A; 0.51, 4.2 and 21 degC at 0.0135 (deg/s)/degC); envelope flicker of 30, 72
and 290 deg/h sd; walks of K 2.0e-6, 6e-6 and 3e-5 rad/s/sqrt(s) (LSBs of 0.0012, 0.0034 and
0.017 deg/s); gated convection of 0.018, 0.057 and 0.14 deg/s sd while on (tc 2 s, 2 s and 20
s); log codes of 3.2 (edge), 1 and 0.5 per octave (relative error sd 6 %, 20 % and 43 %); loaded
mounts of 0.025, 0.069 and 0.34 deg/s sd.
"""
import math

from heldout_detect import allan_taus, allan_z, band_excess, gm_avar
import numpy as np
from scipy import special
from validate_diagnosis_heldout_k import walk_avar
from validate_diagnosis_heldout_m import cov_avar
from validate_diagnosis_heldout_n import dwell_states, gauss_markov

RISE = 0.25                                         # rise time / fall time of the follower
SPIN_HZ, COAST_S = 30.0, 150.0                      # spindle speed; its coast-down time (s)
OFF_SPAN = (0.3, 0.5)                               # switch-off within this share of the record
WARM_S, MELT, MELT_S = 600.0, 0.4, 1800.0           # die lag; melting point / T_hot; spell (s)
ENV_TAUS = 0.05 * 10.0 ** (np.arange(16) / 3)       # s: the flicker's Gauss-Markov times
DAC_S = 100.0                                       # s: the walk crosses an LSB in ~ this
FAN_SHARE, FAN_ON = 0.3, 60.0                       # fan's share of time; mean on spell (s)
BIAS = 0.003                                        # rad/s: the static records' bias
HOPPER_HZ, HOPPER_LOAD, HOPPER_Q = 32.0, 1.56, 20.0  # empty-mount mode; added mass; q
BLOCK = 256                                         # samples per block of the mode recursion


def follower(x: np.ndarray, tau: float, dt: float) -> np.ndarray:
    """Asymmetric one-pole: rise time RISE tau, fall time tau, y_(-1) = x_0."""
    a_up, a_dn = np.exp(-dt / (RISE * tau)), np.exp(-dt / tau)
    out = np.empty(x.size)
    y = float(x[0])
    for k, v in enumerate(np.asarray(x, float).tolist()):
        y += (1 - (a_up if v > y else a_dn)) * (v - y)
        out[k] = y
    return out


def follower_r1(tau: float, dt: float) -> float:
    """Lag-1 autocorrelation of ``follower`` on white input to first order: mean of the a's."""
    return float((np.exp(-dt / (RISE * tau)) + np.exp(-dt / tau)) / 2)


def coast(t, amplitude: float, t_off: float, phase: float = 0.0) -> np.ndarray:
    """Spindle rocking: a SPIN_HZ tone until t_off, then its exponential coast-down."""
    t = np.asarray(t, float)
    s = np.maximum(t - t_off, 0.0)
    decay = np.exp(-s / COAST_S)
    cycles = SPIN_HZ * (np.minimum(t, t_off) + COAST_S * (1 - decay))
    return amplitude * decay ** 2 * np.cos(2 * np.pi * cycles + phase)


def pcm_warm(t, amplitude: float) -> np.ndarray:
    """Return A (1 - e^(-t_w / WARM_S)), t_w the warming time less the melting spell."""
    t = np.asarray(t, float)
    t_melt = -WARM_S * np.log(1 - MELT)
    t_w = np.where(t < t_melt, t, np.maximum(t - MELT_S, t_melt))
    return amplitude * -np.expm1(-t_w / WARM_S)


def envelope(n: int, dt: float, rng) -> np.ndarray:
    """Unit-sd, zero-mean Rayleigh envelope of two independent ENV_TAUS 1/f sums."""
    i, q = (sum(gauss_markov(n, tau, dt, rng) for tau in ENV_TAUS) / np.sqrt(ENV_TAUS.size)
            for _ in range(2))
    return (np.hypot(i, q) - np.sqrt(np.pi / 2)) / np.sqrt(2 - np.pi / 2)


def envelope_rho(u) -> np.ndarray:
    """Correlation of either 1/f component at lag u."""
    return np.mean(np.exp(-np.abs(np.asarray(u, float))[..., None] / ENV_TAUS), axis=-1)


def envelope_cov(u, b: float) -> np.ndarray:
    """Autocovariance b^2 (pi / 2) (2F1(-1/2, -1/2; 1; rho^2) - 1) / (2 - pi / 2)."""
    rho = envelope_rho(u)
    return b * b * np.pi / 2 * (special.hyp2f1(-0.5, -0.5, 1.0, rho * rho) - 1) / (2 - np.pi / 2)


def dac_walk(n: int, k: float, dt: float, rng) -> tuple:
    """Return (bias, walk): a walk W of intensity k; D round((W + c) / D), D = k sqrt(DAC_S)."""
    lsb = k * np.sqrt(DAC_S)
    walk = np.cumsum(rng.standard_normal(n)) * k * np.sqrt(dt)
    return lsb * np.round((walk + rng.uniform(0, lsb)) / lsb), walk


def fan_gated(n: int, sd: float, tc: float, dt: float, rng) -> np.ndarray:
    """Gauss-Markov (sd, tc) while the fan runs (a FAN_SHARE of the time), zero otherwise."""
    means = [FAN_ON * (1 - FAN_SHARE) / FAN_SHARE, FAN_ON]          # off, on
    on = dwell_states(n, dt, means, int(rng.uniform() < FAN_SHARE), rng)
    return sd * on * gauss_markov(n, tc, dt, rng)


def fan_terms(sd: float, tc: float) -> list:
    """Return ``fan_gated``'s autocovariance as (variance, time) exponential terms."""
    p = FAN_SHARE
    ts = 1 / (1 / FAN_ON + 1 / (FAN_ON * (1 - p) / p))
    return [(sd * sd * p * p, tc), (sd * sd * p * (1 - p), 1 / (1 / tc + 1 / ts))]


def log_code(v, k: float) -> np.ndarray:
    """Return sign(v) 2^(round(k log2 |v|) / k) (0 for v = 0)."""
    v = np.asarray(v, float)
    mag = np.abs(v)
    safe = np.where(mag > 0, mag, 1.0)
    return np.where(mag > 0, np.sign(v) * 2.0 ** (np.round(k * np.log2(safe)) / k), 0.0)


def log_dpcm(inc: np.ndarray, k: float) -> np.ndarray:
    """Reconstructed angle after each increment of ``inc``, coded with error feedback."""
    out = np.empty(inc.size)
    err = 0.0
    for i, d in enumerate(np.asarray(inc, float).tolist()):
        v = d - err
        mag = abs(v)
        q = 0.0 if mag == 0 else math.copysign(2.0 ** (round(k * math.log2(mag)) / k), v)
        err = q - v
        out[i] = err
    return np.cumsum(inc) + out


def log_c0(k: float, dt: float, sig: float) -> float:
    """
    Return c = E[e^2] + E[e v] of the log coder on v ~ N(BIAS dt, (sig dt)^2 + Var e).

    The angle error's variance plus its covariance with the increment (the coder's small gain),
    the feedback's own spread solved for by iteration.
    """
    u = np.linspace(-8, 8, 400001)
    w = np.exp(-u ** 2 / 2)
    w /= w.sum()
    var_e = 0.0
    for _ in range(4):
        v = BIAS * dt + np.sqrt((sig * dt) ** 2 + var_e) * u
        e = log_code(v, k) - v
        var_e = float(np.sum(w * e * e))
    return float(var_e + np.sum(w * e * v))


def mode_poles(f_hz, dt: float):
    """Return (r, theta, unit-drive variance) of the mode at f_hz: fixed damping HOPPER_Q."""
    zeta = 1 / (2 * HOPPER_Q)
    w = 2 * np.pi * np.asarray(f_hz, float)
    r, th = np.exp(-zeta * w * dt), w * np.sqrt(1 - zeta * zeta) * dt
    var = (1 + r * r) / ((1 - r * r) * (1 - 2 * r * r * np.cos(2 * th) + r ** 4))
    return r, th, var


def hopper_freq(t, big_t: float) -> np.ndarray:
    """Mode frequency HOPPER_HZ / sqrt(1 + HOPPER_LOAD t / T)."""
    return HOPPER_HZ / np.sqrt(1 + HOPPER_LOAD * np.asarray(t, float) / big_t)


def loaded_mode(n: int, sigma: float, dt: float, rng) -> np.ndarray:
    """White-driven mode whose frequency falls by ``hopper_freq``, sd ``sigma`` throughout."""
    r, th, var = mode_poles(hopper_freq(np.arange(n) * dt, n * dt), dt)
    p = r * np.exp(1j * th)
    gain = p / (p - np.conj(p))
    burn = int(10.0 / dt)
    r0, th0, _ = mode_poles(HOPPER_HZ, dt)
    z = 0j
    for w in rng.standard_normal(burn).tolist():            # run in at the starting pole
        z = r0 * np.exp(1j * th0) * z + w
    w = rng.standard_normal(n)
    out = np.empty(n, complex)
    for s in range(0, n, BLOCK):
        pb = np.cumprod(p[s:s + BLOCK])
        zb = pb * (z + np.cumsum(w[s:s + BLOCK] / pb))
        out[s:s + BLOCK] = zb
        z = zb[-1]
    return sigma * 2 * np.real(gain * out) / np.sqrt(var)


def loaded_psd(f, sigma: float, dt: float, big_t: float, points: int = 97) -> np.ndarray:
    """One-sided PSD of ``loaded_mode`` averaged over the record (``points`` along the sweep)."""
    z1 = np.exp(-2j * np.pi * np.asarray(f, float) * dt)
    t = (np.arange(points) + 0.5) * big_t / points
    out = 0.0
    for r, th, var in zip(*mode_poles(hopper_freq(t, big_t), dt)):
        out = out + 2 * dt * sigma ** 2 / var / np.abs(1 - 2 * r * np.cos(th) * z1
                                                       + r * r * z1 * z1) ** 2
    return out / points


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def buffered(x, rng, tau):
        return follower(x, tau, dt)

    def spindle(x, rng, amplitude):
        t = np.arange(x.size) * dt
        t_off = rng.uniform(*OFF_SPAN) * x.size * dt
        return x + coast(t, amplitude, t_off, rng.uniform(0, 2 * np.pi))

    def sink(x, rng, amplitude):
        return x + pcm_warm(np.arange(x.size) * dt + rng.uniform(0, 60), amplitude)

    def detector(x, rng, b):
        return x + b * envelope(x.size, dt, rng)

    def trimmed(x, rng, k):
        return x + dac_walk(x.size, k, dt, rng)[0]

    def gated(x, rng, sd, tc):
        return x + fan_gated(x.size, sd, tc, dt, rng)

    def coded(x, rng, k):
        theta = log_dpcm(x * dt, k)
        return np.diff(np.r_[0.0, theta]) / dt

    def hopper(x, rng, sigma):
        return x + loaded_mode(x.size, sigma, dt, rng)

    return {
        'internal_lowpass': (buffered, [{'tau': 0.02}, {'tau': 0.1}, {'tau': 2.15e-3}]),
        'vibration': (spindle, [{'amplitude': 5e-4}, {'amplitude': 3e-3},
                                {'amplitude': 7.3e-5}]),
        'temperature_drift': (sink, [{'amplitude': 1e-3}, {'amplitude': 5e-3},
                                     {'amplitude': 1.2e-4}]),
        'bias_instability': (detector, [{'b': 3.5e-4}, {'b': 1.4e-3}, {'b': 1.43e-4}]),
        'rate_random_walk': (trimmed, [{'k': 6e-6}, {'k': 3e-5}, {'k': 2.03e-6}]),
        'gauss_markov': (gated, [{'sd': 1e-3, 'tc': 2.0}, {'sd': 2.5e-3, 'tc': 20.0},
                                 {'sd': 3.16e-4, 'tc': 2.0}]),
        'quantization': (coded, [{'k': 1.0}, {'k': 0.5}, {'k': 3.2}]),
        'resonance': (hopper, [{'sigma': 1.2e-3}, {'sigma': 6e-3}, {'sigma': 4.33e-4}]),
    }


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn, p = n * dt, n_arw ** 2, params
    t = np.arange(n) * dt
    if name == 'internal_lowpass':
        return float(follower_r1(p['tau'], dt) * np.sqrt(n))
    if name in ('vibration', 'temperature_drift'):
        s = (coast(t, p['amplitude'], 0.4 * big_t) if name == 'vibration'
             else pcm_warm(t + 30.0, p['amplitude']))
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        rel = [3 * log_c0(p['k'], dt, sig) / (m * dt * nn) for m in (1, 10)]
        return float(abs(rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n)))
    if name == 'resonance':
        ex, width = band_excess(lambda f: loaded_psd(f, p['sigma'], dt, big_t), dt, sig)
        return float(ex * np.sqrt(big_t * width))
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = cov_avar(lambda u: envelope_cov(u, p['b']), tau)
    elif name == 'rate_random_walk':
        excess = walk_avar(np.round(tau / dt), p['k'] * np.sqrt(dt))
    else:
        excess = sum(gm_avar(tau, np.sqrt(v), tc) for v, tc in fan_terms(p['sd'], p['tc']))
    return allan_z(excess, tau, nn, big_t)
