"""
Offline ingest: CSV and bag reading, vectorised bag writing, stamp sanitising.

Most callers want ``gyro_char.recordings.read_imu`` / ``read_encoder`` / ``write_bag``; the
modules here hold the implementations (``csv_io``, ``bag_read``, ``bag_write``, ``cdr``,
``sanitize``).
"""
