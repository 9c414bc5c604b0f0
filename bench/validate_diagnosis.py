"""
Blind validation of the sim-to-real diagnosis (``gyro-char diagnose --kind static``).

Generates static gyro records with an effect the diagnosis is NOT told about, runs the
diagnosis blind, and prints a confusion table, top-1 accuracy, median gap shrink and the
false-alarm rate on clean baseline records.

The effects are generated here with shapes that differ from the package catalogue's
(``gyro_char.sim.effects``), so that the diagnosis is not rewarded for recognising its own
generator:

- internal_lowpass: a Hann-window FIR at the output rate (catalogue: cascaded moving averages
  at an internal rate, then decimation);
- vibration: a tone with 20 % slow amplitude modulation and a random frequency;
- temperature_drift: a hyperbolic warm-up A / (1 + t / tau) (catalogue: exponential);
- bias_instability: flicker approximated by a sum of five Gauss-Markov processes with
  log-spaced correlation times (catalogue: Kasdin-Walter fractional integration);
- bias_instability_band (scored as ``bias_instability``): a band-limited flicker, four
  Gauss-Markov processes with correlation times 0.2-200 s, one per decade (1/f with a ripple
  between ~1e-3 and 0.8 Hz, 1/f^2 above: the shortest time sets the upper corner);
- rate_random_walk: a random walk with Laplace-distributed increments held for 0.5 s;
- gauss_markov: a second-order (two cascaded first-order) Markov process;
- quantization: a white angle error uniform on one step, differenced into rate (catalogue: a
  floor quantizer of the accumulated angle);
- resonance: white noise through two identical resonators in cascade, a fourth-order band
  (catalogue: one second-order resonator);
- stale_samples: a host loop reading the sensor a share e faster than it updates, with a
  jittered read instant: regularly spaced repeats and no lost sample (catalogue: independent
  holds, each replacing a sample).

A second set of shapes, ``validate_diagnosis_heldout.py``, was fixed before the closed-form
diagnosis was tuned and is run only with ``--held-out`` (once, at the end of a development
round): it says how far the results carry to shapes nobody looked at. A third set,
``validate_diagnosis_heldout_b.py`` (``--held-out b``), was written in session 4 before any
diagnosis ran on it.

Levels per shape: 0 and 1 (the earlier weak and strong magnitudes) and 2, the edge of
detectability on a 2 h record (chosen by the magnitude's own detectability scale: a few sigma
of the block that shows the effect best; see ``--duration``).

The clean baseline (white rate noise of ADIS16405 level, rounded to a 0.05 °/s output step) is
generated here too, without the bench simulator. Usage::

    python bench/validate_diagnosis.py --duration 7200 --levels 2 1 --seeds 11
                                                  # 2 h records, edge and strong levels
    python bench/validate_diagnosis.py --duration 7200 --levels 2 1 --seeds 11 --held-out
    python bench/validate_diagnosis.py --duration 7200 --levels 2 1 --seeds 11 --held-out b
    python bench/validate_diagnosis.py --samples 8192 --method twins   # the earlier table
    python bench/validate_diagnosis.py --quick    # three cases, as in test/test_diag_validation
    python bench/validate_diagnosis.py --swing    # the swing part (validate_diagnosis_swing.py)
"""
import argparse
import importlib
import os
import sys
import time

from gyro_char.diagnosis import engine as diagnose, static as diag_static, static_expect
import heldout_sets
import numpy as np
from scipy import signal

DT = 0.01
N_ARW = 2.4 * np.pi / 180.0 / 60.0          # 2.4 deg/sqrt(h), the ADIS16405 records' level
LSB = 0.05 * np.pi / 180.0                  # 0.05 deg/s output step
SIG = N_ARW / np.sqrt(DT)                   # per-sample white noise, rad/s


HELD_OUT = 'validate_diagnosis_heldout'


def held_out_letters() -> list:
    """Return the held-out sets present beside this harness: a (no suffix), b, c, ..."""
    return heldout_sets.letters(HELD_OUT, 'a')


def clean(n: int, rng) -> np.ndarray:
    return SIG * rng.standard_normal(n) + 0.003


def hann_lowpass(x, rng, length):
    h = np.hanning(length + 2)[1:-1]
    return signal.lfilter(h / h.sum(), [1.0], x)


def am_tone(x, rng, amplitude, freq):
    t = np.arange(x.size) * DT
    env = 1.0 + 0.2 * np.sin(2 * np.pi * t / 37.0 + rng.uniform(0, 6.3))
    return x + amplitude * env * np.sin(2 * np.pi * freq * t + rng.uniform(0, 6.3))


def hyperbolic_warmup(x, rng, amplitude, tau):
    t = np.arange(x.size) * DT
    return x + amplitude / (1.0 + t / tau)


def gm_sum(n, rng, taus):
    """Sum of unit-variance first-order Gauss-Markov processes, one per correlation time."""
    out = np.zeros(n)
    for tc in taus:
        a = np.exp(-DT / tc)
        w = rng.standard_normal(n) * np.sqrt(1 - a * a)
        w[0] = rng.standard_normal()
        out += signal.lfilter([1.0], [1.0, -a], w)
    return out


def gm_sum_flicker(x, rng, b):
    return x + b * gm_sum(x.size, rng, np.geomspace(1.0, 300.0, 5)) / np.sqrt(5.0) * 1.5


def gm_band_flicker(x, rng, b):
    """Four first-order Gauss-Markov processes, tau 0.2-200 s, equal variance each."""
    return x + b * gm_sum(x.size, rng, np.geomspace(0.2, 200.0, 4)) / 2.0


def laplace_rw(x, rng, k):
    hold = int(0.5 / DT)
    steps = rng.laplace(0.0, 1.0 / np.sqrt(2.0), x.size // hold + 1) * k * np.sqrt(hold * DT)
    return x + np.repeat(np.cumsum(steps), hold)[:x.size]


def gm2(x, rng, sigma, tc):
    a = np.exp(-DT / tc)
    y = signal.lfilter([1.0], [1.0, -a], signal.lfilter([1.0], [1.0, -a], rng.standard_normal(
        x.size)))
    y = y[-x.size:]
    return x + sigma * y / np.std(y)


def white_angle(x, rng, step):
    e = rng.uniform(-0.5, 0.5, x.size + 1) * step
    return x + np.diff(e) / DT


def band4(x, rng, sigma, freq, q):
    """White noise through two identical second-order resonators (a fourth-order band)."""
    th, r = 2 * np.pi * freq * DT, np.exp(-np.pi * freq * DT / q)
    a = [1.0, -2 * r * np.cos(th), r * r]
    y = signal.lfilter([1.0], a, signal.lfilter([1.0], a, rng.standard_normal(x.size + 4000)))
    y = y[4000:]
    return x + sigma * y / np.std(y)


def host_reads(x, rng, e):
    """Read x by a host loop (1 + e) times faster than it updates, read instants jittered."""
    j = np.arange(x.size)
    idx = np.maximum.accumulate(np.floor(j / (1.0 + e) + rng.uniform(0.0, 0.3, x.size)))
    return x[np.minimum(idx.astype(int), x.size - 1)]


# name -> (generator, [magnitude parameter sets, weaker first])
SHAPES = {
    'internal_lowpass': (hann_lowpass, [{'length': 3}, {'length': 5}, {'length': 1}]),
    'vibration': (am_tone, [{'amplitude': 0.15 * SIG, 'freq': 13.3},
                            {'amplitude': 0.3 * SIG, 'freq': 31.7},
                            {'amplitude': 0.02 * SIG, 'freq': 13.3}]),
    'temperature_drift': (hyperbolic_warmup, [{'amplitude': 3e-3, 'tau': 20.0},
                                              {'amplitude': 1e-2, 'tau': 30.0},
                                              {'amplitude': 5e-4, 'tau': 20.0}]),
    'bias_instability': (gm_sum_flicker, [{'b': 1e-3}, {'b': 3e-3}, {'b': 1e-4}]),
    'bias_instability_band': (gm_band_flicker, [{'b': 1e-3}, {'b': 3e-3}, {'b': 2e-4}]),
    'rate_random_walk': (laplace_rw, [{'k': 3e-4}, {'k': 1e-3}, {'k': 3e-6}]),
    'gauss_markov': (gm2, [{'sigma': 3e-3, 'tc': 0.5}, {'sigma': 1e-2, 'tc': 1.0},
                           {'sigma': 5e-4, 'tc': 0.5}]),
    'quantization': (white_angle, [{'step': 4 * N_ARW * np.sqrt(DT)},
                                   {'step': 8 * N_ARW * np.sqrt(DT)},
                                   {'step': 1.5 * N_ARW * np.sqrt(DT)}]),
    'resonance': (band4, [{'sigma': 0.3 * SIG, 'freq': 17.0, 'q': 15.0},
                          {'sigma': SIG, 'freq': 23.0, 'q': 8.0},
                          {'sigma': 0.08 * SIG, 'freq': 17.0, 'q': 15.0}]),
    'stale_samples': (host_reads, [{'e': 0.03}, {'e': 0.1}, {'e': 0.008}]),
}
# Shapes scored as another catalogue effect (the truth label is the effect family's name).
LABELS = {'bias_instability_band': 'bias_instability'}
# (effect, magnitude level) pairs; the tone goes through the smoothing filter, so the pair
# with internal_lowpass uses the lower-frequency tone (the 31.7 Hz one would be filtered away).
PAIRS = [(('vibration', 0), ('internal_lowpass', 0)),
         (('temperature_drift', 1), ('internal_lowpass', 0)),
         (('vibration', 1), ('bias_instability', 1))]


# Seeds of the extra clean records (``--clean``), apart from the shape seeds.
CLEAN_SEED0 = 1000


def make_record(effects, n, seed, shapes=None):
    shapes = shapes or SHAPES
    rng = np.random.default_rng(seed)
    x = clean(n, rng)
    for name, level in effects:
        fn, levels = shapes[name]
        x = fn(x, rng, **levels[level])
    return np.round(x / LSB) * LSB


def run_case(effects, n, seed, repeats, method='closed-form', shapes=None):
    """Diagnose one generated record blind (closed forms by default, or twins)."""
    x = make_record(effects, n, seed, shapes)
    if method == 'twins':
        problem = diag_static.static_problem([x], DT, channel='gyro_x')
    else:
        problem = static_expect.closed_form_problem([x], DT, twins=repeats, seed=seed + 17)
    d = diagnose.run(problem, repeats=repeats, seed=seed + 17)
    return d


def cases(quick: bool, seeds, levels=(0, 1), shapes=None, pairs=True, clean_extra=0):
    if quick:
        yield 'clean', [], seeds[0]
        yield 'vibration', [('vibration', 1)], seeds[0]
        yield 'internal_lowpass', [('internal_lowpass', 1)], seeds[0]
        return
    for s in seeds:
        yield 'clean', [], s
    for k in range(clean_extra):
        yield 'clean', [], CLEAN_SEED0 + k
    for name in shapes or SHAPES:
        for level in levels:
            for s in seeds:
                yield name, [(name, level)], s
    for a, b in PAIRS if pairs else ():
        for s in seeds:
            yield f'{a[0]}+{b[0]}', [a, b], s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--quick', action='store_true')
    ap.add_argument('--swing', action='store_true',
                    help='run the swing part instead (bench/validate_diagnosis_swing.py)')
    ap.add_argument('--samples', type=int, default=8192)
    ap.add_argument('--duration', type=float, default=None,
                    help='record length in s (overrides --samples; 7200 = 2 h at 100 Hz)')
    ap.add_argument('--levels', type=int, nargs='+', default=[0, 1],
                    help='magnitude levels (0 weak, 1 strong, 2 edge of detectability)')
    ap.add_argument('--method', choices=('closed-form', 'twins'), default='closed-form')
    ap.add_argument('--clean', type=int, default=0, metavar='K',
                    help=f'K more clean records, seeds {CLEAN_SEED0}.. (the clean record of a '
                         'seed is the same in every shape set: false alarms need many)')
    ap.add_argument('--held-out', nargs='?', const='a', choices=held_out_letters(),
                    default=None,
                    help='a held-out shape set, no pairs: a = validate_diagnosis_heldout.py '
                         '(used once in session 3), b = validate_diagnosis_heldout_b.py, '
                         'and so on')
    ap.add_argument('--only', nargs='+', default=None, metavar='NAME',
                    help='only these shapes (and no pairs, no clean records)')
    ap.add_argument('--repeats', type=int, default=None,
                    help='twins per model (default: 32 of the baseline on closed forms, 6 '
                         'per model with --method twins)')
    ap.add_argument('--seeds', type=int, nargs='+', default=[11, 12])
    args, rest = ap.parse_known_args(argv)
    if args.swing:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import validate_diagnosis_swing
        return validate_diagnosis_swing.main(rest + (['--quick'] if args.quick else []))
    if rest:
        ap.error(f'unrecognized arguments: {" ".join(rest)}')
    rows = []
    t0 = time.time()
    repeats = args.repeats or (static_expect.NULL_TWINS if args.method != 'twins' else 6)
    n = int(round(args.duration / DT)) if args.duration else args.samples
    shapes = SHAPES
    if args.held_out:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        module = heldout_sets.module(HELD_OUT, args.held_out, 'a')
        shapes = importlib.import_module(module).shapes(DT, SIG, N_ARW)
    todo = cases(args.quick, args.seeds, args.levels, shapes, pairs=not args.held_out,
                 clean_extra=args.clean)
    if args.only:
        todo = [c for c in todo if len(c[1]) == 1 and c[1][0][0] in args.only]
    for label, effects, seed in todo:
        d = run_case(effects, n, seed, repeats, args.method, shapes)
        truth = [LABELS.get(e, e) for e, _ in effects]
        # Detected by the gap, or by a finer check (a narrow line) that named an effect.
        detected = d.baseline_gap > d.null_gap['q95'] or bool(d.selected_effects)
        top1 = d.ranking[0]['effect']
        rows.append({'label': label, 'truth': truth, 'shape': label, 'seed': seed,
                     'level': effects[0][1] if effects else None, 'detected': detected,
                     'selected': d.selected_effects, 'top1': top1,
                     'baseline_gap': d.baseline_gap, 'final_gap': d.final_gap,
                     'null_mean': d.null_gap['mean'],
                     'baseline_excess': d.baseline_excess, 'final_excess': d.final_excess,
                     'final_model_mean': d.null_gap['final_model_mean'],
                     'ambiguous': d.ambiguous})
        print(f'{label:40s} seed {seed} level {rows[-1]["level"]} gap '
              f'{d.baseline_gap:7.2f} -> {d.final_gap:6.2f} (null q95 '
              f'{d.null_gap["q95"]:.2f}; final model vs itself '
              f'{d.null_gap["final_model_mean"]:.2f}) selected {d.selected_effects} '
              + ''.join(f'(ambiguous {a["effects"]}) ' for a in d.ambiguous)
              + f'[{time.time() - t0:.0f} s]', flush=True)
    report(rows, list(shapes))
    return 0


def report(rows, names) -> None:
    single = [r for r in rows if len(r['truth']) == 1]
    print('\nconfusion (rows: true effect, columns: first selected effect; detected cases)')
    cols = [n for n in names if n not in LABELS] + ['none']
    print(' ' * 18 + ' '.join(f'{c[:8]:>8s}' for c in cols))
    for name in names:
        sel = [r for r in single if r['shape'] == name and r['detected']]
        counts = [sum(1 for r in sel if (r['selected'] or ['none'])[0] == c) for c in cols]
        print(f'{name[:18]:18s}' + ' '.join(f'{c:8d}' for c in counts))
    det = [r for r in single if r['detected']]
    ok = [r for r in det if r['selected'][:1] == r['truth']]
    print(f'\nsingle effects: detected {len(det)}/{len(single)}; top-1 (first selected == '
          f'truth) among detected: {len(ok)}/{len(det)} = '
          f'{100.0 * len(ok) / max(len(det), 1):.0f} %')
    named = [r for r in det if r['selected']]
    print(f'  where an effect was named: right {len([r for r in named if r in ok])}/{len(named)}'
          f'; nothing named (gap left unexplained) {len(det) - len(named)}')
    said = [r for r in det if r not in ok and r['ambiguous']
            and r['truth'][0] in r['ambiguous'][0]['effects']]
    print(f'  wrong top-1 but flagged ambiguous with the truth among the candidates: '
          f'{len(said)}/{len(det) - len(ok)}')
    for level in sorted({r['level'] for r in single}):
        lv = [r for r in single if r['level'] == level]
        lv_ok = [r for r in lv if r['detected'] and r['selected'][:1] == r['truth']]
        print(f'  magnitude level {level}: detected {sum(r["detected"] for r in lv)}/{len(lv)}, '
              f'correct top-1 {len(lv_ok)}/{len(lv)}')
    hit = [r for r in rows if r['truth'] and r['detected']]
    if hit:
        shrink = [1.0 - r['final_gap'] / r['baseline_gap'] for r in hit]
        # The excess forms only where the gap is above the sim-vs-itself level (a line only
        # the fine scan sees can sit below it: no excess to remove).
        above = [r for r in hit if r['baseline_excess'] > 0.0
                 and r['baseline_gap'] > r['null_mean']]
        excess = [(r['baseline_gap'] - r['final_gap']) / (r['baseline_gap'] - r['null_mean'])
                  for r in above] or [float('nan')]
        # diagnose.excess_gap: the gap above the null level, in quadrature.
        quad = [1.0 - r['final_excess'] / r['baseline_excess'] for r in above] or [np.nan]
        print(f'median gap shrink over detected cases: 1 - final/baseline '
              f'{100.0 * float(np.median(shrink)):.0f} %; over the {len(above)} with a gap '
              f'above the sim-vs-itself level: share of that excess removed '
              f'{100.0 * float(np.median(excess)):.0f} %, 1 - final_excess/baseline_excess '
              f'{100.0 * float(np.median(quad)):.0f} %')
        low = [r for r, v in zip(hit, shrink) if v < 0.7]
        floor = [r for r in low if r['final_gap'] <= r['final_model_mean']]
        print(f'  cases below 70 %: {len(low)}/{len(hit)}, of which {len(floor)} end at or '
              f'below the gap the twins of the final model score against each other (its '
              f'floor: no fit of that model does better on average)')
    pairs = [r for r in rows if len(r['truth']) == 2]
    if pairs:
        both = [r for r in pairs if set(r['truth']) <= set(r['selected'])]
        print(f'pairs: both effects selected in {len(both)}/{len(pairs)}')
        for r in pairs:
            print(f'  {"+".join(r["truth"])} seed {r["seed"]}: selected {r["selected"]}'
                  + (f', ambiguous {[a["effects"] for a in r["ambiguous"]]}'
                     if r['ambiguous'] else ''))
    clean_rows = [r for r in rows if not r['truth']]
    fa = [r for r in clean_rows if r['selected']]
    print(f'false alarms on clean baseline records: {len(fa)}/{len(clean_rows)}'
          + (f' ({[r["selected"] for r in fa]})' if fa else ''))
    amb = [r for r in rows if r['ambiguous']]
    print(f'cases with an ambiguity statement: {len(amb)}')


if __name__ == '__main__':
    sys.exit(main())
