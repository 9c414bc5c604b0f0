"""
Where each static candidate is searched: parameter spaces scaled to one record.

Each effect's range runs from invisible to dominant on this record (white noise, sample time,
length), and data-driven starts come from the record itself (a detected tone, a change point,
an excess of exact repeats, the Allan excess a Gauss-Markov process would explain).
``gyro_char.diagnosis.static`` builds the problem from these.
"""
from dataclasses import replace
from typing import List, Sequence

from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis.band_kurtosis import steady_envelope
from gyro_char.diagnosis.cycle import cycle_start, CycleStart
from gyro_char.diagnosis.fit import EffectSpace, Param
from gyro_char.diagnosis.gate import gate_for_share, GateHolds
from gyro_char.diagnosis.holds import repeat_excess, repeat_runs, REPEAT_Z
from gyro_char.diagnosis.spectra import model_spectrum
from gyro_char.diagnosis.starts import frame_start, FRAMES, markov_start
from gyro_char.diagnosis.static_bands import forest_start, resonance_space, vibration_space
from gyro_char.sim.effects.base import CYCLE_HARMONICS
import numpy as np

STATIC_EFFECTS = ('internal_lowpass', 'bias_instability', 'rate_random_walk', 'gauss_markov',
                  'quantization', 'temperature_drift', 'vibration', 'resonance', 'stale_samples')
# PSD slope halfway between flicker's 1/f and a walk's 1/f^2: a power law on either side is
# fitted (and named) as the IEEE term its slope is nearer.
SLOPE_SPLIT = 1.5
# Runs of holds are searched where this share of the exact repeats come two or more in a row;
# their mean length up to RUN_MAX samples.
RUN_SHARE = 0.5
RUN_MAX = 2000.0
# Every hold form repeats its held share of samples exactly, so where the record's excess of
# exact repeats is measured, the held share is searched within this factor of it (or within
# REPEAT_Z standard errors, whichever is wider).
SHARE_SLACK = 1.5
# The output-rate low-pass's corner, in cycles per sample: from 2 % of the rate (below, it is
# a strong smoother the averages or a Gauss-Markov process describe) to just under Nyquist.
DLPF_LO, DLPF_HI = 0.02, 0.4995
# Interleaved converters searched (``memory_space``): 2 (double sampling) to this many, where
# a lag correlates more than every nearer one by MEMORY_Z standard errors.
INTERLEAVE_MAX = 4
MEMORY_Z = 3.0


# How far (in robust sds of the record's 1/64-length moving average) its largest excursion
# must stand out for a pulse to be searched. Noise alone reached 2.0-4.7 on 28 records of 2 h
# (white, flicker, random walks, Gauss-Markov); strong transients 16-20: a pulse searched on
# wander fitted flicker's edge level as well as flicker did (both then left unnamed).
PULSE_Z = 6.0
# Likewise for a transient that starts mid-record, on the moving average's change over one
# window (the mean after minus the mean before): noise and random walks of every shape seen
# reached 2.0-5.0 on 90 records of 2 h, a draught through a 150 s lag 6.9-7.5. Searched on
# a random walk, the onset fitted its largest wander as a near-step and took its name.
STEP_Z = 6.0


def standout(v: np.ndarray):
    """Return the index of ``v``'s largest deviation from its median, in robust sds."""
    dev = v - np.median(v)
    j = int(np.argmax(np.abs(dev)))
    spread = 1.4826 * float(np.median(np.abs(dev)))
    return j, (abs(dev[j]) / spread if spread > 0.0 else np.inf), (1.0 if dev[j] >= 0 else -1.0)


def static_spaces(base, x: np.ndarray,
                  names: Sequence[str] = STATIC_EFFECTS) -> List[EffectSpace]:
    """
    Search spaces scaled to the record: each effect from invisible to dominant.

    ``base`` is the record's ``static.StaticBaseline`` (N, lsb, bias, dt are used).
    Scales: the white noise's Allan deviation at the longest analysed τ (``sig_long``) sets
    where flicker and random walks become visible; the sample time and the record length bound
    correlation times; the per-sample noise sets tone and transient amplitudes.
    """
    n, dt = x.size, base.dt
    length = n * dt
    tau_max = obs.octave_m(n)[-1] * dt
    sig_long = base.N / np.sqrt(tau_max)
    sig_sample = base.N / np.sqrt(dt)
    # The most prominent narrow peak, however weak: if a tone is there at all, that is where.
    psd = obs.welch_psd(x, dt)
    bump = obs.broad_peak(psd)
    tones = obs.detected_tones(x, dt, min_prominence=0.0, max_tones=1, psd=psd)
    f_tone = float(tones[0]) if tones.size else 0.25 / dt
    df = 1.0 / (obs.welch_segment(n) * dt)
    lines, levels = obs.narrow_lines(x, dt, psd=psd)
    y = obs.detrend(x)

    def spectrum(effects):          # the baseline's model spectrum with ``effects`` added
        return model_spectrum(base.N, base.lsb, dt, effects, bias=base.bias)
    # A wandering tone only where the peak's band has a steadier envelope than noise: the
    # form can mimic a mode's band, which only the fourth moment tells apart.
    wander = bool(tones.size) and steady_envelope(y, dt, f_tone, spectrum([]))
    # Sign of a warm-up transient: early mean against the late mean of the detrended record.
    warm_sign = 1.0 if y[:max(n // 16, 1)].mean() >= y[n // 2:].mean() else -1.0
    # A transient that started mid-record: from the record's change point (the extremum of
    # the detrended cumulative sum), with the sign of the mean before it against after it
    # (the early-against-late sign reads a step at 40 % of the record backwards: the
    # detrending line tilts the early part the other way).
    cum = np.cumsum(y)
    k = int(np.argmax(np.abs(cum)))
    # A pulse (a bias sensing dT/dt as a temperature change passes): from the largest
    # excursion of the record averaged over 1/64 of its length, with its sign. Each is
    # searched only where it stands out of the average's own wander (``standout``): the onset
    # where the average's change over one window does (STEP_Z), the pulse where the average
    # itself does (PULSE_Z).
    w = max(n // 64, 1)
    smooth = (cum[w:] - cum[:-w]) / w if n > 2 * w else y
    stepped = smooth[w:] - smooth[:-w] if smooth.size > w else smooth
    onset = ((k * dt, 1.0 if cum[k] >= 0.0 else -1.0) if standout(stepped)[1] > STEP_Z
             else None)
    j, z, sign = standout(smooth)
    pulse = ((j + w / 2) * dt, sign) if z > PULSE_Z else None
    # A slow cycle (an HVAC or thermostat cycle): periods from two Welch segments (shorter
    # ones are the PSD's lines) up to a quarter of the record, where a line stands out.
    cycle = cycle_start(y, dt, 2.0 * obs.welch_segment(n) * dt)
    k_long = sig_long / np.sqrt(tau_max)
    # Upper bounds from the record itself as well: on a long record a strong random walk or
    # flicker floor can sit far above 30x the white noise's Allan deviation at the longest tau.
    adev_long = float(obs.overlapping_adev(y, np.array([obs.octave_m(n)[-1]]))[0])
    b_hi = max(30.0 * sig_long, 3.0 * adev_long / 0.664)
    k_hi = max(30.0 * k_long, 3.0 * adev_long * np.sqrt(3.0 / tau_max))
    gm_sigma = (0.1 * sig_long, max(2.0 * sig_sample, 3.0 * adev_long))
    # A correlation time whose Allan turnover (~1.9 tc) lies beyond the longest analysed tau
    # cannot be told from a random walk there: the simpler walk takes it.
    gm_tau = (3 * dt, tau_max / 2)
    # A fractional power law's pivot: near the longest tau, where such a process shows.
    pivot = 0.5 / tau_max
    gm_start = markov_start(y, dt, base.N, *gm_tau, *gm_sigma)
    memory = tuple(sp for sp in (memory_space(y),) if sp is not None)
    spaces = {
        # Cascaded moving averages (sinc^k: boxcar, Bartlett, the 3-stage CIC that decimating
        # MEMS front ends use) at 8x the output rate; taps = 1 would be the baseline. Or the
        # output-rate Butterworth low-pass (a DLPF) of order 1 or 2: the averages, decimated,
        # make whole steps of correlation, a gentle roll-off below Nyquist is the DLPF's. Or
        # a mode-split sense channel's response (a peak near the split, then a fall): started
        # at the PSD's broad bump where it has one. Or an interleaved front end's memory.
        'internal_lowpass': EffectSpace('internal_lowpass', [
            Param('taps', 2, 32, integer=True), Param('stages', 1, 3, integer=True, choice=True)],
            fixed={'decimation': 8.0}, alternatives=(EffectSpace('internal_lowpass', [
                Param('corner_hz', DLPF_LO / dt, DLPF_HI / dt, nyquist=0.5 / dt),
                Param('order', 1, 2, integer=True, choice=True)],
                fixed={'taps': 1.0, 'stages': 1.0, 'decimation': 1.0}),
                split_space(dt, psd, bump)) + memory, refit_all=True),
        # Flicker, optionally band-limited (1/f^2 above corner_hz; the top of its range, the
        # output Nyquist frequency, means no corner): B first without a corner, then the
        # corner, then both again (a corner moves the best B; refits near it: one pass). The
        # corner's lower bound keeps 1.5 decades of 1/f in the record (below, the process is a
        # rate random walk). Each power law may also be steeper (flicker) or shallower (walk)
        # than its IEEE slope, up to halfway to the other's (``SLOPE_SPLIT``), the coefficient
        # defined at ``pivot``; flicker's
        # steeper slope is an alternative to its corner, not an addition (with both, a slope
        # and a corner bend it into a walk's shape as well as a walk).
        'bias_instability': EffectSpace('bias_instability', [
            Param('B', 0.1 * sig_long, b_hi),
            Param('corner_hz', min(30.0 / length, 0.05 / dt), 0.5 / dt, off_at='hi')],
            passes=2, alternatives=(EffectSpace('bias_instability', [
                Param('B', 0.1 * sig_long, b_hi),
                Param('alpha', 1.0, SLOPE_SPLIT, log=False, off_at='lo', off_value=1.0)],
                fixed={'corner_hz': 0.0, 'pivot_hz': pivot}, passes=2),)),
        'rate_random_walk': EffectSpace('rate_random_walk', [
            Param('K', 0.1 * k_long, k_hi),
            Param('alpha', SLOPE_SPLIT, 2.0, log=False, off_at='hi', off_value=2.0)],
            fixed={'pivot_hz': pivot}, passes=2),
        # Started where the record's Allan excess puts a first-order process (``starts``).
        'gauss_markov': EffectSpace('gauss_markov', [
            Param('sigma', *gm_sigma, init=gm_start[0] if gm_start else None),
            Param('tau_s', *gm_tau, init=gm_start[1] if gm_start else None),
            Param('order', 1, 2, integer=True, choice=True)], passes=2),
        # Plain (angle error correlated when the step is coarse) or dithered (white error);
        # read once a frame where the PSD shows that comb of nulls (``starts.frame_start``).
        'quantization': quantization_space(base.N * np.sqrt(dt), frame_start(psd, dt)),
        'temperature_drift': warm_up_space(sig_long, sig_sample, length, warm_sign, onset,
                                           pulse, cycle),
        # The detected peak's frequency is known to a Welch bin: searched within +-2 bins (a
        # line between bins spreads its power differently from one on a bin). Where the PSD
        # shows a comb of narrow lines, a comb about its strongest line is the alternative.
        'vibration': vibration_space(sig_sample, f_tone if tones.size else None, df, dt,
                                     lines, levels, wander=wander,
                                     forest=forest_start(x, dt), spectrum=spectrum),
        'resonance': resonance_space(sig_sample, f_tone, dt, bump),
    }
    # Holds: searched where the record repeats samples exactly beyond what its rounding does
    # (``holds.repeat_excess``; everywhere if the step is too coarse to tell). Where the
    # excess is measured, p lies within SHARE_SLACK of it (a hold model must repeat as many
    # samples as the record does: a smoother whose spectrum a share of 0.2 mimics, with 0.5 %
    # of repeats, is no hold), started there; else p from a lag-1 correlation about its
    # standard error 1 / sqrt(n) up to one sample in two (below one in two if never two in a
    # row), started at the record's lag-1 correlation (p, on white noise; the coarse grid
    # steps by a factor 4).
    excess, excess_se = repeat_excess(x, base.lsb)
    p_lo, p_hi = 1.0 / np.sqrt(n), 0.45
    if excess_se > 0.0:
        start = excess
        p_lo = max(p_lo, min(excess / SHARE_SLACK, excess - REPEAT_Z * excess_se))
        p_hi = min(p_hi, max(excess * SHARE_SLACK, excess + REPEAT_Z * excess_se))
    else:
        start = float(np.dot(y[:-1], y[1:]) / np.dot(y, y))
    # Not searched where the excess is within noise, nor where it exceeds every share searched
    # (more repeats than one sample in two: a coarse lattice, not holds).
    if (not excess_se > 0.0 or excess > REPEAT_Z * excess_se) and p_lo < p_hi:
        p_param = Param('p', p_lo, p_hi, init=min(max(start, p_lo), p_hi))
        spaces['stale_samples'] = EffectSpace('stale_samples', [
            p_param, Param('isolated', 0, 1, integer=True, choice=True)])
        # Runs of holds (a frozen register): where most exact repeats come in runs of two or
        # more, an alternative start at their mean length. Where the share is measured, the
        # holds a glitch gate selects are the other alternative (``gate_space``).
        others = [gate_space(p_lo, p_hi, start, base)] if excess_se > 0.0 else []
        length, share = repeat_runs(x, base.lsb)
        if length >= 2.0 and share > RUN_SHARE:
            others.append(EffectSpace('stale_samples', [
                p_param, Param('run', 1.5, RUN_MAX, init=min(length, RUN_MAX))]))
        spaces['stale_samples'].alternatives = tuple(others)
    return [spaces[k] for k in names if k in spaces]


def gate_space(p_lo: float, p_hi: float, start: float, base) -> EffectSpace:
    """
    ``stale_samples``' glitch gate: the gates whose held shares span ``p_lo`` to ``p_hi``.

    The gate is in rad/s; the white noise it sees is the baseline's N less the gain the gate
    itself gives it in the white band (``gate.GateHolds.gain``), taken at the start's share.
    """
    g0 = gate_for_share(start)
    sd = base.N / np.sqrt(base.dt) / GateHolds(g0, 1.0).gain()
    lo, hi = gate_for_share(p_hi) * sd, gate_for_share(p_lo) * sd
    return EffectSpace('stale_samples', [Param('gate', lo, hi, init=g0 * sd)],
                       fixed={'p': 0.0})


def memory_space(y: np.ndarray):
    """
    ``internal_lowpass``' interleaved memory: the share kept and the converters in turn.

    On white noise the memory r of L interleaved converters correlates the samples L apart by
    r and no nearer ones, whereas every smoother correlates neighbours most (and a white angle
    error anti-correlates them). Searched only where some lag L in 2 to ``INTERLEAVE_MAX``
    correlates more than every nearer lag does in magnitude, by MEMORY_Z standard errors
    (1 / sqrt(n)), started there; r from half a standard error to 0.9. None where no lag
    does (one converter's memory is the first-order DLPF).
    """
    rho = obs.autocorrelation(y, INTERLEAVE_MAX)        # zeros for a constant record
    se = 1.0 / np.sqrt(y.size)
    lead = [rho[k] for k in range(1, rho.size)
            if rho[k] > np.abs(rho[:k]).max() + MEMORY_Z * se]
    if not lead:
        return None
    lo, hi = 0.5 * se, 0.9
    return EffectSpace('internal_lowpass', [
        Param('memory', lo, hi, init=min(max(max(lead), lo), hi)),
        Param('interleave', 2, INTERLEAVE_MAX, integer=True, choice=True)],
        fixed={'taps': 1.0, 'stages': 1.0, 'decimation': 1.0})


def split_space(dt: float, psd, bump=None) -> EffectSpace:
    """
    ``internal_lowpass``'s mode-split sense response: the split and the sense half bandwidth.

    The split from 2 % of the rate to 5 times the rate (a split above Nyquist still lifts the
    top of the band, by 2 (f / split)^2 in power); the half bandwidth from 0.2 % to 20 % of
    the rate. Where the PSD has a broad bump the response is started there, peaking as high
    as the bump stands over the white band (1-5 % of the rate): a peak of about split / 2
    sense in amplitude. Its valley is narrow (a tenth off in either moves a 2 h record's PSD
    far more than its scatter), which a start from mid-range does not find.
    """
    lo, hi = DLPF_LO / dt, 5.0 / dt
    s_lo, s_hi = 0.002 / dt, 0.2 / dt
    split = sense = None
    if bump is not None:
        f, p = psd
        white = float(np.median(p[obs.white_band(f, dt)]))
        near = (f >= 0.9 * bump) & (f <= 1.1 * bump)
        rise = float(np.mean(p[near])) / white if white > 0.0 and near.any() else 1.0
        split = min(max(bump, lo), hi)
        sense = min(max(split / (2.0 * np.sqrt(max(rise, 1.0))), s_lo), s_hi)
    return EffectSpace('internal_lowpass', [
        Param('split_hz', lo, hi, init=split), Param('sense_hz', s_lo, s_hi, init=sense)],
        fixed={'taps': 1.0, 'stages': 1.0, 'decimation': 1.0}, passes=2)


def quantization_space(inc: float, framed=None) -> EffectSpace:
    """
    ``quantization``'s search: the step from 0.2 to 10 per-sample angle increments ``inc``.

    With ``framed`` = (step, frame, floor) from the record (``starts.frame_start``), the
    alternative of an angle read once a frame is started there, its step up to sqrt(frame)
    times further (a frame's rate error falls on one sample in it).
    """
    space = EffectSpace('quantization', [
        Param('step_rad', 0.2 * inc, 10.0 * inc),
        Param('dither', 0, 1, integer=True, choice=True)])
    if framed is None:
        return space
    step, frame, _ = framed
    hi = 10.0 * inc * np.sqrt(FRAMES[-1])
    return replace(space, alternatives=(EffectSpace('quantization', [
        Param('step_rad', 0.2 * inc, hi, init=min(max(step, 0.2 * inc), hi)),
        Param('frame', 2, FRAMES[-1], integer=True, init=frame),
        Param('dither', 0, 1, integer=True, choice=True)], passes=2),))


def warm_up_space(amp_lo: float, amp_hi: float, length: float, warm_sign: float,
                  onset=None, pulse=None, cycle=None) -> EffectSpace:
    """
    ``temperature_drift``'s search: a warm-up from power-on, one that started later, a pulse.

    The power-on form (amplitude, lag); and, as alternative starts, ``onset`` = (the record's
    change point, the sign there): a transient from ``t0_s`` (a draught, a heater switching
    mid-record), and ``pulse`` = (time of the largest excursion, its sign): a pulse
    (``rise_s``) rising before it. Each alternative fits amplitude and lags around its start,
    then the onset; the best of them is kept. ``cycle`` (a ``cycle.CycleStart``): a periodic
    cycle (``cycle_space``).
    """
    lag = Param('tau_s', length / 200, length / 2)
    power_on = EffectSpace('temperature_drift', [
        Param('amplitude', amp_lo, amp_hi, sign=warm_sign), lag])
    others = []
    t0 = Param('t0_s', 0.01 * length, 0.9 * length, log=False, off_at='lo',
               init=onset[0] if onset else 0.5 * length)
    if onset is not None and t0.lo < onset[0] < t0.hi:
        others.append(EffectSpace('temperature_drift', [
            Param('amplitude', amp_lo, amp_hi, sign=onset[1]), lag, t0]))
    if pulse is not None:
        at, sign = pulse
        start = min(max(at - length / 50, t0.lo), t0.hi)
        others.append(EffectSpace('temperature_drift', [
            Param('amplitude', amp_lo, amp_hi, sign=sign),
            Param('tau_s', length / 400, length / 4),
            Param('rise_s', length / 4000, length / 20),
            replace(t0, init=start)]))
    if cycle is not None:
        others += [cycle_space(cycle), cycle_onset_space(cycle, length)]
    return replace(power_on, alternatives=tuple(others))


def cycle_space(cycle: CycleStart) -> EffectSpace:
    """
    ``temperature_drift``'s periodic cycle, its period and phases as read from the record.

    Each kept harmonic's amplitude is searched within a factor 3 of the record's; the period
    and the phases are kept (a period off by 1 % turns a 2 h record's 8th cycle by half a
    radian, which the early means see) and counted as estimated.
    """
    params, fixed, phases = [], {'cycle_s': cycle.period}, []
    for suffix, a, phase in zip(CYCLE_HARMONICS, cycle.amplitudes, cycle.phases):
        if a > 0.0:
            params.append(Param('amplitude' + suffix, a / 3.0, 3.0 * a, init=a))
            fixed['phase' + suffix] = phase
            phases.append('phase' + suffix)
    return EffectSpace('temperature_drift', params, fixed=fixed,
                       estimated=('cycle_s',) + tuple(phases))


def cycle_onset_space(cycle: CycleStart, length: float) -> EffectSpace:
    """
    Return the cycle of ``cycle_space`` switched on at ``t0_s``, ramping over ``rise_s``.

    An HVAC turned on mid-record, a loop gone unstable whose cycle grows to a limit: the
    record's least-squares amplitudes average the envelope, so each is searched up to 6
    times the record's (from 1.5 times: a cycle on over two thirds of the record), the start
    over the record's first 80 %, the ramp from none (a step on) to half the record.
    """
    plain = cycle_space(cycle)
    params = [replace(q, hi=6.0 * q.init, init=1.5 * q.init) for q in plain.params]
    params += [Param('t0_s', 0.02 * length, 0.8 * length, log=False, init=0.25 * length),
               Param('rise_s', cycle.period, 0.5 * length, off_at='lo')]
    return replace(plain, params=params)
