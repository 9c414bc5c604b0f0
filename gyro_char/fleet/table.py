"""
The fleet's tidy table: one row per device x channel x quantity (docs/design.md section 4).

Columns ``device, path, kind, status, message, channel, quantity, value, si_unit, lo68, hi68``
(+ ``pass`` with a spec). A device in error is one row with ``status=error`` and the reason in
``message``. Written as ``fleet.csv`` (floats in round-trip form) and ``fleet.parquet``; also
the robust z of every value against the fleet, which the report uses to put outliers first.
"""
import csv
import math
from typing import Dict, List, Optional, Sequence

from gyro_char.jobs.base import is_upper_bound
from gyro_char.report.atomic import atomic_write
from gyro_char.robust import robust_sd
import numpy as np

COLUMNS = ('device', 'path', 'kind', 'status', 'message', 'channel', 'quantity', 'value',
           'si_unit', 'lo68', 'hi68')
VERDICT_COLUMNS = ('device', 'verdict', 'reasons')
OUTLIER_Z = 3.5  # |robust z| above which a value is an outlier (Iglewicz and Hoaglin)


def device_rows(device: str, path: str, kind: str, status: str, message: str,
                measurements: Sequence[dict]) -> List[dict]:
    """Tidy rows of one device: its measurements, or one error row."""
    if status != 'ok':
        return [{'device': device, 'path': path, 'kind': kind, 'status': 'error',
                 'message': message, 'channel': '', 'quantity': '', 'value': math.nan,
                 'si_unit': '', 'lo68': math.nan, 'hi68': math.nan}]
    return [{'device': device, 'path': path, 'kind': kind, 'status': 'ok',
             'message': m.get('message', ''), 'channel': m['channel'],
             'quantity': m['quantity'], 'value': float(m['value']), 'si_unit': m['si_unit'],
             'lo68': _float(m.get('lo68')), 'hi68': _float(m.get('hi68'))}
            for m in measurements]


def _float(v) -> float:
    return math.nan if v is None else float(v)


def _cell(v) -> str:
    if v is None:
        return ''
    if isinstance(v, bool):
        return 'true' if v else 'false'
    if isinstance(v, float):
        return '' if math.isnan(v) else repr(v)
    return str(v)


def write_csv(path: str, rows: List[dict], columns: Sequence[str]) -> None:
    """CSV with floats written by ``repr`` (read back bit for bit), NaN / None as empty."""
    def write(tmp):
        with open(tmp, 'w', newline='') as fh:
            w = csv.writer(fh)
            w.writerow(columns)
            for r in rows:
                w.writerow([_cell(r.get(c)) for c in columns])
    atomic_write(path, write)


def write_parquet(path: str, rows: List[dict], columns: Sequence[str]) -> None:
    """Parquet with typed columns: floats as float64 (NaN = missing), ``pass`` nullable bool."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    floats = {'value', 'lo68', 'hi68'}
    arrays = {}
    for c in columns:
        values = [r.get(c) for r in rows]
        if c in floats:
            arrays[c] = pa.array([math.nan if v is None else float(v) for v in values],
                                 type=pa.float64())
        elif c == 'pass':
            arrays[c] = pa.array(values, type=pa.bool_())
        else:
            arrays[c] = pa.array(['' if v is None else str(v) for v in values],
                                 type=pa.string())
    atomic_write(path, lambda tmp: pq.write_table(pa.table(arrays), tmp))


def robust_z(rows: List[dict]) -> List[Optional[float]]:
    """
    Robust z of each ok row against the same kind x channel x quantity over the fleet.

    z = (x - median) / (1.4826 MAD), on log10 of the values when they are all positive (noise
    terms spread by factors, not by offsets). None for error rows, for upper bounds (an
    unresolved term says nothing about the device) and for groups of fewer than three devices
    or no spread (MAD = 0), where no outlier can be told.
    """
    groups: Dict[tuple, List[int]] = {}
    for i, r in enumerate(rows):
        if r['status'] == 'ok' and math.isfinite(r['value']) and not is_upper_bound(r):
            groups.setdefault((r['kind'], r['channel'], r['quantity']), []).append(i)
    z: List[Optional[float]] = [None] * len(rows)
    for idx in groups.values():
        x = np.array([rows[i]['value'] for i in idx])
        if len(x) < 3:
            continue
        if np.all(x > 0):
            x = np.log10(x)
        med = float(np.median(x))
        mad = float(robust_sd(x))
        if not mad > 0:
            continue
        for i, v in zip(idx, x):
            z[i] = float((v - med) / mad)
    return z


_RANK = {'fail': 0, 'error': 1, 'outlier': 2, 'pass': 3, 'ok': 3}


def device_summaries(rows: List[dict], z: List[Optional[float]],
                     verdicts: Optional[List[dict]]) -> List[dict]:
    """
    Return one summary per device, in the report's order.

    Failing the spec first, then in error, then outlying (largest |robust z| first), then the
    rest by name.
    """
    by_device: Dict[str, dict] = {}
    for r, zi in zip(rows, z):
        d = by_device.setdefault(r['device'], {'device': r['device'], 'kind': r['kind'],
                                               'status': r['status'], 'reasons': r['message'],
                                               'zmax': 0.0, 'zwhere': ''})
        if zi is not None and abs(zi) > abs(d['zmax']):
            d['zmax'], d['zwhere'] = zi, f'{r["channel"]} {r["quantity"]}'
    for v in verdicts or []:
        by_device[v['device']].update(verdict=v['verdict'], reasons=v['reasons'])
    for d in by_device.values():
        if d.get('verdict') == 'fail':
            d['state'] = 'fail'
        elif d['status'] != 'ok':
            d['state'] = 'error'
        elif abs(d['zmax']) > OUTLIER_Z:
            d['state'] = 'outlier'
        else:
            d['state'] = d.get('verdict', 'ok')
        if d['state'] in ('outlier', 'pass', 'ok'):
            d['reasons'] = ''
    return sorted(by_device.values(),
                  key=lambda d: (_RANK[d['state']], -abs(d['zmax']), d['device']))
