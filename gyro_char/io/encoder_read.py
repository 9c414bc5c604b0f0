"""
Read the stand's encoder angle from a bag: JointState position or Vector3Stamped x.

Same sources as the IMU reader (``bag_read``): payload blocks from sqlite / the MCAP scan are
decoded by ``cdr_scalar`` when a block repeats one layout, otherwise message by message with
rosbags and ``msg_adapters``; other storage goes through rosbags' ``AnyReader``.
"""
from pathlib import Path
from typing import Any, Callable, List, Optional, Union

from gyro_char.errors import InputError
from gyro_char.io.bag_read import (Bag, bag_notes, ENCODER_TYPES,
                                   payload_blocks, reading)
from gyro_char.io.cdr_scalar import decode_scalar
from gyro_char.io.typestore import typestore
from gyro_char.progress import progress
from gyro_char.records import ENCODER_CHANNEL, Recording
from msg_adapters import joint_angle, vector3_x
import numpy as np


class _Samples:
    """
    Encoder samples and drop counts, with the one per-message rule of both paths (``take``).

    A message is *undecodable* (counted in ``bad``) when it cannot be deserialised or the
    adapter cannot read a finite-stamped (stamp, value) pair of floats from it, whatever it
    raises (wrong field types, short arrays, garbage bytes); it is *missing* the joint when
    the adapter returns None (no such name or index). A NaN position is kept as a sample: it
    is a reading, and ``sanitize`` drops and counts non-finite samples like the IMU's.
    """

    def __init__(self, sample: Callable) -> None:
        self.sample = sample
        self.ts: List[np.ndarray] = []
        self.vs: List[np.ndarray] = []
        self.bad = 0
        self.missing = 0
        self._t: List[float] = []
        self._v: List[float] = []

    def take(self, raw: Any, decode: Optional[Callable] = None) -> None:
        """Judge one message: ``decode(raw)``, or ``raw`` itself when already deserialised."""
        try:
            msg = raw if decode is None else decode(raw)
            one = None if msg is None else self.sample(msg)
            if one is not None:
                t, v = float(one[0]), float(one[1])
                if not np.isfinite(t):
                    raise ValueError('non-finite stamp')
        except Exception:  # noqa: B902 - whatever a malformed message raises, it is counted
            self.bad += 1
            return
        if msg is None:
            self.bad += 1
        elif one is None:
            self.missing += 1
        else:
            self._t.append(t)
            self._v.append(v)

    def flush(self) -> None:
        """Close the per-message run: its samples become one block, in stream order."""
        if self._t:
            self.ts.append(np.array(self._t, dtype=np.float64))
            self.vs.append(np.array(self._v, dtype=np.float64))
            self._t, self._v = [], []

    def add_block(self, t: np.ndarray, v: np.ndarray) -> None:
        self.flush()
        self.ts.append(t)
        self.vs.append(v)


def _fast_encoder(bag: Bag, topic: str, msgtype: str, sample, joint, quiet: bool) -> _Samples:
    """Block-wise scalar decoding; per-message rosbags deserialisation for odd blocks."""
    store = typestore()
    out = _Samples(sample)
    total = bag.total(topic)

    def decode(raw: bytes):
        return store.deserialize_cdr(raw, msgtype)

    with progress(total=total, desc=f'reading {topic}', quiet=quiet, unit='msg') as bar:
        for buf, offsets, sizes in payload_blocks(bag, topic):
            got = decode_scalar(buf, offsets, sizes, msgtype, joint, store, sample)
            if got is None:
                for off, size in zip(offsets.tolist(), sizes.tolist()):
                    out.take(buf[off:off + size].tobytes(), decode)
            else:
                out.add_block(*got)
            bar.update(offsets.size)
    out.flush()
    return out


def _slow_encoder(bag: Bag, topic: str, sample, quiet: bool) -> _Samples:
    out = _Samples(sample)
    for _, msg in bag.messages(topic, f'reading {topic}', quiet):
        out.take(msg)  # None: rosbags could not deserialise it
    out.flush()
    return out


def read_encoder_bag(path: Path, topic: Optional[str] = None,
                     joint: Union[str, int, None] = None, quiet: bool = False,
                     fast: bool = True) -> Recording:
    """Read the encoder angle from JointState (joint by name or index) or Vector3Stamped x."""
    with Bag(path) as bag:
        name = bag.pick(topic, ENCODER_TYPES, 'encoder (JointState / Vector3Stamped)')
        msgtype = bag.topics()[name][0]
        if msgtype == ENCODER_TYPES[0]:
            def sample(msg):
                return joint_angle(msg, 0 if joint is None else joint)
        else:
            sample = vector3_x
        with reading(path, name):
            if fast and bag.storage() in ('sqlite3', 'mcap'):
                got = _fast_encoder(bag, name, msgtype, sample, joint, quiet)
            else:
                got = _slow_encoder(bag, name, sample, quiet)
    bad, missing = got.bad, got.missing
    t = np.concatenate(got.ts) if got.ts else np.empty(0)
    if t.size == 0:
        why = f'joint {joint!r} is in none of its messages' if missing else 'no decodable message'
        raise InputError(f'{path}: {name}: {why}')
    notes = bag_notes(bag)
    if bad:
        notes.append(f'{bad} undecodable message(s) on {name} dropped')
    if missing:
        notes.append(f'{missing} message(s) on {name} without joint {joint!r} skipped')
    return Recording(t, {ENCODER_CHANNEL: np.concatenate(got.vs)}, source=f'{path}:{name}',
                     notes=notes)
