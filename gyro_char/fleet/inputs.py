"""
The fleet's inputs: which recordings, of which device, analysed by which command.

An INPUT is a directory (searched recursively for ROS 2 bag directories, ``.mcap``, ``.bag``,
``.csv`` and ``.csv.gz``), a recording, or a manifest CSV with the header
``device,path,kind[,period_s,axis]`` (paths relative to the manifest). A device is named by the
manifest, else by the file's stem or the bag directory's name; names that collide are told
apart by their parent directories.
"""
import csv
from dataclasses import dataclass, field
import os
from pathlib import Path
import re
from typing import Dict, List, Optional, Sequence

from gyro_char.errors import InputError

KINDS = ('allan', 'swing', 'diagnose')
MANIFEST_COLUMNS = ('device', 'path', 'kind', 'period_s', 'axis')
_SUFFIXES = ('.csv.gz', '.csv', '.mcap', '.bag')


@dataclass
class Device:
    """One recording of one device and the command that analyses it."""

    device: str
    path: str
    kind: str
    overrides: Dict[str, object] = field(default_factory=dict)  # per-device options


def is_bag_dir(path: Path) -> bool:
    """Return True for a ROS 2 bag directory (it holds ``metadata.yaml``)."""
    return path.is_dir() and (path / 'metadata.yaml').is_file()


def is_manifest(path: Path) -> bool:
    """Return True when ``path`` is a CSV whose header starts with ``device,path``."""
    if not path.is_file() or not path.name.lower().endswith('.csv'):
        return False
    with open(path, newline='', errors='replace') as fh:
        head = fh.readline().strip().lower().replace(' ', '')
    return head.startswith('device,path')


def _recording_suffix(name: str) -> Optional[str]:
    low = name.lower()
    return next((s for s in _SUFFIXES if low.endswith(s)), None)


def _stem(path: Path) -> str:
    suffix = _recording_suffix(path.name) if path.is_file() else None
    return path.name[:-len(suffix)] if suffix else path.name


def _walk(root: Path) -> List[Path]:
    """Find the recordings under ``root`` (bag directories not entered, manifests skipped)."""
    found = []
    for dirpath, dirnames, filenames in os.walk(root, followlinks=True):
        here = Path(dirpath)
        if is_bag_dir(here):
            found.append(here)
            dirnames[:] = []
            continue
        dirnames.sort()
        for name in sorted(filenames):
            p = here / name
            if _recording_suffix(name) and not is_manifest(p):
                found.append(p)
    return found


def read_manifest(path: Path, default_kind: str) -> List[Device]:
    """Devices of a manifest CSV (``device,path,kind[,period_s,axis]``)."""
    base = path.resolve().parent
    with open(path, newline='') as fh:
        rows = list(csv.DictReader(fh))
    devices = []
    for i, row in enumerate(rows, start=2):
        row = {(k or '').strip().lower(): (v or '').strip() for k, v in row.items()}
        extra = sorted(set(row) - set(MANIFEST_COLUMNS))
        if extra:
            raise InputError(f'{path}: unknown manifest column(s) {extra}; '
                             f'columns are {",".join(MANIFEST_COLUMNS)}')
        if not row.get('device') or not row.get('path'):
            raise InputError(f'{path}:{i}: device and path are required')
        kind = row.get('kind') or default_kind
        if kind not in KINDS:
            raise InputError(f'{path}:{i}: kind {kind!r} is not one of {", ".join(KINDS)}')
        overrides = {}
        if row.get('period_s'):
            try:
                period = float(row['period_s'])
            except ValueError:
                period = float('nan')
            if not 0 < period < float('inf'):
                raise InputError(f'{path}:{i}: period_s must be positive seconds, '
                                 f'got {row["period_s"]!r}')
            overrides['period'] = period
        if row.get('axis'):
            if row['axis'] not in ('x', 'y', 'z'):
                raise InputError(f'{path}:{i}: axis must be x, y or z, got {row["axis"]!r}')
            overrides['axis'] = row['axis']
        target = Path(row['path'])
        target = target if target.is_absolute() else base / target
        devices.append(Device(safe_name(row['device']), str(target), kind, overrides))
    return devices


def safe_name(name: str) -> str:
    """Return a device name usable as a directory name (odd characters -> _)."""
    clean = re.sub(r'[^A-Za-z0-9._+-]+', '_', name.strip()).strip('._')
    if not clean:
        raise InputError(f'device name {name!r} has no usable character')
    return clean


def _name_apart(paths: Sequence[Path]) -> List[str]:
    """Stems, prefixed by as many parent directories as it takes to make them unique."""
    names = [_stem(p) for p in paths]
    depth = 0
    while len(set(names)) < len(names) and depth < 64:
        depth += 1
        counts = {}
        for n in names:
            counts[n] = counts.get(n, 0) + 1
        for i, p in enumerate(paths):
            if counts[names[i]] > 1:
                parents = [q.name for q in list(p.parents)[:depth] if q.name][::-1]
                names[i] = '_'.join(parents + [_stem(p)])
    return [safe_name(n) for n in names]


def discover(inputs: Sequence[str], default_kind: str) -> List[Device]:
    """
    Return every device of the fleet, in input order.

    Raises
    ------
    InputError
        On a missing input, a bad manifest, a directory without recordings, or two devices of
        one name.

    """
    named: List[Device] = []
    loose: List[Path] = []
    for item in inputs:
        p = Path(item)
        if not p.exists():
            raise InputError(f'{item}: no such file or directory')
        if is_manifest(p):
            named.extend(read_manifest(p, default_kind))
        elif p.is_dir() and not is_bag_dir(p):
            found = _walk(p)
            if not found:
                raise InputError(f'{item}: no recording found (bag directories, .mcap, .bag, '
                                 '.csv, .csv.gz)')
            loose.extend(found)
        else:
            loose.append(p)
    unique, seen = [], set()
    for q in loose:  # the same recording twice (e.g. a file and its directory) counts once
        if str(q.resolve()) not in seen:
            seen.add(str(q.resolve()))
            unique.append(q)
    devices = named + [Device(n, str(q), default_kind)
                       for n, q in zip(_name_apart(unique), unique)]
    names = [d.device for d in devices]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise InputError(f'two recordings for device(s) {dup}; name them in a manifest '
                         f'({",".join(MANIFEST_COLUMNS)})')
    return devices


def fingerprint(path: str) -> Dict[str, int]:
    """Size and newest mtime of a recording (a bag directory: over its files)."""
    p = Path(path)
    if not p.exists():
        return {'size': -1, 'mtime_ns': -1}
    if p.is_dir():
        size, mtime = 0, p.stat().st_mtime_ns
        for dirpath, _, filenames in os.walk(p):
            for name in filenames:
                st = (Path(dirpath) / name).stat()
                size, mtime = size + st.st_size, max(mtime, st.st_mtime_ns)
        return {'size': size, 'mtime_ns': mtime}
    st = p.stat()
    return {'size': st.st_size, 'mtime_ns': st.st_mtime_ns}
