"""
Static records for ``gyro-char diagnose``: whole records on closed forms, twins as the check.

Each gyro channel is one task (``channel_task``: arrays in, the channel's JSON dict out, its
plot written): the baseline is fitted, ``--repeats`` simulated twins of it calibrate the
closed forms' null level, every candidate is scored on closed-form expectations
(``gyro_char.diagnosis.static_expect``), and ``--check`` twins of the selected model, run
through the bench simulator, check the closed forms and the fit (``posterior_predictive``).
``--method twins`` is the earlier path (every candidate scored on simulated twins), kept for
comparison and for records the closed forms do not cover. Tasks run in this process, or on a
Dask cluster with ``--scheduler ADDRESS`` (``distributed.Client``; the workers need
gyro_char installed and write the plots into ``--out``, so it must be visible to them).
"""
import os
from typing import Callable, List, Optional, Sequence

from gyro_char.errors import InputError
from gyro_char.jobs.dask_client import connect
import numpy as np

STATIC_STEPS = 4      # greedy steps at most, static records on closed forms


def add_static_options(p) -> None:
    """Add the static kind's options: method, posterior-predictive twins, Dask scheduler."""
    p.add_argument('--method', choices=('closed-form', 'twins'), default='closed-form',
                   help='score candidates on closed-form expected observables (static) or '
                        'pseudo-twins (swing) - the default - or on simulated twins (the '
                        'earlier, slower path)')
    p.add_argument('--check', type=int, default=4, metavar='N',
                   help='simulated twins of the selected model that check the closed forms '
                        '(pseudo-twins) and the fit (default 4; 0: none; else at least 3)')
    p.add_argument('--scheduler', default=None, metavar='ADDRESS',
                   help='run the channels as tasks on this Dask scheduler (e.g. '
                        'tcp://127.0.0.1:8786); default: in this process')


def analysed(records: Sequence[np.ndarray], dt: float, sources: Sequence[str],
             max_samples: Optional[int]) -> dict:
    """Return the contract's ``analysed`` field: samples and duration looked at per channel."""
    per = [{'source': str(s), 'samples': int(min(r.size, max_samples or r.size)),
            'duration_s': float(min(r.size, max_samples or r.size) * dt)}
           for r, s in zip(records, sources)]
    return {'samples': per[0]['samples'], 'duration_s': per[0]['duration_s'], 'records': per}


def build_problem(xs, dt, channel, opts: dict, base=None):
    """Build the static problem of one channel, closed-form or twin-based (``opts['method']``)."""
    from gyro_char.diagnosis import static, static_expect
    if opts['method'] == 'twins':
        return static.static_problem(xs, dt, channel=channel, max_samples=opts['max_samples'],
                                     base=base)
    return static_expect.closed_form_problem(xs, dt, channel=channel, base=base,
                                             max_samples=opts['max_samples'],
                                             twins=opts['repeats'], seed=opts['seed'])


def posterior_predictive(problem, diag, repeats: int, seed: int) -> dict:
    """
    Simulate ``repeats`` twins of the selected model and compare them with the closed forms.

    ``gap`` is the real records' gap to the twins' own mean in the baseline's closed-form
    yardstick (what the closed-form ``final_gap`` claims, measured with the simulator);
    ``closed_form_z`` per block is the rms of (twins' mean - closed-form mean) over the
    closed form's standard error of that mean (about 1 when the closed form is right).
    """
    from gyro_char.diagnosis import gap as diag_gap
    effects = list(diag.model)
    base_stats = diag.evaluations['baseline'].stats
    final_stats = diag.evaluations['final'].stats
    # The simulator's own twins: ``problem.twin`` where ``simulate`` approximates them.
    simulate = problem.twin or problem.simulate
    twins = [diag_gap.sim_stats([simulate(i, effects, seed * 1000 + 900 + k)
                                 for k in range(repeats)])
             for i in range(len(problem.reals))]
    gap = diag_gap.multi_gap(problem.reals, twins, [s.std for s in base_stats])
    z = {}
    for b in twins[0].mean:
        se = np.maximum(final_stats[0].std[b] / np.sqrt(repeats), 1e-300)
        dev = (twins[0].mean[b] - final_stats[0].mean[b]) / se
        z[b] = float(np.sqrt(np.mean(dev * dev)))
    return {'repeats': repeats, 'effects': [n for n, _ in effects], 'gap': gap,
            'closed_form_gap': diag.final_gap, 'closed_form_z': z}


def holdout_check(diag, x, dt, channel, opts: dict) -> dict:
    """Gap of the baseline and of the selected model on a record the fit never saw."""
    from gyro_char.diagnosis import gap as diag_gap, static
    from gyro_char.diagnosis.engine import excess_gap, objective_for
    from gyro_char.diagnosis.fit import fit_effect

    problem = build_problem([x], dt, channel, opts)
    seeds = [opts['seed'] * 1000 + 500 + k for k in range(opts['repeats'])]
    objective = objective_for(problem, seeds)
    effects = [(n, p) for n, p in diag.model if n != static.NUISANCE]
    _, base = fit_effect(objective, [], problem.nuisance)
    objective.set_reference(base)
    _, final = fit_effect(objective, effects, problem.nuisance)
    null = diag_gap.null_gaps(base.stats)
    return {'baseline_gap': base.gap, 'final_gap': final.gap,
            'null_gap_q95': float(np.quantile(null, 0.95)),
            'baseline_excess': excess_gap(base.gap, null),
            'final_excess': excess_gap(final.gap, null),
            'analysed': analysed([x], dt, ['holdout'], opts['max_samples']),
            'effects': [{'name': n, 'params': p} for n, p in effects],
            'note': 'effect parameters fixed from the fit; only the baseline white-noise '
                    'level is refitted on this record'}


def channel_task(task: dict) -> dict:
    """Diagnose one channel (``task``: arrays, sample time, options); return its JSON dict."""
    from gyro_char.diagnosis import engine
    from gyro_char.report.diagnosis_plot import plot_diagnosis

    opts, ch, dt = task['opts'], task['channel'], task['dt']
    problem = build_problem(task['records'], dt, ch, opts)
    # A whole record shows more effects at once than a cut one (smoothing, a band, a warm-up
    # and a flicker floor on the ADIS16405's Z axis): up to four steps on closed forms.
    steps = STATIC_STEPS if opts['method'] == 'closed-form' else 3
    diag = engine.run(problem, repeats=opts['repeats'], seed=opts['seed'], quiet=True,
                      max_steps=steps)
    out = diag.to_json()
    out['channel'] = ch
    out['method'] = opts['method']
    out['analysed'] = analysed(task['records'], dt, task['sources'], opts['max_samples'])
    if problem.check:
        out['closed_form_check'] = problem.check
        out['warnings'] = check_warnings(problem.check)
    if problem.expect is not None:
        bands = non_gaussian(task['records'][0], dt, opts['max_samples'], problem.expect,
                             diag.model)
        out['non_gaussian_bands'] = bands
        out.setdefault('warnings', []).extend(band_warnings(bands))
    lines = narrow(task['records'][0], dt, opts['max_samples'], problem, diag.model)
    if lines is not None:
        out['narrow_lines'] = lines
        out.setdefault('warnings', []).extend(line_warnings(lines))
    if opts['method'] == 'closed-form' and opts['check'] > 0:
        out['posterior_predictive'] = posterior_predictive(problem, diag, opts['check'],
                                                           opts['seed'])
    if task.get('holdout') is not None:
        out['holdout'] = holdout_check(diag, task['holdout'], dt, ch, opts)
    if task.get('png'):
        plot_diagnosis(diag, problem.ranges[0], task['png'], title=f'{ch}: sim-to-real gap')
    return out


def non_gaussian(x, dt: float, max_samples: Optional[int], expect, model) -> list:
    """Bands of the analysed record whose excess kurtosis the selected model does not make."""
    from gyro_char.diagnosis.band_kurtosis import non_gaussian_bands
    x = np.asarray(x, dtype=np.float64)[:max_samples or None]
    return non_gaussian_bands(x, dt, expect.spectrum(list(model)))


def narrow(x, dt: float, max_samples: Optional[int], problem, model) -> Optional[dict]:
    """
    Lines of the analysed record at fine resolution, each marked if the model makes it.

    The problem's own check (closed forms: it scanned the record already), else one on the
    twin path's baseline.
    """
    from gyro_char.diagnosis.narrow_lines import LineCheck
    from gyro_char.diagnosis.static_expect import StaticExpect
    check = problem.lines
    if check is None:
        x = np.asarray(x, dtype=np.float64)[:max_samples or None]
        check = LineCheck(x, dt, StaticExpect(problem.context, []).spectrum)
    return check.report(model)


def line_warnings(scan: dict) -> List[str]:
    """Say in words which narrow lines the selected model does not make."""
    from gyro_char.diagnosis.narrow_lines import missing
    return [f'a narrow line at {d["frequency_hz"]:.4f} Hz, {d["excess"]:.2f} x the local noise '
            f'floor in {scan["resolution_hz"]:.2g} Hz bins (family-wise p {d["p_value"]:.1e}), '
            "that the selected model does not make: a steady line finer than the gap's tone "
            'bands resolve (see "narrow_lines")'
            for d in missing(scan)]


def band_warnings(bands: Sequence[dict]) -> List[str]:
    """Say in words which bands are not the Gaussian noise or steady lines the model holds."""
    return [f'{b["range_hz"][0]:g}-{b["range_hz"][1]:g} Hz: excess kurtosis '
            f'{b["excess_kurtosis"]:+.2f}, the selected model {b["model"]:+.2f} '
            f'(sd {b["model_sd"]:.2g}): {b["meaning"]}' for b in bands]


# Baseline twins off their closed form by more than this (rms, in its spread) void the gaps.
CHECK_LIMIT = 3.0


def check_warnings(check: dict) -> List[str]:
    """Say where the baseline's own twins disagree with its closed forms (gaps not valid)."""
    out = []
    for i, rec in enumerate(check.get('records', [])):
        bad = {b: c['rms_residual'] for b, c in rec.items() if c['rms_residual'] > CHECK_LIMIT}
        if bad:
            worst = ', '.join(f'{b} {v:.3g}' for b, v in bad.items())
            out.append(f'record {i + 1}: the twins of the baseline lie off its closed forms (rms '
                       f'residual {worst}, expected ~1): the fitted baseline does not describe '
                       'this record and its gaps are not valid; see "baseline"')
    return out


def map_tasks(fn: Callable[[dict], dict], tasks: List[dict],
              scheduler: Optional[str] = None) -> List[dict]:
    """Run ``fn`` on every task: here, or on the Dask scheduler at ``scheduler``."""
    if not scheduler:
        return [fn(t) for t in tasks]
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise InputError('--scheduler needs the dask distributed package '
                         '(pip install distributed)') from None
    with connect(None, scheduler) as client:
        return client.gather(client.map(fn, tasks, pure=False))


def check_repeats(args) -> int:
    """Return ``--check``: 0 (no check) or at least 3 twins, whose scatter is compared."""
    if args.check < 0 or 0 < args.check < 3:
        raise InputError('--check must be 0 (no check) or >= 3 (their scatter is compared)')
    return args.check


def run_static(args, recs, dts, hold, channels, emit: Callable[[str], None]) -> dict:
    """Diagnose every channel of the static records; return ``{channel: json dict}``."""
    if args.max_samples is not None and args.max_samples < 1024:
        raise InputError('--max-samples must be >= 1024')
    opts = {'method': args.method, 'repeats': args.repeats, 'seed': args.seed,
            'max_samples': args.max_samples, 'check': check_repeats(args)}
    tasks = [{'channel': ch, 'dt': dts[0], 'opts': opts,
              'records': [np.asarray(r.channels[ch], dtype=np.float64) for r in recs],
              'sources': [r.source for r in recs],
              'holdout': None if hold is None else np.asarray(hold.channels[ch], np.float64),
              'png': os.path.abspath(os.path.join(args.out, f'diagnosis_{ch}.png'))}
             for ch in channels]
    results = map_tasks(channel_task, tasks, getattr(args, 'scheduler', None))
    per = {}
    for ch, out in zip(channels, results):
        per[ch] = out
        emit(ch, out)
    return per
