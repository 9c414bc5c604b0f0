"""
``report.html`` of a fleet: one self-contained page (plots inline as base64 PNG).

Top: the devices in the order the fleet gives (failing ones first, then those in error, then
the outliers by robust z against the fleet), each with its reasons and links to its own plots
in ``devices/<device>/``. Below: the distribution of every quantity across the devices (one
point per device and channel) with the spec limits drawn, in the spec's unit or the field's.
"""
import base64
import html
import io
import math
from typing import Callable, Dict, List, Optional, Tuple
from urllib.parse import quote

from gyro_char.report.atomic import atomic_write
from gyro_char.units import HUMAN_UNITS, SI_UNITS, to_si
import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

STATES = ('fail', 'error', 'outlier', 'pass', 'ok')
# limit_of(kind, channel, quantity) -> (unit, {'min' | 'max' | 'max_abs': bound}) or None
LimitOf = Callable[[str, str, str], Optional[Tuple[str, Dict[str, float]]]]
_CSS = """
body{font-family:sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse;font-size:0.9em}td,th{border:1px solid #ccc;padding:3px 6px}
tr.fail td{background:#fde2e2}tr.error td{background:#fff1cc}tr.outlier td{background:#e8eefc}
.plots{display:flex;flex-wrap:wrap;gap:12px}figure{margin:0}figcaption{font-size:0.85em}
"""
# Marks the page once every image has loaded (read by people's tools and by the browser test).
_IMAGES_SCRIPT = """
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var ok = imgs.every(function (i) { return i.complete && i.naturalWidth > 0; });
  document.body.setAttribute('data-images', String(imgs.length));
  document.body.setAttribute('data-images-loaded', ok ? 'all' : 'missing');
});
"""


def _display_unit(kind: str, channel: str, quantity: str, si_unit: str,
                  limit_of: LimitOf) -> str:
    """Return the unit a person reads a quantity in: the spec's, the field's, or SI."""
    lim = limit_of(kind, channel, quantity)
    if lim is not None:
        return lim[0]
    sensor = channel.split('_', 1)[0]
    if kind == 'allan' and quantity in HUMAN_UNITS.get(sensor, {}):
        return HUMAN_UNITS[sensor][quantity][1]
    return si_unit


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format='png', dpi=80)
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode('ascii')


def _distribution(group: List[Dict], limit_of: LimitOf, failing) -> Dict:
    """One quantity's values across devices (x: channel) with the limits drawn."""
    kind, quantity = group[0]['kind'], group[0]['quantity']
    channels = sorted({r['channel'] for r in group})
    unit = _display_unit(kind, channels[0], quantity, group[0]['si_unit'], limit_of)
    factor = to_si(1.0, group[0]['si_unit'], unit)
    fig, ax = plt.subplots(figsize=(4.2, 3.0))
    rng = np.random.default_rng(0)  # horizontal jitter only, fixed: the same page every run
    for i, ch in enumerate(channels):
        mine = [r for r in group if r['channel'] == ch]
        y = np.array([r['value'] for r in mine]) * factor
        x = i + rng.uniform(-0.12, 0.12, len(y))
        bad = np.array([r['device'] in failing for r in mine], dtype=bool)
        bound = np.array([bool(r.get('bound')) for r in mine], dtype=bool)
        for sel, color in ((~bad, 'tab:blue'), (bad, 'tab:red')):
            ax.plot(x[sel & ~bound], y[sel & ~bound], 'o', color=color, ms=4.5)
            ax.plot(x[sel & bound], y[sel & bound], 'v', mfc='none', color=color, ms=5)
        lim = limit_of(kind, ch, quantity)
        for name, bound in (lim[1].items() if lim else ()):
            for b in ((bound, -bound) if name == 'max_abs' else (bound,)):
                ax.plot([i - 0.35, i + 0.35], [b, b], '-', color='tab:red', lw=1.5)
    values = np.array([r['value'] for r in group]) * factor
    if np.all(values > 0) and values.max() > 20 * values.min():
        ax.set_yscale('log')
    ax.set_xticks(range(len(channels)), channels)
    ax.set_xlim(-0.6, len(channels) - 0.4)
    ax.set_title(f'{kind}: {quantity} [{unit}]', fontsize=10)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return {'title': f'{kind} {quantity}', 'unit': unit, 'png': _png(fig)}


def _plots(rows: List[Dict], limit_of: LimitOf, failing) -> List[Dict]:
    groups: Dict[tuple, List[Dict]] = {}
    for r in rows:
        if r['status'] == 'ok' and math.isfinite(r['value']):
            sensor = r['channel'].split('_', 1)[0] if r['kind'] == 'allan' else ''
            groups.setdefault((r['kind'], sensor, r['quantity']), []).append(r)
    order = {q: i for i, q in enumerate(SI_UNITS['gyro'])}
    keys = sorted(groups, key=lambda k: (k[0], k[1], order.get(k[2], 99), k[2]))
    return [_distribution(groups[k], limit_of, failing) for k in keys]


def _links(device: str, plots: List[str]) -> str:
    base = f'devices/{quote(device)}/'
    return ' '.join([f'<a href="{base}">files</a>'] + [
        f'<a href="{base}{quote(n)}">{html.escape(n)}</a>' for n in plots])


def write_report(path: str, devices: List[Dict], rows: List[Dict], limit_of: LimitOf,
                 outlier_z: float) -> None:
    """
    Write the self-contained ``report.html`` of the fleet to ``path``.

    ``devices``: one dict per device in display order with ``device, kind, state`` (one of
    ``STATES``), ``zmax, zwhere`` (largest robust z and where), ``reasons`` and ``plots`` (PNG
    names in ``devices/<device>/``); ``rows``: the tidy rows (``bound`` True where the value is
    only an upper bound); ``limit_of``: the spec's limit of a row, drawn on its distribution.
    """
    failing = {d['device'] for d in devices if d['state'] == 'fail'}
    counts = {s: sum(1 for d in devices if d['state'] == s) for s in STATES}
    head = (f'{len(devices)} devices: {counts["fail"]} failing the spec, {counts["error"]} in '
            f'error, {counts["outlier"]} outlying (|robust z| &gt; {outlier_z:g})')
    out = ['<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">',
           '<title>gyro-char fleet report</title>', f'<style>{_CSS}</style>',
           f'<script>{_IMAGES_SCRIPT}</script></head><body>',
           '<h1>gyro-char fleet report</h1>', f'<p id="summary">{head}</p>',
           '<h2>Devices</h2><table id="devices"><thead><tr><th>device</th><th>kind</th>'
           '<th>state</th><th>largest robust z</th><th>reasons</th><th>plots</th></tr></thead>'
           '<tbody>']
    for d in devices:
        zcell = f'{d["zmax"]:+.2f} ({html.escape(d["zwhere"])})' if d['zwhere'] else ''
        name = html.escape(d['device'])
        out.append(f'<tr class="{d["state"]}" data-device="{name}" data-state="{d["state"]}">'
                   f'<td>{name}</td><td>{d["kind"]}</td><td>{d["state"]}</td><td>{zcell}</td>'
                   f'<td>{html.escape(d["reasons"] or "")}</td>'
                   f'<td>{_links(d["device"], d["plots"])}</td></tr>')
    out.append('</tbody></table><h2>Distributions across the fleet</h2>'
               '<p>One point per device and channel; red: devices failing the spec; open '
               'triangles: upper bounds (term not resolved by the record); red bars: spec '
               'limits.</p><div class="plots">')
    for p in _plots(rows, limit_of, failing):
        out.append(f'<figure><img alt="{html.escape(p["title"])}" '
                   f'src="data:image/png;base64,{p["png"]}"><figcaption>'
                   f'{html.escape(p["title"])} [{html.escape(p["unit"])}]</figcaption></figure>')
    out.append('</div></body></html>')

    def write(tmp):
        with open(tmp, 'w') as fh:
            fh.write('\n'.join(out))

    atomic_write(path, write)
