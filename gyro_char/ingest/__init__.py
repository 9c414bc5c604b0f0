"""
Offline ingest: CSV and bag reading, vectorised bag writing, stamp sanitising.

Most callers want ``gyro_char.recordings.read_imu`` / ``read_encoder`` / ``write_bag`` /
``segments``; the modules here hold the implementations: ``read`` (dispatch), ``csv_io``,
``bag_read`` (IMU) and ``encoder_read``, ``mcap_scan`` (raw MCAP payloads), ``cdr`` /
``cdr_scalar`` / ``ros1_imu`` (vectorised decoders), ``bag_write``, ``sanitize``.
"""
