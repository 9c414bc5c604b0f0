"""
Blind validation of ``gyro-char diagnose --kind swing`` (the swing part of validate_diagnosis).

Clean swing runs come from the bench simulator (the paper's model, ADIS16405 preset; by default
15 minutes with the gyro and the encoder at 1 kHz, ``--duration`` / ``--rate`` /
``--encoder-rate`` give the short form the tests use); the effect is then added HERE, to the
finished run, with shapes that differ from the catalogue's (``gyro_char.sim.effects``), and the
diagnosis is not told. Every shape has one signature,
``fn(imu_t, gyro, enc_t, enc_angle, stand, rng, **params) -> (imu_t, gyro, enc_t, enc_angle)``,
``stand(t)`` giving the true stand (angle, rate) at ``t``; ``shapes(rate_hz)`` maps each
catalogue effect name to its shape and three levels ``[weak, strong, edge]``:

- time_delay: a sensor-internal group delay (whole samples plus a 4-tap Lagrange fractional
  FIR) applied to the rate values (catalogue: the stamps are shifted);
- g_sensitivity: g_y f_y + g_z (f_z - g) from the stand angle (catalogue searches g_y alone);
- scale_factor_nonlinearity: a soft saturation S tanh(ω / S) (catalogue: k2 ω² + k3 ω³);
- scale_factor_asymmetry: a ω tanh(ω / 0.05 rad/s), a smoothed |ω| (catalogue: a |ω|);
- timestamp_jitter: uniformly distributed encoder stamp errors (catalogue: Gaussian). IMU
  stamp errors are not used: the residual is blind to them to first order (the integrated
  angle and the encoder read at the same wrong stamp are off by the same rate x error);
- encoder_cyclic_error: a first + third harmonic error on 1000 lines per turn (catalogue:
  first + second harmonic on 2048 lines);
- time_delay:one_pole (label time_delay): a gyro-side one-pole IIR low-pass, exponential
  form a = exp(-dt / tau), on the rate values, motion and noise (catalogue: backward Euler);
- timestamp_jitter:gauss_markov (label timestamp_jitter): a slowly wandering encoder stamp
  error, a first-order Gauss-Markov process driven by uniform innovations (catalogue:
  Gaussian).

A shape key ``LABEL:FORM`` is scored as the catalogue effect LABEL.

The EDGE level is where the effect starts to show on a 15-minute 1 kHz run at the 5 s period
(20° amplitude, peak rate A ω = 0.44 rad/s, gyro white noise N = 5.5e-4 rad/s/√Hz): about 6
standard deviations on the one element that shows it best, which lifts the rms gap over ~35
elements just above the null's 95th percentile. Quadrature noise q = N / ω √(2 / T) = 2.1e-5
rad: delay A ω d = 6 q (d = 0.28 ms), g-sensitivity g_y g A / ω = 6 q (g_y = 4.5e-5 /g);
saturation: the 3f angle (A ω)³ / (36 ω S²) = 6 q / 3 (S = 6.7 rad/s); asymmetry: the 2f angle
0.21 a A = 6 q / 2 (a = 8.4e-4); jitter: the rate-locked variance scatters by ~6 µs² on a clean
run, 6 x that is σ = 6 µs (uniform half width 1.2e-5 s); cyclic error: the largest noise line in
the 512-1024 lines band reads 4e-7 rad on a clean run, the edge line 1e-6 rad (third harmonic
4e-7 rad, 3x its band's noise line). Weak and strong are the levels the 60 s, 200 Hz form of
this harness used.

Three modes:

- ``single``: one run at the preset's 5 s period per case (the look-alike pairs are
  ambiguous there: the diagnosis flags them and names the separating run);
- ``two``: each case is TWO runs of the same gyro and effect, at periods 5 s and 2.5 s (same
  20° amplitude), diagnosed together. Halving the period doubles the peak rate A ω and halves
  A / ω, which separates both look-alike pairs: the cos θ residual of a delay (-A ω d) doubles
  while that of g-sensitivity (-g_y g A / ω) halves (4x apart), and the 2f line of an
  asymmetry (∝ a A ω) doubles while that of a quadratic term (∝ k2 (A ω)²) quadruples. Half
  the amplitude at the same period would not separate delay from g-sensitivity (both ∝ A);
- ``pairs``: two-run cases with two effects at once (delay + saturation, g-sensitivity +
  asymmetry, jitter + cyclic error); success = both found among the selected effects.

``--held-out [b|c]`` takes the shapes from ``validate_diagnosis_swing_heldout.shapes(rate_hz)``
(set B; the flag alone) or ``validate_diagnosis_swing_heldout_c`` (set C) in this directory
instead (same interface; written apart from this harness, run once at the end).

Usage::

    python bench/validate_diagnosis_swing.py --mode two      # two-run table, 15 min at 1 kHz
    python bench/validate_diagnosis_swing.py --mode single
    python bench/validate_diagnosis_swing.py --mode two --duration 60 --rate 200   # short form
    python bench/validate_diagnosis_swing.py --quick         # clean + delay + g, two-run
"""
import argparse
import importlib
from pathlib import Path
import sys
import time

from gyro_char.diagnosis import engine as diagnose, swing as diag_swing
from gyro_char.errors import InputError
from gyro_char.records import ENCODER_CHANNEL, Recording
from gyro_char.sim import simulator
from gyro_char.sim.chain import stand_angle_clean, stand_rate_clean
from gyro_char.sim.config import BenchConfig
import heldout_sets
import numpy as np
from scipy import signal

RATE_HZ = 1000.0
ENCODER_RATE_HZ = 1000.0
DURATION = 900.0
PERIOD = 5.0
G0 = 9.80665
LEVELS = ('weak', 'strong', 'edge')
HELD_OUT = 'validate_diagnosis_swing_heldout'


def stand_of(cfg):
    """
    ``stand(t) -> (angle, rate)``: the stand's true motion, its system noises left out.

    The swing with the stand's offset and slow drift: an error locked to the disk (an
    encoder's cyclic error) must follow the angle the encoder reads. Until session 37 this
    was the swing alone; the preset's 2e-6 rad/s drift then slid a 4096-line error 7.4 rad
    of phase against the disk over 15 minutes, smearing its line (set AJ's gated error).
    """
    def stand(t):
        return stand_angle_clean(cfg.stand, t), stand_rate_clean(cfg.stand, t)
    return stand


def lagrange_delay(imu_t, gyro, enc_t, enc_angle, stand, rng, delay_s):
    """Delay the rate values by ``delay_s``: whole samples, then a 4-tap Lagrange fraction."""
    dt = float(np.median(np.diff(imu_t)))
    whole = int(np.floor(delay_s / dt))
    d = 1.0 + delay_s / dt - whole     # 4-tap FIR of 1 + fraction samples, minus one sample
    k = np.arange(4)
    h = np.array([np.prod([(d - m) / (j - m) for m in k if m != j]) for j in k])
    y = np.convolve(gyro, h)[:gyro.size]
    y = np.r_[y[1:], y[-1]]
    y[:3] = gyro[:3]
    if whole:
        y = np.r_[np.full(whole, y[0]), y[:-whole]]
    return imu_t, y, enc_t, enc_angle


def g_both(imu_t, gyro, enc_t, enc_angle, stand, rng, gy, gz):
    phi = stand(imu_t)[0]
    return imu_t, gyro + gy * G0 * np.sin(phi) + gz * G0 * (np.cos(phi) - 1.0), enc_t, enc_angle


def saturation(imu_t, gyro, enc_t, enc_angle, stand, rng, s):
    rate = stand(imu_t)[1]
    return imu_t, gyro + s * np.tanh(rate / s) - rate, enc_t, enc_angle


def smooth_asym(imu_t, gyro, enc_t, enc_angle, stand, rng, a):
    rate = stand(imu_t)[1]
    return imu_t, gyro + a * rate * np.tanh(rate / 0.05), enc_t, enc_angle


def uniform_jitter(imu_t, gyro, enc_t, enc_angle, stand, rng, half_width):
    return imu_t, gyro, enc_t + rng.uniform(-half_width, half_width, enc_t.size), enc_angle


def cyclic_13(imu_t, gyro, enc_t, enc_angle, stand, rng, a1, a3):
    e = enc_angle + a1 * np.sin(1000 * enc_angle + 0.4) + a3 * np.sin(3000 * enc_angle + 1.1)
    return imu_t, gyro, enc_t, e


def one_pole_iir(imu_t, gyro, enc_t, enc_angle, stand, rng, tau):
    """Low-pass the rate values by a one-pole IIR of time constant ``tau`` (exponential form)."""
    dt = float(np.median(np.diff(imu_t)))
    a = float(np.exp(-dt / tau))
    y = signal.lfilter([1.0 - a], [1.0, -a], gyro, zi=[a * gyro[0]])[0]
    return imu_t, y, enc_t, enc_angle


def gm_stamps(imu_t, gyro, enc_t, enc_angle, stand, rng, sigma, tau):
    """Move the encoder stamps by a Gauss-Markov error (``sigma``, ``tau``), uniform drive."""
    phi = float(np.exp(-float(np.median(np.diff(enc_t))) / tau))
    w = rng.uniform(-np.sqrt(3.0), np.sqrt(3.0), enc_t.size)
    w[1:] *= np.sqrt(1.0 - phi * phi)
    e = sigma * signal.lfilter([1.0], [1.0, -phi], w)
    lim = 0.45 * float(np.median(np.diff(enc_t)))
    return imu_t, gyro, enc_t + np.clip(e, -lim, lim), enc_angle


def label(key: str) -> str:
    """Return the catalogue effect a shape key ``LABEL[:FORM]`` is scored as."""
    return key.partition(':')[0]


def shapes(rate_hz: float) -> dict:
    """Shape and levels ``[weak, strong, edge]`` per catalogue effect name (module doc)."""
    return {
        'time_delay': (lagrange_delay, [{'delay_s': 1.15e-3}, {'delay_s': 3.05e-3},
                                        {'delay_s': 2.8e-4}]),
        'g_sensitivity': (g_both, [{'gy': 2e-4, 'gz': 5e-5}, {'gy': 5e-4, 'gz': 1e-4},
                                   {'gy': 4.5e-5, 'gz': 1e-5}]),
        'scale_factor_nonlinearity': (saturation, [{'s': 1.3}, {'s': 0.9}, {'s': 6.7}]),
        'scale_factor_asymmetry': (smooth_asym, [{'a': 3e-3}, {'a': 8e-3}, {'a': 8.4e-4}]),
        'timestamp_jitter': (uniform_jitter, [{'half_width': 1e-4}, {'half_width': 3e-4},
                                              {'half_width': 1.2e-5}]),
        'encoder_cyclic_error': (cyclic_13, [{'a1': 5e-5, 'a3': 2e-5}, {'a1': 2e-4, 'a3': 5e-5},
                                             {'a1': 1e-6, 'a3': 4e-7}]),
        'time_delay:one_pole': (one_pole_iir, [{'tau': 1.6e-3}, {'tau': 5e-3},
                                               {'tau': 8e-4}]),
        'timestamp_jitter:gauss_markov': (gm_stamps, [
            {'sigma': 6e-5, 'tau': 0.03}, {'sigma': 2e-4, 'tau': 0.05},
            {'sigma': 3e-5, 'tau': 0.02}]),
    }


SHAPES = shapes(RATE_HZ)


def held_out_letters() -> list:
    """Return the held-out sets present beside this harness: b (no suffix), c, d, ..."""
    return heldout_sets.letters(HELD_OUT, 'b')


def held_out_shapes(rate_hz: float, which: str = 'b') -> dict:
    """Return held-out set ``which``'s ``shapes(rate_hz)``; exit clearly when it is absent."""
    here = Path(__file__).resolve().parent
    module = heldout_sets.module(HELD_OUT, which, 'b')
    if not (here / f'{module}.py').exists():
        raise SystemExit(f'--held-out: no {module}.py in {here} (the held-out shapes are '
                         'written apart from this harness)')
    sys.path.insert(0, str(here))
    return importlib.import_module(module).shapes(rate_hz)


PAIRS = [(('time_delay', 1), ('scale_factor_nonlinearity', 1)),
         (('g_sensitivity', 1), ('scale_factor_asymmetry', 1)),
         (('timestamp_jitter', 1), ('encoder_cyclic_error', 1))]
TWO_PERIODS = (PERIOD, PERIOD / 2)


def make_record(truth, seed, period=PERIOD, *, duration=DURATION, rate_hz=RATE_HZ,
                encoder_rate_hz=ENCODER_RATE_HZ, shape_set=None):
    """IMU and encoder of one run with the harness-shaped effects ``[(name, level), ...]``."""
    shape_set = shapes(rate_hz) if shape_set is None else shape_set
    cfg = BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': rate_hz},
                                                'encoder': {'rate_hz': encoder_rate_hz},
                                                'stand': {'period_s': period}})
    run = simulator.simulate_swing(cfg, duration=duration, seed=seed, channels=('gyro_x',))
    imu, enc = run.imu, run.encoder
    rng = np.random.default_rng(seed + 99)
    stand = stand_of(cfg)
    t, x, te, e = imu.t, imu.channels['gyro_x'], enc.t, enc.channels[ENCODER_CHANNEL]
    for name, level in truth:
        fn, levels = shape_set[name]
        t, x, te, e = fn(t, x, te, e, stand, rng, **levels[level])
    return (Recording(t, {'gyro_x': x}, imu.source),
            Recording(te, {ENCODER_CHANNEL: e}, enc.source))


def run_case(truth, seed, repeats, periods, **run):
    # Runs of one case differ in period and noise realisation (seed), not in the effect.
    records = [(*make_record(truth, seed + 100 * k, per, **run), per)
               for k, per in enumerate(periods)]
    return diagnose.run(diag_swing.swing_records_problem(records), repeats=repeats,
                        seed=seed + 17)


# Seeds of the extra clean runs (``--clean``), apart from the shape seeds.
CLEAN_SEED0 = 1000


def cases(mode, quick, seeds, shape_set=None, clean_extra=0):
    """(mode, truth, seed) per case; truth = [(effect, level), ...]."""
    shape_set = SHAPES if shape_set is None else shape_set
    if quick:
        yield 'two', [], seeds[0]
        yield 'two', [('time_delay', 1)], seeds[0]
        yield 'two', [('g_sensitivity', 1)], seeds[0]
        return
    for m in (('single', 'two', 'pairs') if mode == 'all' else (mode,)):
        if m == 'pairs':
            for pair in [p for p in PAIRS if all(n in shape_set for n, _ in p)]:
                for s in seeds:
                    yield m, list(pair), s
            continue
        for s in seeds:
            yield m, [], s
        for k in range(clean_extra):
            yield m, [], CLEAN_SEED0 + k
        for name, (_, levels) in shape_set.items():
            for level in range(len(levels)):
                for s in seeds:
                    yield m, [(name, level)], s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--quick', action='store_true')
    ap.add_argument('--mode', choices=('single', 'two', 'pairs', 'all'), default='all')
    ap.add_argument('--repeats', type=int, default=5)
    ap.add_argument('--seeds', type=int, nargs='+', default=[11, 12])
    ap.add_argument('--clean', type=int, default=0, metavar='K',
                    help='K more clean runs per mode, seeds 1000.. (false alarms need many)')
    ap.add_argument('--clean-only', action='store_true',
                    help='the clean runs alone, no effect shapes')
    ap.add_argument('--duration', type=float, default=DURATION, help='run length, s (900)')
    ap.add_argument('--rate', type=float, default=RATE_HZ, help='gyro rate, Hz (1000)')
    ap.add_argument('--encoder-rate', type=float, default=ENCODER_RATE_HZ,
                    help='encoder rate, Hz (1000)')
    ap.add_argument('--held-out', nargs='?', const='b', choices=held_out_letters(),
                    default=None,
                    help=f'a held-out set instead of the shapes here: b (the flag alone) = '
                         f'bench/{HELD_OUT}.py, c = bench/{HELD_OUT}_c.py, and so on')
    ap.add_argument('--only', nargs='+', default=None, metavar='NAME[/LEVEL]',
                    help='only these shapes, or one level of a shape (time_delay/weak); no '
                         'pairs, no clean records')
    args = ap.parse_args(argv)
    shape_set = (held_out_shapes(args.rate, args.held_out) if args.held_out
                 else shapes(args.rate))
    run = {'duration': args.duration, 'rate_hz': args.rate,
           'encoder_rate_hz': args.encoder_rate, 'shape_set': shape_set}
    print(f'runs of {args.duration:g} s, gyro {args.rate:g} Hz, encoder {args.encoder_rate:g} '
          f'Hz; shapes: ' + (f'held-out {args.held_out}' if args.held_out else 'this harness'),
          flush=True)
    rows, t0 = [], time.time()
    todo = cases(args.mode, args.quick, args.seeds, {} if args.clean_only else shape_set,
                 clean_extra=args.clean)
    if args.only:   # one-effect cases named by shape or by shape/level
        todo = [(m, truth, s) for m, truth, s in todo if len(truth) == 1
                and {truth[0][0], f'{truth[0][0]}/{level_name(truth[0][1])}'} & set(args.only)]
    for mode, truth, seed in todo:
        row = {'mode': mode, 'truth': [label(n) for n, _ in truth],
               'label': '+'.join(f'{n}/{level_name(lv)}' for n, lv in truth) or 'clean',
               'level': [level_name(lv) for _, lv in truth], 'seed': seed}
        try:
            d = run_case(truth, seed, args.repeats,
                         (PERIOD,) if mode == 'single' else TWO_PERIODS, **run)
        except InputError as exc:
            # The diagnosis refused the run (e.g. a gyro that barely follows the swing): the
            # departure is seen, nothing is named; counted as a detected miss.
            rows.append({**row, 'detected': True, 'selected': [], 'ambiguous': [],
                         'shrink': 0.0, 'shrink_excess': 0.0})
            print(f'{mode:6s} {row["label"]:52s} seed {seed} refused: {exc} '
                  f'[{time.time() - t0:.0f} s]', flush=True)
            continue
        amb = sorted({n for a in d.ambiguous for n in a['effects']})
        rows.append({**row, 'detected': d.baseline_gap > d.null_gap['q95'],
                     'selected': d.selected_effects, 'ambiguous': amb,
                     'shrink': 1.0 - d.final_gap / d.baseline_gap,
                     'shrink_excess': 1.0 - d.final_excess / max(d.baseline_excess, 1e-12)})
        print(f'{mode:6s} {rows[-1]["label"]:52s} seed {seed} gap {d.baseline_gap:6.2f} -> '
              f'{d.final_gap:5.2f} (null q95 {d.null_gap["q95"]:.2f}) selected '
              f'{d.selected_effects} ambiguous {amb} [{time.time() - t0:.0f} s]', flush=True)
    for mode in ('single', 'two', 'pairs'):
        if any(r['mode'] == mode for r in rows):
            report(mode, [r for r in rows if r['mode'] == mode],
                   list(dict.fromkeys(label(k) for k in shape_set)))
    return 0


def level_name(level: int) -> str:
    return LEVELS[level] if level < len(LEVELS) else str(level)


def _pct(k, n):
    return f'{k}/{n} = {100.0 * k / max(n, 1):.0f} %'


def report(mode, rows, names=None):
    print(f'\n=== {mode} ===')
    eff = [r for r in rows if r['truth']]
    det = [r for r in eff if r['detected']]
    if mode == 'pairs':
        both = [r for r in det if set(r['truth']) <= set(r['selected'])]
        first = [r for r in det if r['selected'][:1] and r['selected'][0] in r['truth']]
        print(f'detected {len(det)}/{len(eff)}; both effects selected {_pct(len(both), len(det))}'
              f'; first selected is one of the pair {_pct(len(first), len(det))}')
        for r in eff:
            print(f'  {r["label"]:52s} seed {r["seed"]}: selected {r["selected"]}')
    else:
        ok = [r for r in det if r['selected'][:1] == r['truth']]
        flagged = [r for r in det if r not in ok and r['truth'][0] in r['ambiguous']]
        print(f'detected {len(det)}/{len(eff)}; top-1 (first selected == truth) among '
              f'detected {_pct(len(ok), len(det))}; wrong top-1 but flagged ambiguous with '
              f'the truth: {len(flagged)}')
        named = [r for r in det if r['selected']]
        print(f'  where an effect was named: right {_pct(sum(r in ok for r in named), len(named))}'
              f'; nothing named (gap left unexplained) {len(det) - len(named)}')
        confusion(det, names)
        for lv in LEVELS:
            at = [r for r in eff if r.get('level') == [lv]]
            if at:
                d_at = [r for r in at if r['detected']]
                print(f'  level {lv}: detected {len(d_at)}/{len(at)}, top-1 among detected '
                      f'{_pct(sum(r in ok for r in d_at), len(d_at))}')
    if det:
        print(f'median gap shrink over detected cases: 1 - final/baseline '
              f'{100.0 * float(np.median([r["shrink"] for r in det])):.0f} %, excess form '
              f'{100.0 * float(np.median([r["shrink_excess"] for r in det])):.0f} %')
    clean = [r for r in rows if not r['truth']]
    fa = [r for r in clean if r['selected']]
    print(f'false alarms on clean records: {len(fa)}/{len(clean)}')


def confusion(det, names=None):
    """Truth (rows) against the first selected effect (columns), detected cases."""
    names = list(dict.fromkeys(label(k) for k in SHAPES)) if names is None else names
    cols = names + ['none']
    short = {c: ''.join(w[0] for w in c.split('_')) for c in cols}
    print('  truth \\ first selected    ' + ' '.join(f'{short[c]:>5s}' for c in cols))
    for name in names:
        rs = [r for r in det if r['truth'] == [name]]
        counts = [sum((r['selected'] or ['none'])[0] == c for r in rs) for c in cols]
        print(f'  {name:28s}' + ' '.join(f'{k:5d}' for k in counts))
    print('  (' + ', '.join(f'{short[c]} = {c}' for c in cols) + ')')


if __name__ == '__main__':
    sys.exit(main())
