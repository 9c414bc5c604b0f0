"""gyro_char: gyro/IMU characterization core (numpy/scipy only; no rclpy in the core)."""

__version__ = '0.1.0'
