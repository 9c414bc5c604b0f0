"""
The swing kind of the diagnosis: observables, baseline fit, simulated twins, effect spaces.

Baseline = the paper's swing model fitted to the record: the 5-state Kalman estimates
(``swing_kf.estimate_swing``: scale-factor error, bias, drift, the gyro's white noise N and the
encoder's angle noise) put into the bench simulator (``bench_sim.simulate_swing``) with the
record's amplitude, period, rates and output step. Everything else is for the effects.

Observables (``swing_observables``), identical on the record and on every twin: the gyro angle
(trapezoid integral of the rate at its stamps) minus the least-squares fit of
``(1 + Δρ) · encoder angle + offset + bias · t + drift · t² / 2`` (encoder interpolated at the
gyro stamps), decomposed on the swing phase θ = ωt + ψ of the encoder's own sine fit:

- ``in_phase`` / ``quadrature``: the residual's sin θ / cos θ components (rad). A stamp delay
  d leaves -A ω d cos θ; a g-sensitivity g_y leaves -g_y g A / ω cos θ - the same shape on one
  period and amplitude, hence the ambiguity the engine reports for that pair;
- ``harmonic_2f`` / ``harmonic_3f``: sin and cos of 2θ and 3θ (scale-factor asymmetry and the
  quadratic term give 2f, the cubic term 3f);
- ``residual_psd``: log10 Welch PSD of the residual's rate (its difference over dt) in log bins
  from 1 Hz to 1/8 of the sample rate (stamp jitter, encoder interpolation error, smoothing).

Whole-record components rather than per-window ones: a constant effect's z grows with the
record length instead of being spread over windows; the twins' repeats give the scatter.
"""
from dataclasses import dataclass, replace
from typing import List, Optional, Sequence

from gyro_char import bench_sim
from gyro_char.diag_fit import EffectSpace, Param
from gyro_char.diag_static import output_step, twin_effects
from gyro_char.diagnose import Problem
from gyro_char.recordings import ENCODER_CHANNEL, InputError, Recording
from gyro_char.sim_config import BenchConfig
from gyro_char.swing_align import integrate
from gyro_char.swing_kf import estimate_swing
import numpy as np
from scipy import signal

SWING_EFFECTS = ('time_delay', 'g_sensitivity', 'scale_factor_nonlinearity',
                 'scale_factor_asymmetry', 'encoder_cyclic_error', 'timestamp_jitter')
PRESET = 'adis16405'  # structure only: the fitted numbers override what matters
PSD_BINS = 10
G0 = 9.80665


@dataclass
class SwingBaseline:
    """The paper's swing model fitted to one record (SI)."""

    period_s: float
    amplitude: float
    scale_factor_error: float
    bias: float
    drift: float
    N: float
    encoder_sigma: float
    lsb: float
    dt: float
    encoder_dt: float
    duration: float
    axis: str

    def to_json(self) -> dict:
        units = {'period_s': 's', 'amplitude': 'rad', 'scale_factor_error': '1',
                 'bias': 'rad/s', 'drift': 'rad/s^2', 'N': 'rad/s^0.5', 'encoder_sigma': 'rad',
                 'lsb': 'rad/s', 'dt': 's', 'encoder_dt': 's', 'duration': 's'}
        return {k: {'value': float(getattr(self, k)), 'unit': u} for k, u in units.items()}


def _solve(cols: List[np.ndarray], y: np.ndarray) -> np.ndarray:
    # Normal equations with einsum (a threaded BLAS lstsq is slow on a busy 2-core machine);
    # columns are scaled to unit rms so the 7x7 system stays well conditioned.
    a = np.array(cols)
    s = np.sqrt(np.einsum('ij,ij->i', a, a) / y.size)
    s[s == 0] = 1.0
    a = a / s[:, None]
    coef = np.linalg.solve(np.einsum('ik,jk->ij', a, a), np.einsum('ik,k->i', a, y))
    return coef / s


def layout(n_psd: int, dt: float, period_s: float) -> dict:
    """Per block, the (lo, hi) range (Hz) of every element."""
    f0 = 1.0 / period_s
    # Up to 1/8 of the sample rate: above it the residual is shaped by where the gyro stamps
    # fall between encoder samples (linear interpolation), which says nothing about the gyro.
    edges = np.geomspace(1.0, 0.125 / dt, PSD_BINS + 1)
    return {'in_phase': np.array([[f0, f0]]), 'quadrature': np.array([[f0, f0]]),
            'harmonic_2f': np.array([[2 * f0, 2 * f0]] * 2),
            'harmonic_3f': np.array([[3 * f0, 3 * f0]] * 2),
            'residual_psd': np.c_[edges[:-1], edges[1:]]}


UNITS = {'in_phase': 'Hz', 'quadrature': 'Hz', 'harmonic_2f': 'Hz', 'harmonic_3f': 'Hz',
         'residual_psd': 'Hz'}


def swing_observables(t_g: np.ndarray, rate: np.ndarray, t_e: np.ndarray, enc: np.ndarray,
                      period_s: float, ranges: dict) -> dict:
    """All swing blocks of one record (gyro rate rad/s at ``t_g``, encoder rad at ``t_e``)."""
    lo, hi = max(t_g[0], t_e[0]), min(t_g[-1], t_e[-1])
    m = (t_g >= lo) & (t_g <= hi)
    tau = t_g[m] - lo
    ang = integrate(tau, rate[m])
    e = np.interp(tau, t_e - lo, enc)
    w = 2.0 * np.pi / period_s
    s1, c1 = np.sin(w * tau), np.cos(w * tau)
    ts = tau / max(tau[-1], 1e-9)
    one = np.ones_like(tau)
    ce = _solve([s1, c1, one, ts, ts * ts], e)
    psi = float(np.arctan2(ce[1], ce[0]))
    line = [one, ts, ts * ts]
    k = _solve([e] + line, ang)
    r = ang - k[0] * e - (k[1] + k[2] * ts + k[3] * ts * ts)
    th = w * tau + psi
    cols = [np.sin(th), np.cos(th), np.sin(2 * th), np.cos(2 * th), np.sin(3 * th),
            np.cos(3 * th)]
    h = _solve(cols + line, r)
    dt = float(np.median(np.diff(tau)))
    f, p = signal.welch(np.diff(r) / dt, fs=1.0 / dt, nperseg=min(2048, r.size // 8))
    psd = np.array([np.mean(p[(f >= a) & (f < b)]) if np.any((f >= a) & (f < b))
                    else np.interp(0.5 * (a + b), f, p) for a, b in ranges['residual_psd']])
    return {'in_phase': h[0:1], 'quadrature': h[1:2], 'harmonic_2f': h[2:4],
            'harmonic_3f': h[4:6], 'residual_psd': np.log10(np.maximum(psd, 1e-300))}


def fit_baseline(imu: Recording, encoder: Recording, period_s: float,
                 axis: Optional[str] = None) -> SwingBaseline:
    run = estimate_swing(imu, encoder, period_s, axis)
    al = run.aligned
    # Mean sample intervals, not medians: a twin whose encoder and gyro rates differ by a
    # jitter-sized amount drifts through the interpolation phase and reshapes the residual PSD.
    dt = float((al.tau_gyro[-1] - al.tau_gyro[0]) / (al.tau_gyro.size - 1))
    lsb = output_step(al.rate_gyro)
    est = run.estimates
    # The filter's N covers the output rounding too (lsb^2 dt / 12); the twin adds it back.
    n2 = est.noise_gyro_arw ** 2 - lsb ** 2 * dt / 12.0
    return SwingBaseline(
        period_s=float(period_s), amplitude=float(est.amplitude_encoder.value),
        scale_factor_error=float(est.scale_factor_error.value), bias=float(est.bias.value),
        drift=float(est.bias_drift.value),
        N=float(np.sqrt(max(n2, 0.01 * est.noise_gyro_arw ** 2))),
        encoder_sigma=float(est.noise_encoder_rad), lsb=lsb, dt=dt,
        encoder_dt=float((al.tau_encoder[-1] - al.tau_encoder[0]) / (al.tau_encoder.size - 1)),
        duration=float(min(al.tau_gyro[-1], al.tau_encoder[-1])) + dt,
        axis=al.axis.replace('gyro_', ''))


def twin_config(base: SwingBaseline) -> BenchConfig:
    """Return the bench simulator's config for a twin: the paper's swing model only."""
    a = base.axis
    ch = f'gyro_{a}'
    # Stand: the record's amplitude and period; encoder: its rate and white noise (the
    # preset's level/word steps kept: a record does not reveal them below its noise).
    cfg = BenchConfig.from_preset(PRESET, {
        'stand': {'amplitude': base.amplitude, 'period_s': base.period_s},
        'encoder': {'rate_hz': 1.0 / base.encoder_dt},
        'gyro': {'rate_hz': 1.0 / base.dt, 'axis': a, 'output_step': base.lsb,
                 'quantizer': 'round', 'misalignment': 0.0,
                 'scale_factor_error': {a: base.scale_factor_error},
                 'bias': {a: base.bias}, 'bias_drift': {a: base.drift}},
        'noise': {ch: {'N': base.N, 'B': 0.0, 'K': 0.0, 'Q': 0.0, 'R': 0.0}},
    })
    cfg.encoder.adc_noise = encoder_white_sigma(base, cfg)
    return cfg


def simulate_twin(base: SwingBaseline, effects: Sequence, seed: int):
    """IMU and encoder recordings of a twin: the baseline plus ``effects``."""
    run = bench_sim.simulate_swing(twin_config(base), duration=base.duration,
                                   seed=int(seed), effects=twin_effects(effects),
                                   channels=(f'gyro_{base.axis}',))
    return run.imu, run.encoder


def _obs(imu: Recording, encoder: Recording, base: SwingBaseline, ranges: dict) -> dict:
    return swing_observables(imu.t, imu.channels[f'gyro_{base.axis}'], encoder.t,
                             encoder.channels[ENCODER_CHANNEL], base.period_s, ranges)


def _white(o: dict) -> float:
    return float(np.mean(10 ** o['residual_psd'][: PSD_BINS // 2]))


def encoder_white_sigma(base: SwingBaseline, cfg: BenchConfig) -> float:
    """
    Return the encoder ADC noise that gives the filter's encoder noise estimate in a twin.

    The estimate lumps the stand's white amplitude noise (seen as A_noise^2 / 2 on average
    over the swing) and both quantizations with the ADC noise; the twin adds those again.
    """
    st, en = cfg.stand, cfg.encoder
    other = st.amplitude_noise ** 2 / 2 + en.level_step ** 2 / 12 + en.word_step ** 2 / 12
    return float(np.sqrt(max(base.encoder_sigma ** 2 - other, 0.0)))


def calibrate_n(base: SwingBaseline, real: dict, ranges: dict,
                seeds: Sequence[int] = (901, 902, 903)) -> SwingBaseline:
    """
    Rescale N so that the twins' residual PSD in the gyro band matches the record's.

    The gyro filter's N is estimated from the angle residuals, which also carry the stand's
    and the encoder's noise; the white band of the residual rate (1 Hz to ~10 % of the sample
    rate, where the gyro's white noise dominates) pins it to about 1 %.
    """
    sims = [_white(_obs(*simulate_twin(base, [], s), base, ranges)) for s in seeds]
    return replace(base, N=base.N * float(np.sqrt(_white(real) / np.mean(sims))))


def swing_spaces(base: SwingBaseline) -> List[EffectSpace]:
    """Search spaces scaled to the record (sign of signed parameters set by ``_signs``)."""
    w = 2.0 * np.pi / base.period_s
    rate = base.amplitude * w                       # peak swing rate, rad/s
    sig = base.N / np.sqrt(base.duration)           # rate noise averaged over the record
    # Quadrature noise of the angle residual at the swing frequency (random-walk angle of PSD
    # N^2 / w^2 projected over the record): a delay and a g-sensitivity are searched over
    # the same span of quadrature amplitudes, so neither is favoured by its grid.
    q = base.N / w * np.sqrt(2.0 / base.duration)
    return [
        EffectSpace('time_delay', [Param('delay_s', 0.5 * q / rate, 200.0 * q / rate)]),
        EffectSpace('g_sensitivity', [Param('gy', 0.5 * q * w / (G0 * base.amplitude),
                                            200.0 * q * w / (G0 * base.amplitude))]),
        EffectSpace('scale_factor_nonlinearity', [
            Param('k2', 0.03 * sig / rate ** 2, 300.0 * sig / rate ** 2),
            Param('k3', 0.03 * sig / rate ** 3, 300.0 * sig / rate ** 3)]),
        EffectSpace('scale_factor_asymmetry', [Param('a', 0.03 * sig / rate,
                                                     300.0 * sig / rate)]),
        EffectSpace('encoder_cyclic_error', [Param('a1', 0.1 * base.encoder_sigma + 1e-9,
                                                   30.0 * base.encoder_sigma + 1e-7)],
                    fixed={'a2': 0.0}),
        # Both streams: an IMU stamp error alone leaves no first-order trace here (the gyro
        # angle and the encoder read at the same wrong stamp move together); an encoder
        # stamp error shows as residual angle noise rate x error.
        EffectSpace('timestamp_jitter', [Param('sigma_s', 0.01 * base.encoder_dt,
                                               0.4 * base.encoder_dt)],
                    fixed={'stream': 2.0}),
    ]


SIGNED = {'time_delay': ['delay_s'], 'g_sensitivity': ['gy'],
          'scale_factor_nonlinearity': ['k2', 'k3'], 'scale_factor_asymmetry': ['a']}


def _signs(spaces: List[EffectSpace], real: dict, simulate) -> List[EffectSpace]:
    """
    Give each signed parameter the sign that moves the twins towards the record.

    A probe twin with the parameter at its range's geometric middle, against a baseline twin
    of the same seed (common random numbers: the difference is the effect alone), gives the
    effect's response on the harmonic blocks; its projection on the record's departure from
    the baseline twin gives the sign.
    """
    blocks = ('in_phase', 'quadrature', 'harmonic_2f', 'harmonic_3f')
    base = simulate([], 4242)
    dev = np.concatenate([real[b] - base[b] for b in blocks])
    out = []
    for sp in spaces:
        params = []
        for p in sp.params:
            if p.name in SIGNED.get(sp.name, []):
                probe = simulate([(sp.name, {**sp.fixed, p.name: float(np.sqrt(p.lo * p.hi))})],
                                 4242)
                resp = np.concatenate([probe[b] - base[b] for b in blocks])
                sign = 1.0 if float(np.einsum('i,i->', resp, dev)) >= 0 else -1.0
                p = Param(p.name, p.lo, p.hi, p.log, p.integer, sign)
            params.append(p)
        out.append(EffectSpace(sp.name, params, dict(sp.fixed), dict(sp.start)))
    return out


def swing_problem(imu: Recording, encoder: Recording, period_s: float, *,
                  axis: Optional[str] = None, max_samples: Optional[int] = None,
                  names: Sequence[str] = SWING_EFFECTS,
                  base: Optional[SwingBaseline] = None) -> Problem:
    """
    Build the diagnosis problem for one swing record (IMU + encoder).

    Records longer than ``max_samples`` gyro samples are cut to that span from the start of
    the overlap (twins are simulated at the same length).
    """
    if encoder is None or ENCODER_CHANNEL not in encoder.channels:
        raise InputError('the swing diagnosis needs the encoder angle of the stand')
    if max_samples and len(imu) > max_samples:
        t_end = imu.t[0] + (max_samples - 1) * float(np.median(np.diff(imu.t)))
        imu = Recording(imu.t[imu.t <= t_end],
                        {c: v[imu.t <= t_end] for c, v in imu.channels.items()},
                        imu.source, list(imu.notes))
        keep = encoder.t <= t_end
        encoder = Recording(encoder.t[keep], {ENCODER_CHANNEL: encoder.channels[
            ENCODER_CHANNEL][keep]}, encoder.source, list(encoder.notes))
    fitted = base is None
    if fitted:
        base = fit_baseline(imu, encoder, period_s, axis)
    ch = f'gyro_{base.axis}'
    if ch not in imu.channels:
        raise InputError(f'no {ch} channel in the IMU input')
    n_min = 8 * 256
    if len(imu) < n_min:
        raise InputError(f'swing record too short for the diagnosis: {len(imu)} samples '
                         f'(need >= {n_min})')
    ranges = layout(len(imu), base.dt, base.period_s)
    real = _obs(imu, encoder, base, ranges)
    if fitted:
        base = calibrate_n(base, real, ranges)

    def sim(effects: list, seed: int) -> dict:
        return _obs(*simulate_twin(base, effects, seed), base, ranges)

    spaces = [s for s in swing_spaces(base) if s.name in names]
    spaces = _signs(spaces, real, sim)
    return Problem(kind='swing', reals=[real], simulate=lambda i, fx, s: sim(fx, s),
                   spaces=spaces, ranges=[ranges], units=dict(UNITS),
                   baseline=base.to_json(), context=base)
