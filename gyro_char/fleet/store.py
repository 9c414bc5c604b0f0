"""
The fleet's output directory and its resume cache.

``devices/<device>/`` holds the single command's files (and ``log.txt``, what it printed). A
device's directory is written beside its final place and renamed into it, so it is either
complete or absent. ``.fleet-cache/<device>.json`` records the outcome with its key: the
recording's path, size and mtime, the job kind and options and the gyro_char version. On a
re-run a device whose key matches (and whose files are there) is not recomputed.
"""
import hashlib
import json
import os
from pathlib import Path
import shutil
from typing import Dict, Optional
import uuid

from gyro_char.fleet.inputs import fingerprint
from gyro_char.fleet.task import package_version

CACHE_DIR = '.fleet-cache'
DEVICES_DIR = 'devices'
LOG_NAME = 'log.txt'


def cache_key(path: str, kind: str, options: Dict) -> str:
    """Key of one device's work: what would change its result."""
    blob = json.dumps({'path': str(Path(path).resolve()), 'input': fingerprint(path),
                       'kind': kind, 'options': options, 'gyro_char': package_version()},
                      sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()


class Store:
    """Reads and writes the fleet's per-device outputs under ``out``."""

    def __init__(self, out: str):
        self.out = Path(out)
        (self.out / DEVICES_DIR).mkdir(parents=True, exist_ok=True)
        (self.out / CACHE_DIR).mkdir(exist_ok=True)
        for stale in (self.out / DEVICES_DIR).glob('.*.partial'):  # left by an interrupted run
            shutil.rmtree(stale, ignore_errors=True)
        for stale in (self.out / DEVICES_DIR).glob('.*.old'):
            shutil.rmtree(stale, ignore_errors=True)

    def device_dir(self, device: str) -> Path:
        """Where a device's files go."""
        return self.out / DEVICES_DIR / device

    def _entry(self, device: str) -> Path:
        return self.out / CACHE_DIR / f'{device}.json'

    def cached(self, device: str, key: str) -> Optional[Dict]:
        """Return the recorded outcome of a device if its key matches and its files are there."""
        try:
            entry = json.loads(self._entry(device).read_text())
        except (OSError, ValueError):
            return None
        if entry.get('key') != key:
            return None
        folder = self.device_dir(device)
        if not all((folder / name).is_file() for name in entry.get('files', [])):
            return None
        return entry

    def save(self, result: Dict, key: str) -> None:
        """Write a task's files into ``devices/<device>/`` atomically, then its cache entry."""
        device = result['device']
        final = self.device_dir(device)
        stage = final.parent / f'.{device}.{uuid.uuid4().hex}.partial'
        stage.mkdir()
        files = dict(result['files'])
        files[LOG_NAME] = result['log'].encode()
        for name, data in files.items():
            (stage / name).write_bytes(data)
        self._entry(device).unlink(missing_ok=True)
        old = None
        if final.exists():
            old = final.parent / f'.{device}.{uuid.uuid4().hex}.old'
            os.replace(final, old)
        os.replace(stage, final)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        if result.get('cacheable', False):
            keep = ('device', 'status', 'message', 'measurements', 'seconds', 'cpu_seconds',
                    'peak_rss', 'pid', 'host')
            entry = {k: result[k] for k in keep}
            entry.update(key=key, files=sorted(files))
            tmp = self._entry(device).with_suffix(f'.tmp-{uuid.uuid4().hex}')
            tmp.write_text(json.dumps(entry))
            os.replace(tmp, self._entry(device))
