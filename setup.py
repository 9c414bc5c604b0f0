"""
ament_python packaging for gyro_char.

Runtime requirements are the numeric stack only: on a real ROS 2 Jazzy install rclpy and the
message packages come from apt (see package.xml); the PyPI ROS wheels live in
requirements-dev.txt for the no-ROS development path.
"""
from glob import glob

from setuptools import find_packages, setup

PACKAGE = 'gyro_char'

NODES = ['swing_kf_node', 'allan_node', 'bench_sim_node']

setup(
    name=PACKAGE,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*', 'bench', 'bench.*']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + PACKAGE]),
        ('share/' + PACKAGE, ['package.xml']),
        ('share/' + PACKAGE + '/config', glob('config/*.yaml')),
        ('share/' + PACKAGE + '/launch', glob('launch/*.launch.py')),
    ],
    install_requires=[
        'setuptools',
        'numpy>=1.24',
        'scipy>=1.10',
        'matplotlib>=3.6',
        'pyyaml>=6',
        'tqdm>=4.60',
        'rosbags>=0.10',
        'filterpy>=1.4',
        'numba>=0.59',
        'threadpoolctl>=3.1',
    ],
    zip_safe=True,
    maintainer='gyro_char developers',
    maintainer_email='gyro-char@example.com',
    description='Gyro/IMU characterization: swing-stand Kalman filter and Allan variance.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            f'{node} = {PACKAGE}.nodes.entry:{node}' for node in NODES
        ] + [
            f'gyro-char = {PACKAGE}.cli:main',
        ],
    },
)
