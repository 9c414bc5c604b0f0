"""
Launch the simulator and both characterization nodes for one IMU (real ROS 2 installs).

    ros2 launch gyro_char gyro_char.launch.py                      # the simulated bench
    ros2 launch gyro_char gyro_char.launch.py namespace:=imu0 sim:=false

``namespace`` puts the three nodes, their topics and services under ``/<namespace>`` (one
launch per IMU); the shipped parameter files use ``/**/<node>:`` keys, so they apply in any
namespace. ``sim:=false`` leaves the simulator out (a real IMU driver publishes instead).
"""
import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

NODES = ('bench_sim_node', 'swing_kf_node', 'allan_node')


def generate_launch_description():
    config = os.path.join(get_package_share_directory('gyro_char'), 'config')
    namespace = LaunchConfiguration('namespace')
    nodes = []
    for name in NODES:
        condition = IfCondition(LaunchConfiguration('sim')) if name == 'bench_sim_node' else None
        nodes.append(Node(package='gyro_char', executable=name, name=name, namespace=namespace,
                          output='screen', parameters=[os.path.join(config, name + '.yaml')],
                          condition=condition))
    return LaunchDescription([
        DeclareLaunchArgument('namespace', default_value='',
                              description='namespace of the nodes of this IMU, e.g. imu0'),
        DeclareLaunchArgument('sim', default_value='true',
                              description='also start bench_sim_node (the simulated bench)'),
        *nodes,
    ])
