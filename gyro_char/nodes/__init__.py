"""Thin rclpy glue around the core; the only place in gyro_char that imports rclpy."""
