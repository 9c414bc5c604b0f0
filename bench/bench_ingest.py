"""
Ingest speed: the vectorised raw-CDR reader against plain rosbags, in the same run.

Writes bags into a temporary directory (never the repository) and measures messages/s of

- the fast path (``read_imu_bag``: stamps + 6 channels, not yet sanitised), whole bag;
- rosbags per-message (``AnyReader.messages`` on the Imu topic + ``deserialize`` +
  ``msg_adapters.imu_sample``), timed on the first ``--subset`` Imu messages and extrapolated
  (stated in the output);

checks that both give the same stamps and values bit for bit on that subset, and prints the ratio
of wall-clock rates and of CPU-time rates (the box is shared: CPU time is the steadier figure).
In the ``mixed`` and ``three`` cases the encoder topic is measured the same way
(``read_encoder_bag`` against rosbags + ``msg_adapters.joint_angle``).
Cases:

- ``imu``: N sensor_msgs/Imu messages (default 3.6 M: 3 h at 333 Hz) written with
  ``gyro_char.io.write_bag``, sqlite3 and mcap: one record size per MCAP chunk;
- ``mixed``: N/4 Imu + N/4 JointState merged by stamp (``write_bag`` with an encoder), mcap:
  every chunk mixes two record sizes, as ``ros2 bag record`` logs several topics;
- ``noindex``: the ``mixed`` bag with its message index records made private records (as from
  a writer that omits them): the reader's byte-scan fallback;
- ``three``: N/12 Imu + N/12 JointState + N/120 std_msgs/String of varying length, written
  message by message by rosbags' own MCAP writer (its chunk layout and message index).

Usage: ``python bench/bench_ingest.py [--n 3600000] [--subset 300000]
[--cases imu,mixed,noindex,three] [--keep DIR]``.
"""
import argparse
from itertools import islice
import mmap
from pathlib import Path
import shutil
import struct
import sys
import tempfile
import time

from gyro_char.io import write_bag
from gyro_char.io.bag_read import read_imu_bag
from gyro_char.io.bag_write import IMU_TYPE, joint_state_encoder, JOINT_TYPE, stamps_ns
from gyro_char.io.cdr import encode_imu
from gyro_char.io.encoder_read import read_encoder_bag
from gyro_char.io.sanitize import sanitize
from gyro_char.io.typestore import typestore
from gyro_char.records import ENCODER_CHANNEL, IMU_CHANNELS, Recording
from msg_adapters import imu_sample, joint_angle
import numpy as np
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import StoragePlugin, Writer

IMU_TOPIC = '/imu/data_raw'
ENCODER_TOPIC = '/stand/joint_states'


def make_recording(n: int, rate: float = 333.0, seed: int = 1) -> Recording:
    rng = np.random.default_rng(seed)
    t = 1.7e9 + np.arange(n) / rate + rng.uniform(0, 2e-5, n)
    scale = {'gyro': 1e-3, 'accel': 1e-2}
    ch = {k: rng.normal(scale=scale[k.split('_')[0]], size=n) for k in IMU_CHANNELS}
    ch['accel_z'] += 9.80665
    return Recording(t, ch)


def make_encoder(n: int, rate: float = 333.0, seed: int = 2) -> Recording:
    rng = np.random.default_rng(seed)
    t = 1.7e9 + np.arange(n) / rate + rng.uniform(0, 2e-5, n)
    return Recording(t, {ENCODER_CHANNEL: np.sin(np.arange(n) / 200.0)})


def write_three(path: Path, n: int) -> None:
    """Imu + JointState + std_msgs/String (1/10 the rate, 0..99 chars), rosbags' writer."""
    store = typestore()
    imu, enc = make_recording(n), make_encoder(n)
    imu_raw = encode_imu(imu.t, [imu.channels[k] for k in IMU_CHANNELS[:3]],
                         [imu.channels[k] for k in IMU_CHANNELS[3:]], frame_id='imu_link')
    enc_raw = joint_state_encoder(store, 'stand_joint')(enc.t, enc.channels[ENCODER_CHANNEL])
    t_str = 1.7e9 + np.arange(n // 10) / 33.3 + 1e-4
    text = store.types['std_msgs/msg/String']
    strs = [bytes(store.serialize_cdr(text(data='x' * (k % 100)), 'std_msgs/msg/String'))
            for k in range(t_str.size)]
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conns = [writer.add_connection(name, kind, typestore=store) for name, kind in
                 ((IMU_TOPIC, IMU_TYPE), (ENCODER_TOPIC, JOINT_TYPE),
                  ('/diagnostics_text', 'std_msgs/msg/String'))]
        stamps = [stamps_ns(imu.t), stamps_ns(enc.t), stamps_ns(t_str)]
        rows = [imu_raw, enc_raw, strs]
        topic = np.concatenate([np.full(s.size, k) for k, s in enumerate(stamps)])
        order = np.argsort(np.concatenate(stamps), kind='stable')
        index = np.concatenate([np.arange(s.size) for s in stamps])
        for k, i in zip(topic[order].tolist(), index[order].tolist()):
            writer.write(conns[k], int(stamps[k][i]), bytes(rows[k][i]))


def write_mixed(path: Path, n: int, hide_index: bool = False) -> None:
    """Imu + JointState merged by stamp (``write_bag``), optionally without message index."""
    write_bag(str(path), make_recording(n), make_encoder(n), storage='mcap')
    if hide_index and hide_message_index(path) == 0:
        raise RuntimeError(f'{path}: no message index records to hide')


def hide_message_index(path: Path) -> int:
    """Turn the message index records (0x07) of the bag's MCAP into private records (0x80)."""
    hidden = 0
    with open(next(path.glob('*.mcap')), 'r+b') as fh, mmap.mmap(fh.fileno(), 0) as mm:
        pos = 8
        while pos + 9 <= len(mm) and mm[pos] != 0x0F:  # up to the data end record
            if mm[pos] == 0x07:
                mm[pos] = 0x80
                hidden += 1
            pos += 9 + struct.unpack_from('<Q', mm, pos + 1)[0]
    return hidden


def _imu_fast(path: Path):
    rec = read_imu_bag(path, topic=IMU_TOPIC, quiet=True)
    return rec, [rec.channels[k] for k in IMU_CHANNELS]


def _encoder_fast(path: Path):
    rec = read_encoder_bag(path, topic=ENCODER_TOPIC, quiet=True)
    return rec, [rec.channels[ENCODER_CHANNEL]]


# what -> (topic, message name, fast reader, per-message adapter: msg -> (stamp, [values]))
READERS = {
    'imu': (IMU_TOPIC, 'Imu', _imu_fast, imu_sample),
    'encoder': (ENCODER_TOPIC, 'JointState', _encoder_fast,
                lambda msg: (lambda s_v: (s_v[0], [s_v[1]]))(joint_angle(msg, 0))),
}


def rosbags_per_message(path: Path, count: int, what: str):
    """Return (wall s, CPU s, stamps, values) for the first ``count`` messages of ``what``."""
    topic, _, _, sample = READERS[what]
    start, cpu = time.perf_counter(), time.process_time()
    ts, rows = [], []
    with AnyReader([path], default_typestore=typestore()) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        for conn, _, raw in islice(reader.messages(connections=conns), count):
            stamp, values = sample(reader.deserialize(raw, conn.msgtype))
            ts.append(stamp)
            rows.append(values)
    return (time.perf_counter() - start, time.process_time() - cpu, np.array(ts),
            np.array(rows))


def measure(label: str, path: Path, n: int, subset: int, t_write: float,
            what: str = 'imu') -> bool:
    """Time both readers on one topic of ``path`` (``n`` messages); print one line."""
    _, name, fast_read, _ = READERS[what]
    size = sum(f.stat().st_size for f in path.iterdir())
    t0, c0 = time.perf_counter(), time.process_time()
    fast, columns = fast_read(path)
    t_fast, c_fast = time.perf_counter() - t0, time.process_time() - c0
    extra = ''
    if what == 'imu':
        t0 = time.perf_counter()
        sanitize(fast)
        extra = f' (+ sanitize {time.perf_counter() - t0:.2f} s)'
    m = min(subset, n)
    t_slow, c_slow, ts, rows = rosbags_per_message(path, m, what)
    same = (np.array_equal(ts.view(np.int64), fast.t[:m].view(np.int64)) and all(
        np.array_equal(rows[:, i].view(np.int64), col[:m].view(np.int64))
        for i, col in enumerate(columns)))
    fast_rate, slow_rate = n / t_fast, m / t_slow
    print(f'[{label}] write {t_write:.2f} s ({size / 1e6:.0f} MB) | fast read {t_fast:.2f} s '
          f'= {fast_rate / 1e6:.2f} M {name} msg/s{extra} | rosbags per-message '
          f'{slow_rate / 1e6:.3f} M msg/s (timed on the first {m} {name} messages, '
          f'extrapolated to {n / slow_rate:.1f} s for all) | speed-up '
          f'{fast_rate / slow_rate:.1f}x wall, {(n / c_fast) / (m / c_slow):.1f}x CPU time '
          f'({c_fast:.2f} s CPU for all vs {c_slow:.2f} s for {m}) | bit-for-bit equal on '
          f'those {m}: {same}')
    return same and len(fast) == n


def bench(n: int, subset: int, workdir: Path, cases) -> bool:
    ok = True
    print(f'N = {n}, bags in {workdir}')
    jobs = []
    if 'imu' in cases:
        rec = make_recording(n)
        jobs += [(f'imu {s}', n, lambda p, s=s: write_bag(str(p), rec, storage=s), ('imu',))
                 for s in ('sqlite3', 'mcap')]
    if 'mixed' in cases:
        jobs.append(('mixed imu+joint_states mcap', n // 4, lambda p: write_mixed(p, n // 4),
                     ('imu', 'encoder')))
    if 'noindex' in cases:
        jobs.append(('mixed, message index hidden: scan', n // 4,
                     lambda p: write_mixed(p, n // 4, hide_index=True), ('imu',)))
    if 'three' in cases:
        jobs.append(('three topics, rosbags writer, mcap', n // 12,
                     lambda p: write_three(p, n // 12), ('imu', 'encoder')))
    for k, (label, count, write, whats) in enumerate(jobs):
        path = workdir / f'bag_{k}'
        t0 = time.perf_counter()
        write(path)
        t_write = time.perf_counter() - t0
        for what in whats:
            ok &= measure(label if what == 'imu' else f'{label}, encoder', path, count, subset,
                          t_write, what)
        shutil.rmtree(path)
    return ok


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--n', type=int, default=3_600_000,
                        help='messages (default 3 h x 333 Hz); see the cases for each size')
    parser.add_argument('--subset', type=int, default=300_000,
                        help='messages timed through rosbags per-message deserialization')
    parser.add_argument('--cases', default='imu,mixed,noindex,three',
                        help='comma-separated: imu, mixed, noindex, three')
    parser.add_argument('--keep', default=None, help='work in this directory (not deleted)')
    args = parser.parse_args(argv)
    cases = set(args.cases.split(','))
    if args.keep:
        Path(args.keep).mkdir(parents=True, exist_ok=True)
        return 0 if bench(args.n, args.subset, Path(args.keep), cases) else 1
    with tempfile.TemporaryDirectory(prefix='bench_ingest_') as tmp:
        return 0 if bench(args.n, args.subset, Path(tmp), cases) else 1


if __name__ == '__main__':
    sys.exit(main())
