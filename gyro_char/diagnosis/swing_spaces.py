"""
Search spaces of the swing diagnosis's candidate effects, scaled to the fitted record.

Bounds come from the record's own noise (what an effect must reach to be seen); signed
parameters get the sign that moves the twins towards the record, and the encoder's line
count starts at the line the record's encoder residual shows (``signs``).
"""
from dataclasses import replace
from typing import Callable, List, Optional, Sequence

from gyro_char.diagnosis.fit import EffectSpace, LinearTerms, Param
from gyro_char.diagnosis.swing_baseline import SwingBaseline
from gyro_char.diagnosis.swing_expect import LAG_GRID, SMOOTH_GRID
from gyro_char.sim.effects.motion import EVEN_ORDERS, ODD_ORDERS, TILT_ORDERS
from gyro_char.sim.effects.timing import SPEED_ORDERS
import numpy as np

G0 = 9.80665
MEMORY = (0.005, 1.0)     # scale-factor memory searched: from none, 0.5 % .. 1 period
LOCK_IN = (3e-4, 0.3)     # lock-in rate searched: from none, fractions of the peak rate
RANGE = (0.2, 1.1)        # full-scale limit searched: fractions of the smallest, largest peak
WINDUP = 10.0             # a saturation's debt remembered up to this many periods
CREST_SIGMAS = 2.5        # a crest below the peak plus this many sample sds: a limit shown
# A limit's grid, in units of its start (``with_saturation``): dense just below it (a
# clip of the output, noise included, sits at the crest; the baseline's scale factor, fitted
# on the clipped record, moves the twin's equivalent a percent or two), sparse down to a
# quarter less (a limit on the true rate, the read-out noise added after it: some 4 noise
# sds lower).
CREST_GRID = (0.6, 0.75, 0.85, 0.92, 0.96, 0.98, 0.99, 1.0, 1.02)
ECE_TOP = 300.0           # cyclic error amplitudes searched up to this many encoder sds
HARMONICS = {f'a{k}': k for k in (2, 3, 4)}   # the cyclic error's harmonic amplitudes
PROBE_SEED = 4242         # seed of the twins the search's start-ups compare and probe with


def swing_spaces(base: SwingBaseline) -> List[EffectSpace]:
    """Search spaces scaled to the record (sign of signed parameters set by ``signs``)."""
    w = 2.0 * np.pi / base.period_s
    rate = base.amplitude * w                       # peak swing rate, rad/s
    sig = base.N / np.sqrt(base.duration)           # rate noise averaged over the record
    # Quadrature noise of the angle residual at the swing frequency (random-walk angle of PSD
    # N^2 / w^2 projected over the record): a delay and a g-sensitivity are searched over
    # the same span of quadrature amplitudes, so neither is favoured by its grid.
    q = base.N / w * np.sqrt(2.0 / base.duration)
    memory = Param('tau_s', MEMORY[0] * base.period_s, MEMORY[1] * base.period_s, off_at='lo')
    cyclic = (0.1 * base.encoder_sigma + 1e-9, ECE_TOP * base.encoder_sigma + 1e-7)
    return [
        # The gyro lag part of the delay (a one-pole filter inside the gyro): the motion
        # sees delay_s whatever the split, the lag alone colours the noise; searched over the
        # pseudo-twins' grid of lags from "none" (a pure stamp delay; the grid's lowest lag,
        # 0.05 sample, is no stand-in for none: its output correlation ~0.05 is 15 sigma of
        # the increment correlation on 900 s at 1 kHz).
        EffectSpace('time_delay', [Param('delay_s', 0.5 * q / rate, 200.0 * q / rate),
                                   Param('lag_s', LAG_GRID[0] * base.dt, LAG_GRID[1] * base.dt,
                                         off_at='lo')]),
        EffectSpace('g_sensitivity', [Param('gy', 0.5 * q * w / (G0 * base.amplitude),
                                            200.0 * q * w / (G0 * base.amplitude))]),
        # Up to 3000 record-averaged noise sds at the peak rate: a saturation 30 % down at
        # twice the peak rate (k3 ~ -0.4 s^2/rad^2 at 0.44 rad/s) is inside. Both scale-factor
        # shapes may have a memory (``tau_s``: self-heating of the cubic, a relaxing switch),
        # fitted after the memoryless shape, from none up to a period (longer: the memory
        # only averages, a constant scale-factor error the baseline already holds). The
        # lock-in rate last, from none up to a third of the peak rate.
        EffectSpace('scale_factor_nonlinearity', [
            Param('k2', 0.03 * sig / rate ** 2, 3000.0 * sig / rate ** 2),
            Param('k3', 0.03 * sig / rate ** 3, 3000.0 * sig / rate ** 3), memory,
            Param('lock_in', LOCK_IN[0] * rate, LOCK_IN[1] * rate, off_at='lo')]),
        EffectSpace('scale_factor_asymmetry', [
            Param('a', 0.03 * sig / rate, 300.0 * sig / rate), memory]),
        # Line count: started by ``signs`` at the record's line-spectrum peak (exact to a
        # fraction of a line); its range is +-1 % around that start (a whole number). The
        # harmonics 2-4 of that line after it, each from none (its band of ``encoder_lines``
        # an octave or two up: a third harmonic, clipped tracks' bumps four a line). Up to
        # 300 encoder noise sds (0.8 mrad on the preset, 3 % of a 256-line pitch; at 30 the
        # development set's strong 0.2 mrad error sat on the bound).
        # The harmonics a record does not show are held at 0, not left to the catalogue's
        # defaults (a2 = 2e-6 rad, which every twin carried until session 37).
        EffectSpace('encoder_cyclic_error', [
            Param('a1', *cyclic), *(Param(name, *cyclic, off_at='lo') for name in HARMONICS)],
            fixed=dict.fromkeys(HARMONICS, 0.0)),
        # Both streams: an IMU stamp error alone leaves no first-order trace here (the gyro
        # angle and the encoder read at the same wrong stamp move together); an encoder
        # stamp error shows as residual angle noise rate x error. Down to 0.2 % of the
        # encoder interval (2 µs at 1 kHz): below the ``rate_locked`` floor of a clean record.
        # Correlation time from 0.05 interval (white: phi = e^-20) to a tenth of a period,
        # searched from the white end: a wandering stamp error's angle error rate x e(t) is
        # coherent over tau_s, lines in the encoder residual rather than white noise.
        # The alternative: a smooth error (``order`` 2), a clock offset slewed by a time-sync
        # servo, from 5 % to 20 intervals (milliseconds at 1 kHz: not clipped, its steps are
        # small), correlation times from a tenth of a period to a twentieth of the record.
        EffectSpace('timestamp_jitter', [
            Param('sigma_s', 0.002 * base.encoder_dt, 0.4 * base.encoder_dt),
            Param('tau_s', 0.05 * base.encoder_dt, 0.1 * base.period_s,
                  init=0.05 * base.encoder_dt)], fixed={'stream': 2.0},
            alternatives=(EffectSpace('timestamp_jitter', [
                Param('sigma_s', SMOOTH_GRID[0] * base.encoder_dt,
                      SMOOTH_GRID[1] * base.encoder_dt),
                Param('tau_s', 0.1 * base.period_s,
                      max(0.05 * base.duration, 0.2 * base.period_s))],
                fixed={'stream': 2.0, 'order': 2.0}),)),
    ]


SIGNED = {'time_delay': ['delay_s'], 'g_sensitivity': ['gy'],
          'scale_factor_nonlinearity': ['k2', 'k3'], 'scale_factor_asymmetry': ['a']}


def probe_twins(n: int, simulate: Callable[[int, list, int], dict]) -> list:
    """Return the baseline twins of ``PROBE_SEED`` of n records: the start-ups' yardstick."""
    return [simulate(i, [], PROBE_SEED) for i in range(n)]


def signs(spaces: List[EffectSpace], reals: Sequence[dict],
          simulate: Callable[[int, list, int], dict],
          base: Optional[list] = None) -> List[EffectSpace]:
    """
    Give each signed parameter the sign that moves the twins towards the record.

    Two probe twins with the parameter at plus and minus its range's geometric middle (common
    random numbers) give the part of the effect's response on the harmonic blocks that
    changes sign with it; its projection on the record's departure from a baseline twin of the
    same seed gives the sign. The part that does not change sign (a cubic scale factor moves
    the 2f block alike either way) says nothing of the sign and, projected, outweighed the
    3f line of a compressive read-out. With several records (``simulate(record, effects, seed)``
    as in ``diagnose.Problem``) the departures of all of them are projected together.
    The encoder cyclic error's line count is started at the records' line (``with_lines``).
    ``base``: the records' ``probe_twins``, if already run.
    """
    idx = range(len(reals))
    blocks = [b for b in ('quadrature', 'harmonic_2f', 'harmonic_3f', 'harmonic_high')
              if all(b in reals[i] for i in idx)]
    base = probe_twins(len(reals), simulate) if base is None else base
    dev = np.concatenate([reals[i][b] - base[i][b] for i in idx for b in blocks])
    out = []
    for sp in spaces:
        if sp.name == 'encoder_cyclic_error':
            sp = with_lines(sp, reals, base)
        params = []
        for p in sp.params:
            if p.name in SIGNED.get(sp.name, []):
                mid = float(np.sqrt(p.lo * p.hi))
                up, down = ([simulate(i, [(sp.name, {**sp.fixed, p.name: v})], PROBE_SEED)
                             for i in idx] for v in (mid, -mid))
                resp = np.concatenate([up[i][b] - down[i][b] for i in idx for b in blocks])
                sign = 1.0 if float(np.einsum('i,i->', resp, dev)) >= 0 else -1.0
                p = replace(p, sign=sign)
            params.append(p)
        out.append(replace(sp, params=params, fixed=dict(sp.fixed), start=dict(sp.start)))
    return out


# Line-spectrum excess (log10 amplitude) above which a band is taken as a line, not noise;
# above LINE_GATE, as a line no stamp noise makes (``with_stamp_band``).
LINE_EXCESS, LINE_GATE = 0.3, 1.0


def line_bands(reals: Sequence[dict], base: Sequence[dict]):
    """Per record with line peaks: (peak line counts, ``encoder_lines``, excess over the twin)."""
    for r, b in zip(reals, base):
        peaks = getattr(r, 'line_peaks', None)
        if peaks is None or len(peaks) == 0 or 'encoder_lines' not in r:
            continue
        level = np.asarray(r['encoder_lines'])
        yield np.asarray(peaks, dtype=float), level, level - np.asarray(b['encoder_lines'])


def line_start(reals: Sequence[dict], base: Sequence[dict]) -> Optional[float]:
    """
    Line count of the record's encoder error: the strongest line that stands out of the twin.

    Among the bands of ``encoder_lines`` where a record exceeds its baseline twin by more
    than ``LINE_EXCESS`` (a factor 2 in amplitude), the one with the largest amplitude (a
    cyclic error's first harmonic is its largest); failing any, the band of largest excess.
    Its peak's line count (``SwingObs.line_peaks``, interpolated between FFT bins) is rounded
    to a whole number. None when the observables carry no peaks.
    """
    best, key = None, None
    for peaks, level, ex in line_bands(reals, base):
        for k in np.flatnonzero(np.isfinite(peaks)):
            rank = (ex[k] > LINE_EXCESS, level[k] if ex[k] > LINE_EXCESS else ex[k])
            if key is None or rank > key:
                best, key = float(np.round(peaks[k])), rank
    return best


def harmonics_shown(reals: Sequence[dict], base: Sequence[dict], start: float) -> set:
    """
    Harmonics k = 2..4 of line ``start`` that a record shows as lines of their own.

    A band of ``encoder_lines`` standing ``LINE_EXCESS`` above the twin with its peak within
    1 % of k x start. Without this test the harmonics raised three more octave bands at will
    and took a strong stamp jitter's broadband excess (the development set's: named a
    cyclic error, 151.5 -> 5.74).
    """
    shown = set()
    for peaks, _, ex in line_bands(reals, base):
        for k in HARMONICS.values():
            near = np.abs(peaks / (k * start) - 1.0) < 0.01
            if np.any(near & (ex > LINE_EXCESS)):
                shown.add(k)
    return shown


def with_lines(sp: EffectSpace, reals: Sequence[dict], base: Sequence[dict]) -> EffectSpace:
    """
    ``sp`` with ``lines`` started at the record's line and searchable within +-1 %.

    Its harmonics a2..a4 stay only where the record shows them (``harmonics_shown``); no
    line found, none stay.
    """
    start = line_start(reals, base)
    found = start is not None and start >= 1
    shown = harmonics_shown(reals, base, start) if found else set()
    params = [p for p in sp.params if p.name not in HARMONICS or HARMONICS[p.name] in shown]
    if not found:
        return replace(sp, params=params)
    lines = Param('lines', max(1.0, np.floor(0.99 * start)), np.ceil(1.01 * start),
                  integer=True)
    fixed = {k: v for k, v in sp.fixed.items() if k != 'lines'}
    return replace(sp, params=params + [lines], fixed=fixed,
                   start={**sp.start, 'lines': start})


def with_stamp_band(spaces: List[EffectSpace], reals: Sequence[dict], ranges: Sequence[dict],
                    base: Sequence[dict], bases: Sequence[SwingBaseline]) -> List[EffectSpace]:
    """
    Give the stamp error a resonant form, its centre started at the record's band.

    A clock disciplined by an underdamped servo (a PLL, a PTP loop tuned fast) errs most
    around the servo's frequency: a stamp error band-limited around f0 (``freq_hz``, quality
    ``q``), which reads as residual noise rate x error in that band. Its centre starts at
    the ``residual_psd`` bin where the records stand highest above their ``probe_twins``
    (``base``) and is searched from 1 Hz, or two swing frequencies, to a fifth
    of the slower stream's rate; q from 0.6 (no peak) to 30. Not offered where the encoder
    residual shows a line ``LINE_GATE`` above the twin: a cyclic error's chirp (1000 lines
    at 0.44 rad/s sweep 0-70 Hz) is a band in time too, and at 0.4 ms the resonant jitter
    took the development set's strong cyclic error (lines 2.7 above the twin; stamp errors
    strong enough to raise the residual PSD a decade raise no band above 0.7).
    """
    if any(np.any(ex > LINE_GATE) for _, _, ex in line_bands(reals, base)):
        return spaces
    best, band = -np.inf, None
    for i, r in enumerate(reals):
        if 'residual_psd' not in r:
            continue
        ex = np.asarray(r['residual_psd']) - np.asarray(base[i]['residual_psd'])
        if float(np.max(ex)) > best:
            best, band = float(np.max(ex)), np.asarray(ranges[i]['residual_psd'])[np.argmax(ex)]
    lo = max(1.0, 2.0 / min(b.period_s for b in bases))
    hi = 0.2 / max(max(b.dt, b.encoder_dt) for b in bases)
    if band is None or hi <= 2.0 * lo:
        return spaces
    start = float(np.clip(np.sqrt(band[0] * band[1]), lo, hi))
    enc = min(b.encoder_dt for b in bases)
    form = EffectSpace('timestamp_jitter', [
        Param('sigma_s', 0.002 * enc, 0.4 * enc, init=0.02 * enc),
        Param('freq_hz', lo, hi, init=start), Param('q', 0.6, 30.0, init=2.0)],
        fixed={'stream': 2.0})
    return [replace(sp, alternatives=tuple(sp.alternatives) + (form,))
            if sp.name == 'timestamp_jitter' else sp for sp in spaces]


def saturation_shown(crests: Sequence[tuple], bases: Sequence[SwingBaseline]) -> bool:
    """
    Return True if a record's output stays on one side below what its swing alone reaches.

    ``crests``: each record's (max(gyro), -min(gyro)), the output's two crests. Unlimited,
    the samples near a crest reach the bias plus or minus the peak rate (with the
    scale-factor error) plus about 4 of the gyro's sample sds (the largest of ~10^5 near the
    crest); a full-scale limit holds them at the limit, a wound-up loop too (its noise owed
    with the rest), a limit on the true rate within a read-out noise of it.
    """
    return any(min(up - b.bias, down + b.bias) < (1.0 + b.scale_factor_error) * b.peak_rate
               + CREST_SIGMAS * b.N / np.sqrt(b.dt) for (up, down), b in zip(crests, bases))


def with_saturation(spaces: List[EffectSpace], crests: Sequence[tuple],
                    bases: Sequence[SwingBaseline]) -> List[EffectSpace]:
    """
    Give the scale-factor nonlinearity a full-scale limit where the records show one.

    Two forms: a plain clip of the output (noise included), and a loop that owes what it
    could not follow and pays it back in range (its integrator winds up), its memory
    searched down from ten periods (the angle kept whole) to none. The limit (one, at
    +-range) starts at the records' lowest crest times one plus the baseline's scale-factor
    error (the twin's equivalent) and is gridded densely just below it (``CREST_GRID``),
    then refined within a fifth of the smallest peak rate to just beyond the largest. A
    plain clip at the right limit is worse than none where the loop winds up, so the loop's
    search starts wound up. Not shown (``saturation_shown``), neither is searched.
    """
    if not saturation_shown(crests, bases):
        return spaces
    peaks = [b.peak_rate for b in bases]
    lo, hi = RANGE[0] * min(peaks), RANGE[1] * max(peaks)
    # The twin's equivalent of a limit at the crest: the baseline's scale factor, fitted on
    # the clipped record, took the clipped peaks' loss (-5.5 % on a clip 12 % under the
    # peak), and the twin's swing enters the limit that much smaller.
    crest = float(np.clip(min((1.0 + b.scale_factor_error) * min(c)
                              for c, b in zip(crests, bases)), lo, hi))
    limit = Param('range_rads', lo, hi, off_at='hi', init=crest,
                  points=tuple(crest * np.array(CREST_GRID)))
    period = max(b.period_s for b in bases)
    windup = Param('windup_s', min(b.dt for b in bases), WINDUP * period, off_at='lo',
                   init=WINDUP * period)
    forms = (EffectSpace('scale_factor_nonlinearity', [limit], fixed={'k2': 0.0}),
             EffectSpace('scale_factor_nonlinearity', [limit, windup], fixed={'k2': 0.0}))
    return [replace(sp, alternatives=tuple(sp.alternatives) + forms)
            if sp.name == 'scale_factor_nonlinearity' else sp for sp in spaces]


def unresolved_pairs(bases: Sequence[SwingBaseline], rel: float = 0.1) -> frozenset:
    """
    Return the look-alike pairs that swing runs with these baselines cannot tell apart.

    One period (all within ``rel``): a delay and g-sensitivity (cos θ residuals scaling as
    A·ω and g·A/ω). One peak rate A·ω: an asymmetry and a quadratic scale factor (2f lines
    growing as the peak rate and as its square).
    """
    def one(values):
        return max(values) <= (1.0 + rel) * min(values)
    out = set()
    if one([b.period_s for b in bases]):
        out.add(frozenset({'time_delay', 'g_sensitivity'}))
    if one([b.peak_rate for b in bases]):
        out.add(frozenset({'scale_factor_asymmetry', 'scale_factor_nonlinearity'}))
    return frozenset(out)


# The tabulated forms (``sim.effects``): effect, range key, coefficient prefix, orders, what
# else is fixed (the plain form's parameters at 0 beside the table, for their catalogue
# defaults are not; where the table acts: the true rate, or the sensed value), and the plain
# parameters solved with the table (a delay's constant part).
TABLES = (('scale_factor_nonlinearity', 'table_rads', 'c', ODD_ORDERS, {'k2': 0.0}, ()),
          ('scale_factor_nonlinearity', 'table_rads', 'c', ODD_ORDERS,
           {'k2': 0.0, 'on_output': 1.0}, ()),
          ('scale_factor_asymmetry', 'table_rads', 'c', EVEN_ORDERS, {'a': 0.0}, ()),
          ('scale_factor_asymmetry', 'table_rads', 'c', EVEN_ORDERS,
           {'a': 0.0, 'on_output': 1.0}, ()),
          ('g_sensitivity', 'table_mps2', 't', TILT_ORDERS, {'gy': 0.0}, ()),
          ('time_delay', 'table_rads', 'd', SPEED_ORDERS, {'lag_s': 0.0}, ('delay_s',)))
TABLE_BLOCKS = ('quadrature', 'harmonic_2f', 'harmonic_3f', 'harmonic_high',
                'scale_factor_shift')
# The table's range over the records' largest peak rate or tilt: just beyond, so that on a
# swing of that peak T_n(u) is nearly cos n theta (a wider range leaves the scale factor a
# near-null combination of the coefficients, which the least squares then blow up).
TABLE_MARGIN = 1.02
TABLE_UNIT = 1e-4     # rad/s or s: a coefficient's probe runs (the blocks are linear in it)


def with_tables(spaces: List[EffectSpace], bases: Sequence[SwingBaseline],
                simulate: Callable[[int, list, int], dict],
                zero: Optional[list] = None) -> List[EffectSpace]:
    """
    Give the rate- and tilt-shaped effects a tabulated alternative, solved by least squares.

    A waveform the motion drives has harmonics far beyond what k2, k3, gy or one delay make
    (a look-up table's residual, a companding law, a diode's one-sided knee, a flexure's
    softening, a latency that grows with the speed); the table is a Chebyshev series over the
    records' range of rate (odd for the nonlinearity, even for the asymmetry and the
    latency) or of the tilt's specific force (odd, for the g-sensitivity).
    Its harmonic blocks are linear in the coefficients: one probe run per coefficient and
    record gives their change per unit (``LinearTerms``), and every fit solves the
    coefficients on what the model leaves (``fit.solve_linear``). ``zero``: the records'
    ``probe_twins``, if already run.
    """
    rate = TABLE_MARGIN * max(b.peak_rate for b in bases)
    tilt = TABLE_MARGIN * G0 * np.sin(max(b.amplitude for b in bases))
    idx = range(len(bases))
    zero = probe_twins(len(bases), simulate) if zero is None else zero
    probed = {}

    def basis(name: str, probe: dict, names: tuple) -> tuple:
        key = (name, repr(sorted(probe.items())))
        if key not in probed:
            out = []
            for i in idx:
                runs = [simulate(i, [(name, {**probe, n: TABLE_UNIT})], PROBE_SEED)
                        for n in names]
                out.append({b: np.array([(o[b] - zero[i][b]) / TABLE_UNIT for o in runs])
                            for b in TABLE_BLOCKS if b in zero[i]})
            probed[key] = tuple(out)
        return probed[key]

    out = []
    for sp in spaces:
        tables = []
        for name, key, prefix, orders, plain, lead in TABLES:
            if name != sp.name:
                continue
            fixed = {**plain, key: rate if key == 'table_rads' else tilt}
            names = lead + tuple(f'{prefix}{n}' for n in orders)
            # The linear blocks see the table's deterministic part only: probed on the true
            # rate, whether or not the table acts on the sensed value.
            probe = {**{k: v for k, v in fixed.items() if k != 'on_output'},
                     **dict.fromkeys(names, 0.0)}
            tables.append(EffectSpace(name, [], fixed={**fixed, **dict.fromkeys(names, 0.0)},
                                      estimated=names, linear=LinearTerms(
                                          names, TABLE_BLOCKS, basis(name, probe, names))))
        out.append(replace(sp, alternatives=tuple(sp.alternatives) + tuple(tables))
                   if tables else sp)
    return out
