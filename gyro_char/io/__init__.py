# noqa: A005  (the package I/O layer; absolute imports keep the standard io module reachable)
"""
Offline input and output: CSV, ROS 2 bags (sqlite3, mcap), ROS 1 bags, and the bag writer.

``read_imu`` / ``read_encoder`` read any supported input into a ``Recording`` with every stamp
treatment counted in its ``notes``; ``write_bag`` writes a ROS 2 bag; ``segments`` splits a
recording at its gaps. The modules hold the implementations: ``read`` (dispatch), ``csv_io``,
``bag_read`` (IMU) and ``encoder_read``, ``mcap_scan`` (raw MCAP payloads), ``cdr`` /
``cdr_scalar`` / ``ros1_imu`` (vectorised decoders), ``bag_write``, ``typestore``, ``sanitize``.
"""
from gyro_char.io.bag_write import write_bag
from gyro_char.io.read import read_encoder, read_imu
from gyro_char.io.sanitize import segments

__all__ = ['read_encoder', 'read_imu', 'segments', 'write_bag']
