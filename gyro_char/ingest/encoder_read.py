"""
Read the stand's encoder angle from a bag: JointState position or Vector3Stamped x.

Same sources as the IMU reader (``bag_read``): payload blocks from sqlite / the MCAP scan are
decoded by ``cdr_scalar`` when a block repeats one layout, otherwise message by message with
rosbags and ``msg_adapters``; other storage goes through rosbags' ``AnyReader``.
"""
from pathlib import Path
from typing import Optional, Union

from gyro_char.ingest.bag_read import (_bag_notes, _payload_blocks, Bag, ENCODER_TYPES,
                                       reading)
from gyro_char.ingest.bag_write import typestore
from gyro_char.ingest.cdr_scalar import decode_scalar
from gyro_char.progress import progress
from gyro_char.recordings import ENCODER_CHANNEL, InputError, Recording
from msg_adapters import joint_angle, vector3_x
import numpy as np


def _fast_encoder(bag: Bag, topic: str, msgtype: str, sample, joint, quiet: bool):
    """Block-wise scalar decoding; per-message rosbags deserialisation for odd blocks."""
    store = typestore()
    ts, vs, bad, missing = [], [], 0, 0
    total = bag.total(topic)
    with progress(total=total, desc=f'reading {topic}', quiet=quiet, unit='msg') as bar:
        for buf, offsets, sizes in _payload_blocks(bag, topic):
            got = decode_scalar(buf, offsets, sizes, msgtype, joint, store, sample)
            if got is None:
                t, v = [], []
                for off, size in zip(offsets.tolist(), sizes.tolist()):
                    try:
                        one = sample(store.deserialize_cdr(buf[off:off + size].tobytes(),
                                                           msgtype))
                    except Exception:  # noqa: B902 - an undecodable message is counted
                        bad += 1
                        continue
                    if one is None:
                        missing += 1
                        continue
                    t.append(one[0])
                    v.append(one[1])
                got = np.array(t, dtype=np.float64), np.array(v, dtype=np.float64)
            ts.append(got[0])
            vs.append(got[1])
            bar.update(offsets.size)
    return ts, vs, bad, missing


def _slow_encoder(bag: Bag, topic: str, sample, quiet: bool):
    ts, vs, bad, missing = [], [], 0, 0
    for _, msg in bag.messages(topic, f'reading {topic}', quiet):
        try:
            one = None if msg is None else sample(msg)
        except (AttributeError, TypeError, ValueError):
            msg = None
        if msg is None:
            bad += 1
            continue
        if one is None:
            missing += 1
            continue
        ts.append(one[0])
        vs.append(one[1])
    return [np.array(ts, dtype=np.float64)], [np.array(vs, dtype=np.float64)], bad, missing


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
                ts, vs, bad, missing = _fast_encoder(bag, name, msgtype, sample, joint, quiet)
            else:
                ts, vs, bad, missing = _slow_encoder(bag, name, sample, quiet)
    t = np.concatenate(ts) if ts else np.empty(0)
    if t.size == 0:
        why = f'joint {joint!r} is in none of its messages' if missing else 'no decodable message'
        raise InputError(f'{path}: {name}: {why}')
    notes = _bag_notes(bag)
    if bad:
        notes.append(f'{bad} undecodable message(s) on {name} dropped')
    if missing:
        notes.append(f'{missing} message(s) on {name} without joint {joint!r} skipped')
    return Recording(t, {ENCODER_CHANNEL: np.concatenate(vs)}, source=f'{path}:{name}',
                     notes=notes)
