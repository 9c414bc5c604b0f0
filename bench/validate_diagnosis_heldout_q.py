"""
Held-out set Q of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_o.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]; the eight catalogue names, as set O);
every shape is a physical form unlike the catalogue's, the development shapes
(``validate_diagnosis.py``) and held-out sets A-P, and the kinds of departure differ from
shape to shape:

- internal_lowpass: a distributed RC line: an analog-output gyro's DAC updates once a sample
  period (a zero-order hold) and its signal reaches the logger's ADC through a long
  high-resistance strip over a ground plane (a thin-film resistor line, open at the ADC end),
  so it diffuses along the line rather than charging one capacitor: H(s) = 1 / cosh(sqrt(s
  tau)), tau = R C of the whole line, the logger sampling the far end just before each update:
  y_k = sum_j x_(k-j) (S((j+1) dt) - S(j dt)), S the line's step response (2 sum (-1)^n
  erfc((2n+1) / (2 sqrt(t / tau))), or 1 - sum (-1)^(k+1) 4 / ((2k-1) pi) e^(-(2k-1)^2 pi^2
  t / (4 tau))): an infinite cascade of real poles, a dead time and no overshoot (3 dB at 0.387
  / tau), DC gain 1;
- vibration: a hunting servo: a robot joint beside the bench (or carrying the bench) holds
  position by a servo that limit-cycles in its gear backlash at HUNT_HZ = 3.3 Hz: the joint
  sweeps across the backlash at the servo's saturated speed and reverses on each gear flank in
  a fifth of the time (HUNT_RAMP = 0.2), so the rocking RATE is a symmetric trapezoid wave, A
  clip(tri(t) / 0.2, -1, 1) (the angle a rounded triangle): odd harmonics only, amplitudes
  (4 A / (pi k)) sin(0.1 pi k) / (0.1 pi k), all of them folded into the output band;
- temperature_drift: a heat soak into potting: the module is potted in a thick epoxy block
  and the electronics' dissipation flows into it as a constant flux into a semi-infinite
  solid, so the die's temperature, and the bias, rise as the square root of the time since
  power-on: A sqrt(t' / 7200 s), t' = t + t0, t0 in 0-60 s (A the rise 2 h after power-on): a
  power law, no time constant, infinite initial slope, never settling;
- bias_instability: warming leakage flicker: the 1/f noise comes from a leakage-dominated
  node whose noise power goes as the leakage current squared, which doubles every 10 degC;
  the die warms by ~16 degC after power-on through a HEAT_S = 1200 s lag, so the drive of the
  flicker (a Gaussian sum of 21 first-order processes, four per decade, 0.02-2000 s, unit
  variance each) has a variance that rises from 1 / 9 to 1 of its hot value: s(t')^2 = 1 / 9
  + (8 / 9) (1 - e^(-t' / HEAT_S)), t' = t + t0 (t0 in 0-60 s); each component's variance
  follows s^2 through its own time (the slow ones lag): non-stationary, growing (b the hot sd);
- rate_random_walk: a thermal-cycling ratchet: the bench heater cycles every CYCLE_S = 300 s
  and the die attach creeps only while hot, in the first half of each cycle: each cycle adds an
  independent Gaussian step (sd K sqrt(CYCLE_S)) spread over the hot half as a raised cosine,
  and the bias is flat through the cool half (random cycle phase): a staircase of smooth
  risers and flat treads at a fixed cadence, K^2 tau / 3 at long tau;
- gauss_markov: processor load bursts: the robot's processor beside the sensor is busy BUSY =
  25 % of the time in bursts (a two-state Markov chain, correlation time tc: mean busy spell tc
  / 0.75, idle spell tc / 0.25) and heats the die through a short thermal path of time LAG tc
  (LAG = 0.25): a telegraph through a one-pole, mean removed: bounded (between the idle and
  busy levels), skewed upwards, autocovariance sd^2 (e^(-u / tc) - LAG e^(-u / (LAG tc))) /
  (1 - LAG);
- quantization: a pipelined carry: the DSP requantizes each angle increment to the output step
  q and carries the remainder so that no angle is lost, but in its two-stage pipeline the
  carry reaches the sample after next: u_k = x_k dt - e_(k-2), word q round(u_k / q), e_k the
  rounding error; the even and the odd samples form two independent error-feedback chains
  (two interleaved accumulators, each rounded), and the angle error is e_k + e_(k-1): bounded
  by q, triangular, lag-1 correlated (angle error PSD ~ cos^2(pi f dt), rate error PSD ~
  sin^2(2 pi f dt): nil at DC and at Nyquist), rate words on a q / dt lattice;
- resonance: a base-excited bracket: the gyro sits on a cantilevered bracket on a bench whose
  floor rocks broadband (white over the output band); the gyro senses the base's rocking rate
  directly plus the bracket's flexural rotation, which responds to the base's angular
  acceleration with a participation PARTICIPATION = 0.6: T(s) = 1 - 0.6 s^2 / (s^2 + 2 zeta w0
  s + w0^2), f0 = 23.7 Hz, q = 15 (matched z: poles and zeros mapped by e^(s dt), DC gain 1):
  unity below the mode, the peak, an anti-resonance at f0 / sqrt(0.4) = 37.5 Hz and a low
  floor above it (|T|^2 0.02 at 50 Hz; (1 - 0.6)^2 = 0.16 only far above the band): a line on
  the base's broadband rocking with a notch beside it (sigma the rms of the whole added rate).

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- RC line: lag-1 autocorrelation of the output on white input, sum h_j h_(j+1) / sum h_j^2,
  against 1 / sqrt(n);
- hunting servo, heat soak: matched to the noise-free waveform (zero phase; t0 = 30 s), mean
  removed: |s - mean(s)| / sigma;
- warming flicker, ratchet, load bursts: Allan variance excess over N^2 / tau in units of the
  white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]: the
  flicker from its hot autocovariance (``cov_avar``) times the record's mean drive variance
  (t0 = 30 s; the slow components' lag ignored), the ratchet exactly, averaged over the cycle
  phase (``ratchet_avar``), the load bursts as two first-order terms (``gm_avar``, one of
  negative weight);
- pipelined carry: e white and uniform (variance v = q^2 / 12; the increments' spread covers
  the step), so the angle error's autocovariance c is 2 v, v, 0, ...: relative Allan excess
  (3 c0 - 4 c_m + c_2m) / (m dt N^2), 2 v / (dt N^2) at dt less 0.6 v / (dt N^2) at 10 dt,
  against sqrt(3 / n + 40 / (3 n)) (as sets O and P);
- bracket: the one-sided PSD 2 dt sigma_b^2 |T(e^(i 2 pi f dt))|^2, its mean excess over
  white in the band above half its peak, times sqrt(T B).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
Physical scale: RC lines of tau 4.4 ms (edge), 20 and 80 ms (3 dB at 88 Hz, 19 Hz and 4.8
Hz); hunting servos of 0.002, 0.029 and 0.17 deg/s (backlash swings of 0.27, 3.9 and 23
mdeg); heat soaks of A 0.0081, 0.029 and 0.11 deg/s (0.6, 2.1 and 8.5 degC at 0.0135
(deg/s)/degC); warming flicker of 22, 72 and 290 deg/h hot sd; ratchets of K 2.04e-6, 5e-6 and
2.5e-5 rad/s/sqrt(s) (steps of 0.002, 0.005 and 0.025 deg/s sd a cycle); load bursts of 0.0089,
0.057 and 0.14 deg/s sd (tc 2 s, 2 s and 20 s); output steps q of 28, 60 and 120 urad (words
of 0.16, 0.34 and 0.69 deg/s); brackets of 0.020, 0.069 and 0.34 deg/s sd.
"""
from heldout_detect import allan_taus, allan_z, band_excess, gm_avar
import numpy as np
from scipy import signal, special
from validate_diagnosis_heldout_m import cov_avar
from validate_diagnosis_heldout_n import dwell_states

HUNT_HZ, HUNT_RAMP = 3.3, 0.2                       # limit cycle; share of time reversing
SOAK_S = 7200.0                                     # s: A is the rise this long after power-on
FLK_TAUS = 0.02 * 10.0 ** (np.arange(21) / 4)       # s: the flicker's Gauss-Markov times
HEAT_S, HOT_COLD = 1200.0, 9.0                      # die lag (s); hot / cold drive variance
CYCLE_S = 300.0                                     # s: heater cycle (creep in its hot half)
BUSY, LAG = 0.25, 0.25                              # processor's busy share; die lag / tc
BRACKET_HZ, BRACKET_Q, PARTICIPATION = 23.7, 15.0, 0.6


def line_step(t, tau: float) -> np.ndarray:
    """Step response of 1 / cosh(sqrt(s tau)): erfc series for t < tau, exponential beyond."""
    t = np.asarray(t, float)
    x = np.maximum(t.ravel() / tau, 1e-300)
    n = np.arange(12)[:, None]
    short = 2 * np.sum((-1.0) ** n * special.erfc((2 * n + 1) / (2 * np.sqrt(x))), axis=0)
    k = np.arange(1, 61)[:, None]
    c = (-1.0) ** (k + 1) * 4 / ((2 * k - 1) * np.pi)
    p = (2 * k - 1) ** 2 * np.pi ** 2 / 4
    long = 1 - np.sum(c * np.exp(-p * np.maximum(x, 1.0)), axis=0)
    return np.where(x < 1, short, long).reshape(t.shape)


def line_kernel(tau: float, dt: float) -> np.ndarray:
    """Zero-order-hold kernel h_j = S((j + 1) dt) - S(j dt) of the line (sum 1 - 1e-12)."""
    length = int(np.ceil(12 * tau / dt)) + 2
    return np.diff(line_step(np.arange(length + 1) * dt, tau))


def rc_line(x: np.ndarray, tau: float, dt: float) -> np.ndarray:
    """Return the line's far end sampled each period (input held at x_0 before the record)."""
    h = line_kernel(tau, dt)
    x = np.asarray(x, float)
    return np.convolve(np.r_[np.full(h.size - 1, x[0]), x], h, mode='valid')


def line_r1(tau: float, dt: float) -> float:
    """Lag-1 autocorrelation of ``rc_line`` on white input: sum h_j h_(j+1) / sum h_j^2."""
    h = line_kernel(tau, dt)
    return float(np.sum(h[:-1] * h[1:]) / np.sum(h * h))


def hunt(t, amplitude: float, phase: float = 0.0) -> np.ndarray:
    """Trapezoid rate A clip(tri / HUNT_RAMP, -1, 1), tri the unit triangle at HUNT_HZ."""
    u = np.mod(HUNT_HZ * np.asarray(t, float) + phase / (2 * np.pi), 1.0)
    tri = 2 / np.pi * np.arcsin(np.sin(2 * np.pi * u))
    return amplitude * np.clip(tri / HUNT_RAMP, -1.0, 1.0)


def hunt_line(k: int, amplitude: float) -> float:
    """Amplitude of harmonic k of ``hunt``: (4 A / (pi k)) sinc(k HUNT_RAMP / 2), odd k."""
    return float(4 * amplitude / (np.pi * k) * np.sinc(k * HUNT_RAMP / 2)) if k % 2 else 0.0


def soak(t, amplitude: float) -> np.ndarray:
    """Return A sqrt(t / SOAK_S), t from power-on."""
    return amplitude * np.sqrt(np.maximum(np.asarray(t, float), 0.0) / SOAK_S)


def drive_variance(t) -> np.ndarray:
    """Flicker drive variance, hot = 1: 1 / HOT_COLD + (1 - 1 / HOT_COLD) (1 - e^(-t / HEAT_S))."""
    return 1 / HOT_COLD - (1 - 1 / HOT_COLD) * np.expm1(-np.asarray(t, float) / HEAT_S)


def warming_flicker(n: int, dt: float, t0: float, rng) -> np.ndarray:
    """Sum of FLK_TAUS first-order processes, drive sd sqrt(``drive_variance``(t + t0))."""
    s = np.sqrt(drive_variance(np.arange(n) * dt + t0))
    out = np.zeros(n)
    for tau in FLK_TAUS:
        c = np.exp(-dt / tau)
        w = rng.standard_normal(n) * np.sqrt(1 - c * c) * s
        out += signal.lfilter([1.0], [1.0, -c], w, zi=[c * s[0] * rng.standard_normal()])[0]
    return out / np.sqrt(FLK_TAUS.size)


def flicker_cov(u, b: float) -> np.ndarray:
    """Hot autocovariance b^2 mean_i e^(-|u| / tau_i)."""
    return b * b * np.mean(np.exp(-np.abs(np.asarray(u, float))[..., None] / FLK_TAUS), axis=-1)


def mean_drive(big_t: float, t0: float = 30.0) -> float:
    """Mean of ``drive_variance`` over a record of length big_t started t0 after power-on."""
    a = (1 - 1 / HOT_COLD) * HEAT_S / big_t
    return float(1 - a * (np.exp(-t0 / HEAT_S) - np.exp(-(t0 + big_t) / HEAT_S)))


def riser(u) -> np.ndarray:
    """Share of a cycle's step taken u into the cycle: raised cosine over the hot half."""
    h = CYCLE_S / 2
    u = np.asarray(u, float)
    return np.where(u < 0, 0.0, np.where(u < h, (1 - np.cos(np.pi * u / h)) / 2, 1.0))


def ratchet(n: int, k: float, dt: float, rng) -> np.ndarray:
    """Cycle steps N(0, k^2 CYCLE_S), each spread by ``riser``, at a random cycle phase."""
    t = np.arange(n) * dt + rng.uniform(0, CYCLE_S)
    j = np.floor(t / CYCLE_S).astype(int)
    steps = rng.standard_normal(j[-1] + 1) * k * np.sqrt(CYCLE_S)
    before = np.r_[0.0, np.cumsum(steps)[:-1]]
    return before[j] + steps[j] * riser(t - j * CYCLE_S)


def _riser_integral(u) -> np.ndarray:
    """Integral of ``riser`` from -inf to u."""
    h = CYCLE_S / 2
    u = np.asarray(u, float)
    ramp = u / 2 - h / (2 * np.pi) * np.sin(np.pi * np.clip(u, 0, h) / h)
    return np.where(u < 0, 0.0, np.where(u < h, ramp, u - h / 2))


def ratchet_avar(tau, k: float, points: int = 6001) -> np.ndarray:
    """
    Allan variance of ``ratchet`` averaged over the cycle phase.

    (k^2 / 2) int (R2(s) - R1(s))^2 ds over the start s of a cycle, R1 and R2 the means of its
    riser over [0, tau] and [tau, 2 tau]: K^2 tau / 3 for steps without riser.
    """
    out = []
    for tt in np.atleast_1d(np.asarray(tau, float)):
        s = np.linspace(-CYCLE_S / 2, 2 * tt, points)
        d = (_riser_integral(2 * tt - s) - 2 * _riser_integral(tt - s)
             + _riser_integral(-s)) / tt
        out.append(k * k / 2 * np.trapezoid(d * d, s))
    return np.array(out)


def load_sd() -> float:
    """Stationary sd of the unit telegraph (0 idle, 1 busy) through the die's lag."""
    return float(np.sqrt(BUSY * (1 - BUSY) / (1 + LAG)))


def load_bursts(n: int, sd: float, tc: float, dt: float, rng) -> np.ndarray:
    """Busy/idle telegraph (share BUSY, correlation time tc) through a one-pole LAG tc."""
    means = [tc / BUSY, tc / (1 - BUSY)]                            # idle, busy spells
    busy = dwell_states(n, dt, means, int(rng.uniform() < BUSY), rng).astype(float)
    a = np.exp(-dt / (LAG * tc))
    v = signal.lfilter([1 - a], [1.0, -a], busy, zi=[a * busy[0]])[0]
    return sd * (v - BUSY) / load_sd()


def load_cov(u, sd: float, tc: float) -> np.ndarray:
    """Autocovariance sd^2 (e^(-|u| / tc) - LAG e^(-|u| / (LAG tc))) / (1 - LAG)."""
    u = np.abs(np.asarray(u, float))
    return sd * sd * (np.exp(-u / tc) - LAG * np.exp(-u / (LAG * tc))) / (1 - LAG)


def pipelined_counts(d: np.ndarray, q: float) -> np.ndarray:
    """Words (units of q) sent so far: the two interleaved chains' rounded running sums."""
    d = np.asarray(d, float)
    counts = np.zeros(d.size)
    for par in (0, 1):
        k = np.round(np.cumsum(d[par::2]) / q)
        idx = (np.arange(d.size) - par) // 2
        counts += np.where(idx >= 0, k[np.maximum(idx, 0)], 0.0)
    return counts


def pipelined(x: np.ndarray, q: float, dt: float) -> np.ndarray:
    """Rate words of the pipelined carry: q diff(counts) / dt (first word from zero)."""
    counts = pipelined_counts(np.asarray(x, float) * dt, q)
    return q * np.diff(np.r_[0.0, counts]) / dt


def bracket_filter(dt: float):
    """Return (b, a) of T(s) = 1 - PARTICIPATION s^2 / (s^2 + 2 zeta w0 s + w0^2), matched z."""
    w0, zeta, kap = 2 * np.pi * BRACKET_HZ, 1 / (2 * BRACKET_Q), PARTICIPATION
    zeros = np.exp(np.roots([1 - kap, 2 * zeta * w0, w0 * w0]) * dt)
    poles = np.exp(np.roots([1.0, 2 * zeta * w0, w0 * w0]) * dt)
    b, a = np.real(np.poly(zeros)), np.real(np.poly(poles))
    return b * np.sum(a) / np.sum(b), a                            # DC gain 1


def bracket_gain2(f, dt: float) -> np.ndarray:
    """Return |T(e^(i 2 pi f dt))|^2."""
    b, a = bracket_filter(dt)
    _, h = signal.freqz(b, a, worN=2 * np.pi * np.asarray(f, float) * dt)
    return np.abs(h) ** 2


def bracket_base(sigma: float, dt: float) -> float:
    """Return the base rocking sd sigma_b that gives the added rate an rms ``sigma``."""
    f = (np.arange(2 ** 16) + 0.5) * 0.5 / dt / 2 ** 16
    return float(sigma / np.sqrt(np.mean(bracket_gain2(f, dt))))


def bracket(n: int, sigma: float, dt: float, rng) -> np.ndarray:
    """Return the base rocking (white, sd sigma_b) through T, run in for 20 q / (pi f0)."""
    b, a = bracket_filter(dt)
    burn = int(20 * BRACKET_Q / (np.pi * BRACKET_HZ * dt)) + 1
    w = rng.standard_normal(n + burn) * bracket_base(sigma, dt)
    return signal.lfilter(b, a, w)[burn:]


def bracket_psd(f, sigma: float, dt: float) -> np.ndarray:
    """One-sided PSD 2 dt sigma_b^2 |T|^2 of ``bracket``."""
    return 2 * dt * bracket_base(sigma, dt) ** 2 * bracket_gain2(f, dt)


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def line(x, rng, tau):
        return rc_line(x, tau, dt)

    def servo(x, rng, amplitude):
        return x + hunt(np.arange(x.size) * dt, amplitude, rng.uniform(0, 2 * np.pi))

    def potted(x, rng, amplitude):
        return x + soak(np.arange(x.size) * dt + rng.uniform(0, 60), amplitude)

    def leakage(x, rng, b):
        return x + b * warming_flicker(x.size, dt, rng.uniform(0, 60), rng)

    def cycling(x, rng, k):
        return x + ratchet(x.size, k, dt, rng)

    def processor(x, rng, sd, tc):
        return x + load_bursts(x.size, sd, tc, dt, rng)

    def carried(x, rng, q):
        return pipelined(x, q, dt)

    def mounted(x, rng, sigma):
        return x + bracket(x.size, sigma, dt, rng)

    return {
        'internal_lowpass': (line, [{'tau': 0.02}, {'tau': 0.08}, {'tau': 4.4e-3}]),
        'vibration': (servo, [{'amplitude': 5e-4}, {'amplitude': 3e-3},
                              {'amplitude': 3.53e-5}]),
        'temperature_drift': (potted, [{'amplitude': 5e-4}, {'amplitude': 2e-3},
                                       {'amplitude': 1.41e-4}]),
        'bias_instability': (leakage, [{'b': 3.5e-4}, {'b': 1.4e-3}, {'b': 1.07e-4}]),
        'rate_random_walk': (cycling, [{'k': 5e-6}, {'k': 2.5e-5}, {'k': 2.04e-6}]),
        'gauss_markov': (processor, [{'sd': 1e-3, 'tc': 2.0}, {'sd': 2.5e-3, 'tc': 20.0},
                                     {'sd': 1.56e-4, 'tc': 2.0}]),
        'quantization': (carried, [{'q': 6e-5}, {'q': 1.2e-4}, {'q': 2.82e-5}]),
        'resonance': (mounted, [{'sigma': 1.2e-3}, {'sigma': 6e-3}, {'sigma': 3.5e-4}]),
    }


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn, p = n * dt, n_arw ** 2, params
    t = np.arange(n) * dt
    if name == 'internal_lowpass':
        return float(line_r1(p['tau'], dt) * np.sqrt(n))
    if name in ('vibration', 'temperature_drift'):
        s = (hunt(t, p['amplitude']) if name == 'vibration'
             else soak(t + 30.0, p['amplitude']))
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        v = p['q'] ** 2 / 12
        rel = [(3 * 2 * v - 4 * c_m + c_2m) / (m * dt * nn)
               for m, c_m, c_2m in ((1, v, 0.0), (10, 0.0, 0.0))]
        return float(abs(rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n)))
    if name == 'resonance':
        ex, width = band_excess(lambda f: bracket_psd(f, p['sigma'], dt), dt, sig)
        return float(ex * np.sqrt(big_t * width))
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = cov_avar(lambda u: flicker_cov(u, p['b']), tau) * mean_drive(big_t)
    elif name == 'rate_random_walk':
        excess = ratchet_avar(tau, p['k'])
    else:
        tc, sd, w = p['tc'], p['sd'], 1 / (1 - LAG)
        excess = w * (gm_avar(tau, sd, tc) - LAG * gm_avar(tau, sd, LAG * tc))
    return allan_z(excess, tau, nn, big_t)
