"""Launch the simulator and both characterization nodes (for real ROS 2 installs)."""
import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch_ros.actions import Node


def generate_launch_description():
    config = os.path.join(get_package_share_directory('gyro_char'), 'config')
    return LaunchDescription([
        Node(package='gyro_char', executable=name, name=name, output='screen',
             parameters=[os.path.join(config, name + '.yaml')])
        for name in ('bench_sim_node', 'swing_kf_node', 'allan_node')
    ])
