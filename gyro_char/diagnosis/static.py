"""
The static kind of the diagnosis: baseline fit, simulated twins, the problem to search.

Baseline = the paper's static gyro model (docs/method.md, docs/design.md): white rate noise N,
constant bias, linear bias drift, output quantization dH. Its parameters come from the real
record: N from the Allan deviation at τ = 1 s (the paper's ARW read-out, less the quantization
noise the twin adds back), bias and drift from a least-squares line, dH from the record's own
output step. Everything else the record shows (flicker, random walks, internal smoothing, tones,
warm-up) is for the candidate effects to explain.

A twin of a record of ``n`` samples at ``dt`` comes from the bench simulator
(``simulator.simulate_static``) configured with the fitted baseline, with the catalogue effects
(``gyro_char.sim.effects``) added in order, restricted to the record's channel.
"""
from dataclasses import asdict, dataclass, replace
from typing import Optional, Sequence

from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis.engine import Problem
from gyro_char.diagnosis.fit import EffectSpace, Param
from gyro_char.diagnosis.gate import hold_model
from gyro_char.diagnosis.starts import frame_start
from gyro_char.diagnosis.static_bands import with_gap_band, with_notch_band
from gyro_char.diagnosis.static_spaces import STATIC_EFFECTS, static_spaces
from gyro_char.diagnosis.twins import channel_row, output_step, twin_effects
from gyro_char.errors import InputError
from gyro_char.sim import simulator
from gyro_char.sim.config import AXES, BenchConfig
from gyro_char.sim.effects import EFFECTS
import numpy as np

# Effects a static record can reveal. (scale-factor, cross-axis, g-sensitivity, time delay and
# encoder effects need motion or an encoder; a static record cannot tell them from bias.)
TAU_REF = 1.0  # s, where N is read off the Allan curve
NUISANCE = 'baseline_white_noise'  # pseudo-effect: scale on the baseline N, tuned per model
PRESET = 'adis16405'  # only its structure is used: every number that matters is overridden


@dataclass
class StaticBaseline:
    """The paper's static model of one channel, fitted to one record (SI)."""

    N: float        # rad/sqrt(s)
    bias: float     # rad/s
    drift: float    # rad/s^2
    lsb: float      # rad/s, 0 = unquantized
    dt: float       # s

    def to_json(self) -> dict:
        units = {'N': 'rad/s^0.5', 'bias': 'rad/s', 'drift': 'rad/s^2', 'lsb': 'rad/s',
                 'dt': 's'}
        return {k: {'value': float(v), 'unit': units[k]} for k, v in asdict(self).items()}


def fit_baseline(x: np.ndarray, dt: float) -> StaticBaseline:
    x = np.asarray(x, dtype=np.float64)
    t = np.arange(x.size) * dt
    drift, bias = np.polyfit(t, x, 1)
    lsb = output_step(x)
    if lsb > 0.0 and np.var(x - drift * t) < lsb ** 2 / 12.0:
        # Rounding adds lsb^2 / 12 to a noisy rate's variance; a record that varies less
        # than that in all (isolated one-step spikes: an angle quantized, then differenced)
        # is not a rounded rate, and its grid is left to the quantization candidate.
        lsb = 0.0
    m = max(int(round(TAU_REF / dt)), 1)
    if 8 * m > x.size:
        m = max(x.size // 8, 1)
    tau = m * dt
    adev = obs.overlapping_adev(x - drift * t, np.array([m]))[0]
    # White rate noise of PSD N^2 gives AVAR N^2/tau; rounding to lsb adds lsb^2/12 per sample,
    # i.e. AVAR lsb^2 dt / (12 tau).
    n2 = adev ** 2 * tau - lsb ** 2 * dt / 12.0
    return StaticBaseline(N=float(np.sqrt(max(n2, 0.01 * adev ** 2 * tau))), bias=float(bias),
                          drift=float(drift), lsb=lsb, dt=float(dt))


def twin_config(base: StaticBaseline, channel: str, effects: Sequence = ()) -> BenchConfig:
    """
    Return the bench simulator's config for a twin: the paper's static model only.

    With ``internal_lowpass`` the chain runs at the internal rate and decimates; the white
    noise there is scaled so that the long-τ N at the output is still the baseline's N (so
    it is with ``stale_samples``, whose holds raise a white noise's long-τ level).
    """
    gain = 1.0
    for name, params in effects:
        if name == 'internal_lowpass':
            lp = EFFECTS[name](**params)
            gain *= lp.noise_gain(int(lp.decimation))
    for name, params in effects:
        if name == 'stale_samples':
            gain *= hold_model(params, base.N, base.dt, gain).gain()
    axis = AXES[channel_row(channel)]
    overrides = {
        'gyro': {'static_rate_hz': 1.0 / base.dt, 'output_step': base.lsb,
                 'quantizer': 'round', 'jitter_s': 0.0, 'bias': {axis: base.bias}},
        'noise': {channel: {'N': base.N / gain, 'B': 0.0, 'K': 0.0, 'Q': 0.0, 'R': 0.0}},
    }
    return BenchConfig.from_preset(PRESET, overrides)


def simulate_twin(base: StaticBaseline, n: int, effects: Sequence, seed: int,
                  channel: str = 'gyro_x') -> np.ndarray:
    """``n`` samples of ``channel`` from the bench simulator: baseline plus ``effects``."""
    run = simulator.simulate_static(twin_config(base, channel, effects),
                                    duration=n * base.dt, seed=int(seed),
                                    effects=twin_effects(effects, channel),
                                    channels=(channel,))
    x = run.imu.channels[channel]
    if x.size != n:
        raise RuntimeError(f'twin has {x.size} samples, expected {n}')
    # The static chain has no drift term (a static ramp is the IEEE R >= 0); the baseline's
    # drift is added here, where its sign is free. Observables remove the line anyway.
    return x + base.drift * (np.arange(n) * base.dt)


def white_level(x: np.ndarray, dt: float) -> float:
    """
    Return the median Welch PSD of the detrended record in the white band.

    The band is 1-5 % of the rate (``observables.white_band``), where a MEMS gyro's white
    rate noise is cleanest; the median ignores a tone in it. Where an angle read once a frame
    puts its comb of nulls in the PSD (``starts.frame_start``), the PSD's median at the
    nulls, where the read-out adds nothing.
    """
    psd = obs.welch_psd(obs.detrend(x), dt)
    framed = frame_start(psd, dt)
    if framed is not None:
        return framed[2]
    f, p = psd
    return float(np.median(p[obs.white_band(f, dt)]))


def calibrate_n(base: StaticBaseline, x: np.ndarray, channel: str,
                repeats: int = 4, seed: int = 99) -> StaticBaseline:
    """
    Rescale N so that the twins' white-noise level matches the record's.

    The closed-form correction for the output quantization in ``fit_baseline`` assumes a
    uniform, white rounding error, and the Allan deviation at 1 s is only known to a few per
    cent; the median PSD in the white band (``white_level``) of simulated twins, matched to the
    record's, pins N to about 1 % whatever the quantization.
    """
    real = white_level(x, base.dt)
    sims = [white_level(simulate_twin(base, x.size, [], seed + k, channel), base.dt)
            for k in range(repeats)]
    return replace(base, N=base.N * float(np.sqrt(real / np.mean(sims))))


def checked_records(records: Sequence, dt: float, max_samples: Optional[int] = None):
    """Return the records as float64 cut to ``max_samples``, and their observable layouts."""
    recs = [np.asarray(r, dtype=np.float64)[:max_samples] for r in records]
    for r in recs:
        if not np.all(np.isfinite(r)):
            raise InputError('static record contains non-finite samples')
    try:
        layouts = [obs.static_layout(r.size, dt) for r in recs]
    except ValueError as exc:
        raise InputError(str(exc)) from None
    return recs, layouts


def static_problem(records: Sequence[np.ndarray], dt: float, *, channel: str = 'gyro_x',
                   max_samples: Optional[int] = None,
                   names: Sequence[str] = STATIC_EFFECTS,
                   base: Optional[StaticBaseline] = None) -> Problem:
    """
    Build the diagnosis problem for static records of one channel at one sample time.

    The baseline is fitted on the first record unless given (a held-out check passes the
    baseline fitted elsewhere). Records longer than ``max_samples`` are cut to their first
    ``max_samples`` (twins are simulated at the same length, so real and simulated observables
    are computed identically).
    """
    recs, layouts = checked_records(records, dt, max_samples)
    if base is None:
        base = calibrate_n(fit_baseline(recs[0], dt), recs[0], channel)
    reals = [obs.static_observables(r, lay) for r, lay in zip(recs, layouts)]

    def simulate(i: int, effects: list, seed: int):
        b, fx = base, []
        for name, params in effects:
            if name == NUISANCE:
                b = replace(base, N=base.N * params['n_scale'])
            else:
                fx.append((name, params))
        x = simulate_twin(b, layouts[i].n, fx, seed + 7919 * i, channel)
        return obs.static_observables(x, layouts[i])

    spaces = static_spaces(base, recs[0], names)
    span = (layouts[0].ranges['psd'][0][0], layouts[0].ranges['psd'][-1][1])
    return Problem(kind='static', reals=reals, simulate=simulate, spaces=spaces,
                   ranges=[lay.ranges for lay in layouts], units=dict(obs.BLOCK_UNITS),
                   baseline=base.to_json(),
                   nuisance=EffectSpace(NUISANCE, [Param('n_scale', 0.95, 1.05)]),
                   context=base, unresolved=unresolved_pairs(len(recs)),
                   reseed=lambda where: with_notch_band(
                       with_gap_band(spaces, where, base.N / np.sqrt(dt), dt, span), where, dt,
                       span),
                   prune=True)


def unresolved_pairs(records: int) -> frozenset:
    """
    Return the look-alike pairs that ``records`` static records cannot tell apart.

    One record: a warm-up and a rate random walk (a slow bias change is one of either; a
    second record from switch-on shows whether it recurs).
    """
    if records > 1:
        return frozenset()
    return frozenset({frozenset({'temperature_drift', 'rate_random_walk'})})
