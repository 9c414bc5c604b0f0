"""
Held-out set S of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_r.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]; the nine names of sets P and R, with
``stale_samples``); every shape is a physical form unlike the catalogue's, the development
shapes (``validate_diagnosis.py``) and held-out sets A-R, and the kinds of departure differ
from shape to shape:

- internal_lowpass: a mode-matched sense bandwidth: in a mode-matched gyro the rate and the
  proof mass's own Brownian (mechanical) noise both reach the output through the sense mode,
  which after demodulation is a first-order low-pass of time tau (corner f0 / (2 q) of the
  mode), while the pick-off amplifier's (electronic) noise is added after it, unfiltered; a
  share MECH = 0.6 of the white noise power is mechanical: the record's white part is split
  into its two independent Gaussian shares (m = MECH x + sqrt(MECH (1 - MECH)) sigma w, e = x
  - m), and y = h * m + e, h the one-pole (1 - a) / (1 - a z^-1), a = e^(-dt / tau), started
  settled: DC gain 1, output PSD sigma^2 (MECH |H|^2 + 1 - MECH): a low-pass onto a SHELF,
  its high band held at 1 - MECH of the white level however long tau is (a partial filter);
- vibration: an engine-driven generator: a single-cylinder four-stroke generator set on the
  bench (3540 rpm under load: firing at ENGINE_HZ = 29.5 Hz) rocks its frame once a firing
  cycle, the rocking rate over cycle k being a_k sin(2 pi u), u the cycle's phase (one full
  sine a cycle: the angle returns each cycle); the combustion varies from cycle to cycle,
  a_k = A (1 + CYCLE_CV g_k), CYCLE_CV = 0.15, g_k independent N(0, 1), and a share MISFIRE =
  4 % of the cycles misfire (a_k = 0), independently: a line at ENGINE_HZ of amplitude A (1 -
  MISFIRE) on a broad pedestal (the cycle shape's spectrum, |P(f)|^2 Var(a) F) carrying the
  amplitude scatter, and sporadic silent cycles;
- temperature_drift: a lagging compensation: the bias's temperature coefficient is
  compensated with the reading of the board's thermistor, which lags the die: after power-on
  the die warms with DIE_S = 200 s and the thermistor follows the die through a further
  SENSOR_S = 900 s lag, so the compensated output keeps c (T_die - T_sensor): A (e^(-t' /
  SENSOR_S) - e^(-t' / DIE_S)) / r_peak, t' = t + t0 (t0 in 0-60 s), r_peak the bracket's
  maximum (at 387 s): a transient from zero at power-on, a peak A and a slow return to zero (a
  difference of exponentials, nothing left after the warm-up);
- bias_instability: a hierarchical landscape: the die-attach polymer is a glass whose local
  configurations form an ultrametric tree of TREE_LEVELS = 19 levels (Ogielski-Stein
  diffusion): crossing a level-l barrier (Poisson, rate w_l) moves the anchor stress into the
  sibling basin of that level (bit l flips) and leaves it in a random sub-basin of every
  faster level (bits below l drawn afresh, +-1 alike); the bias is b sum_l s_l / sqrt(19): a
  lattice, and a slow crossing moves many levels at once (coordinated, cascading jumps); bit
  l's correlation is exactly e^(-(2 w_l + sum_(m > l) w_m) |u|) = e^(-|u| / tau_l), the w_l
  chosen so that tau_l = TREE_TAUS (three a decade, 0.02-2e4 s): 1/f in between;
- rate_random_walk: slips with anelastic recovery: the die attach slips at Poisson times
  (SLIP_RATE = 0.5 a second) by independent Gaussian amounts s_k, and the adhesive's
  viscoelastic recovery takes back a share RECOVER = 0.7 of each slip exponentially (RECOVER_S
  = 20 s): bias sum_k s_k ((1 - RECOVER) + RECOVER e^(-(t - t_k) / RECOVER_S)) over the slips
  so far: a walk whose increments are anti-persistent over ~20 s, its intensity falling from
  SLIP_RATE E[s^2] at short times to K^2 = SLIP_RATE E[s^2] (1 - RECOVER)^2 at long times
  (PSD K^2 / (2 pi f)^2 plus a first-order term, exactly);
- gauss_markov: field-switched trap kinetics: dielectric traps at the sense electrode exchange
  charge with it at a rate set by the electrode field, and the ASIC's power manager switches
  the electrode bias between its high-performance and low-power levels (a two-state Markov
  chain, mean spell MODE_S = 30 s in each); the traps' occupancy stays in equilibrium (variance
  sd^2 in both modes) but its correlation time switches between tc and SLOW tc (SLOW = 8):
  X_k = c_k X_(k-1) + sd sqrt(1 - c_k^2) w_k, c_k = e^(-dt / tc_k): Gaussian at every instant,
  its memory switching (non-stationary correlation), autocovariance exactly sd^2 pi^T
  exp((G - R) |u|) 1, two exponentials;
- quantization: a counted VFC: the analog gyro's rate drives a charge-balance voltage-to-
  frequency converter whose zero-rate frequency F0 = 50012.37 Hz is not a whole number of
  cycles a 10 ms window (F0 dt = 500 + VFC_NU, VFC_NU = 0.1237), f = F0 + Omega / Q (Q rad a
  cycle); the host counts the cycles in each window and returns (count - F0 dt) Q / dt: the
  integral is kept (no angle lost), the angle error is -Q frac(VFC_NU k + theta_k / Q + p):
  once Q is large against the angle's walk a sample, the counter's idle tones, a sawtooth in
  the angle at VFC_NU / dt (+ the bias's advance) and its folded harmonics, broadened by the
  angle's walk; white and uniform when Q is small;
- resonance: a wire loom: the IMU's connector carries WIRES = 24 loose wires whose free lengths
  spread by a few per cent, each a cantilever whose first mode (WIRE_HZ = 21 Hz times 1 +
  WIRE_SPREAD g_i, g_i the 24 normal quantiles, WIRE_SPREAD = 0.04; q WIRE_Q = 60 each) is
  driven by air currents, and the board senses the sum of their root torques' rocking, equal
  rms each: a line with an inhomogeneous, Gaussian profile (sd 0.84 Hz) made of 24 narrow
  ones, its skirts falling far faster than a Lorentzian of the same width (sigma the sum's
  rms);
- stale_samples: a deadband gateway: the robot's telemetry gateway (an industrial OPC UA /
  MQTT bridge with an absolute deadband) publishes a new rate only when it differs from the
  last published one by at least delta, and the logger records the last published value at
  every tick: y_k = x_k if |x_k - y_(k-1)| >= delta, else y_(k-1): value-dependent holds (a
  hold is likelier where the signal is quiet), and no published step smaller than delta.

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- sense bandwidth: lag-1 autocorrelation of the output on white input, MECH sum h_j h_(j+1)
  / (MECH sum h_j^2 + 1 - MECH), against 1 / sqrt(n) (it saturates for long tau: the strong
  level is set by it, not by the corner);
- generator, lagging compensation: matched to the noise-free waveform (the mean line A (1 -
  MISFIRE) at zero phase, the pedestal not counted; t0 = 30 s), mean removed: |s - mean(s)| /
  sigma;
- landscape, slips, switched kinetics: Allan variance excess over N^2 / tau in units of the
  white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]: the
  landscape as the sum of its levels' ``gm_avar`` (b^2 / 19 each), the slips as K^2 tau / 3
  plus ``gm_avar`` of variance K^2 RECOVER (2 - RECOVER) RECOVER_S / (2 (1 - RECOVER)^2) and
  time RECOVER_S (the PSD's partial fractions), the kinetics as two ``gm_avar`` terms (the
  eigen-decomposition of G - R);
- counted VFC: the angle error's autocovariance c(l) = 2 sum_h (Q / 2 pi h)^2 cos(2 pi h nu l)
  exp(-2 pi^2 h^2 l dt N^2 / Q^2), nu = VFC_NU + b dt / Q (b = 0.003 rad/s the records' bias;
  the angle walking by the white noise, as sets E, M and R): relative Allan excess (3 c0 - 4
  c_l + c_2l) / (l dt N^2) at dt less at 10 dt, against sqrt(3 / n + 40 / (3 n));
- wire loom: the mean PSD (the sum of the 24 modes'), its mean excess over white in the band
  above half its peak, times sqrt(T B);
- deadband: the exact repeats of the harness's output (rounded to LSB = 0.05 deg/s): the
  share s of zero first differences, q0 on white noise, from the published value's stationary
  law (a Markov chain on it, solved on a grid): s = E[P(hold) + P(no hold, same LSB level)];
  z = (s - q0) sqrt(n / (q0 (1 - q0))) (as sets P and R, with the deadband's own share).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
Physical scale: sense bandwidths tau of 2.07 ms (edge; 77 Hz), 5 and 15 ms (32 and 11 Hz);
generators of A 0.0028, 0.029 and 0.17 deg/s; compensation residuals peaking at 0.0065, 0.034
and 0.11 deg/s (0.5, 2.5 and 8.5 degC at 0.0135 (deg/s)/degC); landscapes of 21, 72 and 290
deg/h sd; slips of K 2.0e-6, 6e-6 and 3e-5 rad/s/sqrt(s) at long times; switched kinetics of
0.0078, 0.057 and 0.14 deg/s sd (tc 2 s, 2 s and 20 s); VFC steps Q of 20 urad, 0.5 and 2 mrad
(1 count a window = 0.12, 2.9 and 11 deg/s); looms of 0.018, 0.069 and 0.34 deg/s rms;
deadbands of 0.0078 (edge), 0.029 and 0.11 deg/s.
"""
from heldout_detect import allan_taus, allan_z, band_excess, gm_avar
import numpy as np
from scipy import signal, special
from validate_diagnosis_heldout_n import dwell_states
from validate_diagnosis_heldout_p import BIAS, LSB, repeat_share

MECH = 0.6                                          # mechanical share of the white noise power
ENGINE_HZ, CYCLE_CV, MISFIRE = 29.5, 0.15, 0.04     # firing rate; cycle scatter; misfire share
DIE_S, SENSOR_S = 200.0, 900.0                      # s: die warm-up; thermistor's further lag
TREE_TAUS = 0.02 * 10.0 ** (np.arange(19) / 3)      # s: the landscape levels' times
SLIP_RATE, RECOVER, RECOVER_S = 0.5, 0.7, 20.0      # slips a second; share recovered; its time
SLOW, MODE_S = 8.0, 30.0                            # low-power / high-power time; mean spell (s)
VFC_NU = 0.1237                                     # F0 dt less its whole cycles
WIRES, WIRE_HZ, WIRE_SPREAD, WIRE_Q = 24, 21.0, 0.04, 60.0


def split_white(x: np.ndarray, sig: float, rng, share: float = MECH) -> tuple:
    """Return (m, e): x split into independent Gaussian shares, m carrying ``share`` of it."""
    m = share * x + np.sqrt(share * (1 - share)) * sig * rng.standard_normal(x.size)
    return m, x - m


def sense_pole(tau: float, dt: float) -> float:
    """Return a = e^(-dt / tau) of the demodulated sense mode (0 for tau = 0)."""
    return float(np.exp(-dt / tau)) if tau > 0 else 0.0


def mode_matched(x: np.ndarray, tau: float, sig: float, dt: float, rng) -> np.ndarray:
    """Return h * m + e: the mechanical share through the one-pole, the electronic as is."""
    x = np.asarray(x, float)
    if tau <= 0:
        return x.copy()
    m, e = split_white(x, sig, rng)
    a = sense_pole(tau, dt)
    return signal.lfilter([1 - a], [1.0, -a], m, zi=[a * m[0]])[0] + e


def shelf_r1(tau: float, dt: float) -> float:
    """Lag-1 autocorrelation of ``mode_matched`` on white input."""
    a = sense_pole(tau, dt)
    u = (1 - a) / (1 + a)                          # sum h_j^2 of the one-pole
    return float(MECH * a * u / (MECH * u + 1 - MECH))


def shelf_gain2(f, tau: float, dt: float) -> np.ndarray:
    """Output PSD over white: MECH |H|^2 + 1 - MECH."""
    a = sense_pole(tau, dt)
    z1 = np.exp(-2j * np.pi * np.asarray(f, float) * dt)
    return MECH * np.abs((1 - a) / (1 - a * z1)) ** 2 + 1 - MECH


def cycle_amplitudes(count: int, amplitude: float, rng) -> np.ndarray:
    """Per-cycle rocking amplitudes A (1 + CYCLE_CV g), zero in a MISFIRE share of cycles."""
    a = amplitude * (1 + CYCLE_CV * rng.standard_normal(count))
    return np.where(rng.uniform(size=count) < MISFIRE, 0.0, a)


def engine(t, amplitudes: np.ndarray, phase: float = 0.0) -> np.ndarray:
    """Return a_k sin(2 pi u), u = ENGINE_HZ t + phase, k = floor(u) (cycle k's amplitude)."""
    u = ENGINE_HZ * np.asarray(t, float) + phase
    k = np.floor(u).astype(int)
    return amplitudes[k] * np.sin(2 * np.pi * (u - k))


def lag_bracket(t) -> np.ndarray:
    """Return T_die - T_sensor for a unit warm-up: (e^(-t / SENSOR_S) - e^(-t / DIE_S)) k."""
    t = np.asarray(t, float)
    return SENSOR_S / (SENSOR_S - DIE_S) * (np.exp(-t / SENSOR_S) - np.exp(-t / DIE_S))


def lag_peak_time() -> float:
    """Return the bracket's peak time ln(SENSOR_S / DIE_S) DIE_S SENSOR_S / (SENSOR_S - DIE_S)."""
    return float(np.log(SENSOR_S / DIE_S) * DIE_S * SENSOR_S / (SENSOR_S - DIE_S))


def lag_residual(t, amplitude: float) -> np.ndarray:
    """Return A lag_bracket(t) / lag_bracket(peak): peak A, t from power-on."""
    return amplitude * lag_bracket(t) / lag_bracket(lag_peak_time())


def tree_rates() -> np.ndarray:
    """Return the crossing rates w_l with 2 w_l + sum_(m > l) w_m = 1 / TREE_TAUS[l]."""
    lam = 1.0 / TREE_TAUS
    w = np.zeros(lam.size)
    above = 0.0
    for lv in range(lam.size - 1, -1, -1):
        w[lv] = (lam[lv] - above) / 2
        above += w[lv]
    return w


def tree_bits(n: int, dt: float, rng) -> np.ndarray:
    """Return the levels' bits (+-1, shape (levels, n)) of the ultrametric walk, stationary."""
    w = tree_rates()
    big_t = n * dt
    levels = w.size
    times = [np.sort(rng.uniform(0, big_t, rng.poisson(r * big_t))) for r in w]
    grid = np.arange(n) * dt
    bits = np.empty((levels, n), dtype=np.int8)
    for lv in range(levels):
        resets = np.concatenate(times[lv + 1:]) if lv + 1 < levels else np.zeros(0)
        at = np.r_[times[lv], resets]
        is_reset = np.r_[np.zeros(times[lv].size, bool), np.ones(resets.size, bool)]
        order = np.argsort(at, kind='stable')
        at, is_reset = at[order], is_reset[order]
        start = np.where(rng.uniform() < 0.5, -1, 1)
        fresh = np.where(rng.uniform(size=at.size) < 0.5, -1, 1)
        idx = np.arange(at.size)
        last = np.maximum.accumulate(np.where(is_reset, idx, -1))
        flips = np.cumsum(~is_reset)
        since = flips - np.where(last >= 0, flips[np.maximum(last, 0)], 0)
        base = np.where(last >= 0, fresh[np.maximum(last, 0)], start)
        value = base * (1 - 2 * (since % 2))
        j = np.searchsorted(at, grid, side='right') - 1
        value = np.r_[value, start]                  # index -1: before the first event
        bits[lv] = value[j]
    return bits


def landscape(n: int, b: float, dt: float, rng) -> np.ndarray:
    """Return b sum_l s_l / sqrt(levels) (sd b)."""
    bits = tree_bits(n, dt, rng)
    return b * bits.sum(axis=0, dtype=float) / np.sqrt(bits.shape[0])


def landscape_cov(u, b: float) -> np.ndarray:
    """Autocovariance b^2 mean_l e^(-|u| / TREE_TAUS[l])."""
    u = np.abs(np.asarray(u, float))[..., None]
    return b * b * np.mean(np.exp(-u / TREE_TAUS), axis=-1)


def slip_size(k: float) -> float:
    """Return the slips' sd S: SLIP_RATE S^2 (1 - RECOVER)^2 = K^2."""
    return k / ((1 - RECOVER) * np.sqrt(SLIP_RATE))


def slips(n: int, k: float, dt: float, rng) -> np.ndarray:
    """Return (1 - RECOVER) W + RECOVER G: the walk of the slips and their recovering part."""
    burn = int(10 * RECOVER_S / dt)
    count = rng.poisson(SLIP_RATE * dt, n + burn)
    steps = np.sqrt(count) * slip_size(k) * rng.standard_normal(n + burn)
    a = np.exp(-dt / RECOVER_S)
    walk = np.cumsum(steps)
    shot = signal.lfilter([1.0], [1.0, -a], steps)
    return ((1 - RECOVER) * (walk - walk[burn - 1]) + RECOVER * shot)[burn:]


def slip_gm_sd(k: float) -> float:
    """Return the sd of the first-order term of the slips' PSD (time RECOVER_S)."""
    return float(k * np.sqrt(RECOVER * (2 - RECOVER) * RECOVER_S / 2) / (1 - RECOVER))


def slip_avar(tau, k: float) -> np.ndarray:
    """Allan variance K^2 tau / 3 + gm_avar(tau, ``slip_gm_sd``, RECOVER_S)."""
    tau = np.atleast_1d(np.asarray(tau, float))
    return k * k * tau / 3 + gm_avar(tau, slip_gm_sd(k), RECOVER_S)


def kinetics_terms(tc: float) -> tuple:
    """Return (weights, times) with pi^T exp((G - R) u) 1 = sum w_i e^(-u / time_i)."""
    g = np.array([[-1.0, 1.0], [1.0, -1.0]]) / MODE_S
    r = np.diag([1.0 / tc, 1.0 / (SLOW * tc)])
    mu, v = np.linalg.eigh(g - r)
    weights = 0.5 * (v.sum(axis=0)) ** 2
    return weights, -1.0 / mu


def kinetics_cov(u, sd: float, tc: float) -> np.ndarray:
    """Autocovariance sd^2 sum_i w_i e^(-|u| / time_i)."""
    w, times = kinetics_terms(tc)
    u = np.abs(np.asarray(u, float))[..., None]
    return sd * sd * np.sum(w * np.exp(-u / times), axis=-1)


def kinetics(n: int, sd: float, tc: float, dt: float, rng) -> tuple:
    """Return (X, mode): the switched first-order process (variance sd^2) and the mode (1 slow)."""
    mode = dwell_states(n, dt, [MODE_S, MODE_S], int(rng.uniform() < 0.5), rng)
    w = rng.standard_normal(n)
    out = np.empty(n)
    prev = sd * rng.standard_normal()
    edges = np.r_[0, np.flatnonzero(np.diff(mode)) + 1, n]
    for i0, i1 in zip(edges[:-1], edges[1:]):
        c = np.exp(-dt / (tc * (SLOW if mode[i0] else 1.0)))
        drive = sd * np.sqrt(1 - c * c) * w[i0:i1]
        out[i0:i1] = signal.lfilter([1.0], [1.0, -c], drive, zi=[c * prev])[0]
        prev = out[i1 - 1]
    return out, mode


def vfc_counts(x: np.ndarray, q: float, dt: float, phase: float) -> np.ndarray:
    """Return the window counts less their whole zero-rate part: floor(psi_k) - floor(psi_k-1)."""
    k = np.arange(1, x.size + 1)
    psi = np.r_[phase, VFC_NU * k + np.cumsum(x) * dt / q + phase]
    return np.diff(np.floor(psi))


def vfc(x: np.ndarray, q: float, dt: float, phase: float) -> np.ndarray:
    """Return the counted rate (count - F0 dt) Q / dt."""
    return (vfc_counts(x, q, dt, phase) - VFC_NU) * q / dt


def vfc_excess(q: float, dt: float, n_arw: float, harmonics: int = 400) -> tuple:
    """Return the relative Allan excess of the counted VFC at dt and at 10 dt."""
    nu = VFC_NU + BIAS * dt / q
    h = np.arange(1, harmonics + 1)

    def c(lag):
        damp = np.exp(-2 * np.pi ** 2 * h * h * lag * dt * n_arw ** 2 / q ** 2)
        return 2 * np.sum((q / (2 * np.pi * h)) ** 2 * np.cos(2 * np.pi * h * nu * lag) * damp)
    c0 = q * q / 12
    return tuple((3 * c0 - 4 * c(lag) + c(2 * lag)) / (lag * dt * n_arw ** 2) for lag in (1, 10))


def wire_freqs() -> np.ndarray:
    """Return the wires' mode frequencies WIRE_HZ (1 + WIRE_SPREAD g_i), g_i normal quantiles."""
    g = special.ndtri((np.arange(WIRES) + 0.5) / WIRES)
    return WIRE_HZ * (1 + WIRE_SPREAD * g)


def wire_coeffs(freq: float, dt: float):
    """Return (a, rate variance per unit drive) of one wire's mode (rate = angle diff / dt)."""
    th = 2 * np.pi * freq * dt * np.sqrt(1 - 1 / (4 * WIRE_Q ** 2))
    r = np.exp(-np.pi * freq * dt / WIRE_Q)
    a = np.array([1.0, -2 * r * np.cos(th), r * r])
    var = (1 + r * r) / ((1 - r * r) * (1 - 2 * r * r * np.cos(2 * th) + r ** 4))
    rho1 = 2 * r * np.cos(th) / (1 + r * r)
    return a, 2 * var * (1 - rho1) / dt ** 2


def loom(n: int, sigma: float, dt: float, rng) -> np.ndarray:
    """Return the sum of the WIRES modes' rates, each of variance sigma^2 / WIRES."""
    out = np.zeros(n)
    for freq in wire_freqs():
        a, var = wire_coeffs(freq, dt)
        burn = int(20 * WIRE_Q / (np.pi * freq * dt)) + 1
        g = sigma / np.sqrt(WIRES * var)
        ang = signal.lfilter([g], a, rng.standard_normal(n + 1 + burn))[burn:]
        out += np.diff(ang) / dt
    return out


def loom_psd(f, sigma: float, dt: float) -> np.ndarray:
    """One-sided mean PSD of ``loom``: the sum of the modes' rate PSDs."""
    z1 = np.exp(-2j * np.pi * np.asarray(f, float) * dt)
    out = np.zeros(z1.shape)
    for freq in wire_freqs():
        a, var = wire_coeffs(freq, dt)
        g2 = sigma ** 2 / (WIRES * var)
        out += 2 * dt * g2 * np.abs(1 - z1) ** 2 / dt ** 2 / np.abs(
            a[0] + a[1] * z1 + a[2] * z1 * z1) ** 2
    return out


def deadband(x: np.ndarray, delta: float) -> np.ndarray:
    """Return y_k = x_k if |x_k - y_(k-1)| >= delta, else y_(k-1) (y_0 = x_0)."""
    x = np.asarray(x, float)
    if delta <= 0:
        return x.copy()
    vals = x.tolist()
    out = [vals[0]]
    last = vals[0]
    for v in vals[1:]:
        if abs(v - last) >= delta:
            last = v
        out.append(last)
    return np.array(out)


def deadband_law(delta: float, sig: float, points: int = 20001, sweeps: int = 400):
    """Return (grid, density): the published value's stationary law, white x ~ N(BIAS, sig^2)."""
    v = np.linspace(BIAS - 9 * sig, BIAS + 9 * sig, points)
    dv = v[1] - v[0]
    phi = np.exp(-((v - BIAS) / sig) ** 2 / 2) / (sig * np.sqrt(2 * np.pi))
    hold = special.ndtr((v + delta - BIAS) / sig) - special.ndtr((v - delta - BIAS) / sig)
    pi = phi.copy()
    for _ in range(sweeps):
        cdf = np.cumsum(pi) * dv
        far = 1 - np.interp(v + delta, v, cdf, right=cdf[-1]) + np.interp(v - delta, v, cdf,
                                                                          left=0.0)
        new = pi * hold + phi * far
        new /= new.sum() * dv
        if np.max(np.abs(new - pi)) < 1e-12 * np.max(pi):
            pi = new
            break
        pi = new
    return v, pi


def deadband_share(delta: float, sig: float) -> float:
    """Return the share of zero first differences of the rounded deadband output (white x)."""
    v, pi = deadband_law(delta, sig)
    dv = v[1] - v[0]
    ndtr = special.ndtr
    hold = ndtr((v + delta - BIAS) / sig) - ndtr((v - delta - BIAS) / sig)
    c = np.round(v / LSB) * LSB
    lo, hi = c - LSB / 2, c + LSB / 2
    cell = ndtr((hi - BIAS) / sig) - ndtr((lo - BIAS) / sig)
    inner = np.maximum(ndtr((np.minimum(hi, v + delta) - BIAS) / sig)
                       - ndtr((np.maximum(lo, v - delta) - BIAS) / sig), 0.0)
    return float(np.sum(pi * (hold + cell - inner)) * dv)


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def sense(x, rng, tau):
        return mode_matched(x, tau, sig, dt, rng)

    def generator(x, rng, amplitude):
        t = np.arange(x.size) * dt
        phase = rng.uniform()
        count = int(np.floor(ENGINE_HZ * t[-1] + phase)) + 1
        return x + engine(t, cycle_amplitudes(count, amplitude, rng), phase)

    def compensation(x, rng, amplitude):
        return x + lag_residual(np.arange(x.size) * dt + rng.uniform(0, 60), amplitude)

    def glass(x, rng, b):
        return x + landscape(x.size, b, dt, rng)

    def anelastic(x, rng, k):
        return x + slips(x.size, k, dt, rng)

    def switched(x, rng, sd, tc):
        return x + kinetics(x.size, sd, tc, dt, rng)[0]

    def counted(x, rng, q):
        return vfc(x, q, dt, rng.uniform())

    def wires(x, rng, sigma):
        return x + loom(x.size, sigma, dt, rng)

    def gateway(x, rng, delta):
        return deadband(x, delta)

    return {
        'internal_lowpass': (sense, [{'tau': 0.005}, {'tau': 0.015}, {'tau': 2.07e-3}]),
        'vibration': (generator, [{'amplitude': 5e-4}, {'amplitude': 3e-3},
                                  {'amplitude': 4.9e-5}]),
        'temperature_drift': (compensation, [{'amplitude': 6e-4}, {'amplitude': 2e-3},
                                             {'amplitude': 1.14e-4}]),
        'bias_instability': (glass, [{'b': 3.5e-4}, {'b': 1.4e-3}, {'b': 1.03e-4}]),
        'rate_random_walk': (anelastic, [{'k': 6e-6}, {'k': 3e-5}, {'k': 2.0e-6}]),
        'gauss_markov': (switched, [{'sd': 1e-3, 'tc': 2.0}, {'sd': 2.5e-3, 'tc': 20.0},
                                    {'sd': 1.37e-4, 'tc': 2.0}]),
        'quantization': (counted, [{'q': 5e-4}, {'q': 2e-3}, {'q': 2.03e-5}]),
        'resonance': (wires, [{'sigma': 1.2e-3}, {'sigma': 6e-3}, {'sigma': 3.08e-4}]),
        'stale_samples': (gateway, [{'delta': 5e-4}, {'delta': 2e-3}, {'delta': 1.37e-4}]),
    }


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn, p = n * dt, n_arw ** 2, params
    t = np.arange(n) * dt
    if name == 'internal_lowpass':
        return float(shelf_r1(p['tau'], dt) * np.sqrt(n))
    if name in ('vibration', 'temperature_drift'):
        if name == 'vibration':
            s = p['amplitude'] * (1 - MISFIRE) * np.sin(2 * np.pi * np.mod(ENGINE_HZ * t, 1.0))
        else:
            s = lag_residual(t + 30.0, p['amplitude'])
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        rel = vfc_excess(p['q'], dt, n_arw)
        return float(abs(rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n)))
    if name == 'resonance':
        ex, width = band_excess(lambda f: loom_psd(f, p['sigma'], dt), dt, sig)
        return float(ex * np.sqrt(big_t * width))
    if name == 'stale_samples':
        q0 = repeat_share(sig)
        s = deadband_share(p['delta'], sig)
        return float((s - q0) * np.sqrt(n / (q0 * (1 - q0))))
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        sd = p['b'] / np.sqrt(TREE_TAUS.size)
        excess = sum(gm_avar(tau, sd, tt) for tt in TREE_TAUS)
    elif name == 'rate_random_walk':
        excess = slip_avar(tau, p['k'])
    else:
        w, times = kinetics_terms(p['tc'])
        excess = sum(gm_avar(tau, p['sd'] * np.sqrt(wi), ti) for wi, ti in zip(w, times))
    return allan_z(excess, tau, nn, big_t)
