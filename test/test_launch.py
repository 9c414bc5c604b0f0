"""
The shipped launch file and what it needs at run time.

``package.xml`` must declare what the launch file imports (``launch``, ``launch_ros``,
``ament_index_python``), so that rosdep installs it. The launch description itself needs
``launch_ros``, which has no PyPI wheel: that test is skipped where it cannot be imported (as in
this repository's PyPI development environment) and runs on a ROS 2 install.
"""
import ast
import importlib.util
import xml.etree.ElementTree as ElementTree

from node_harness import ROOT
import pytest

LAUNCH = ROOT / 'launch' / 'gyro_char.launch.py'
NODES = {'bench_sim_node', 'swing_kf_node', 'allan_node'}


def _imported_packages(path) -> set:
    tree = ast.parse(path.read_text())
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module.split('.')[0])
        elif isinstance(node, ast.Import):
            names.update(a.name.split('.')[0] for a in node.names)
    return names


def test_package_xml_declares_what_the_launch_file_imports():
    declared = {e.text for e in ElementTree.parse(ROOT / 'package.xml').getroot()
                if e.tag in ('exec_depend', 'depend')}
    needed = _imported_packages(LAUNCH) - {'os'}
    assert needed == {'ament_index_python', 'launch', 'launch_ros'}
    assert needed <= declared, needed - declared
    # Each node launched with its shipped parameter file.
    assert all((ROOT / 'config' / f'{name}.yaml').is_file() for name in NODES)
    assert "os.path.join(config, name + '.yaml')" in LAUNCH.read_text()


def test_launch_description(tmp_path, monkeypatch):
    pytest.importorskip('launch_ros', reason='launch_ros is not importable here (it has no PyPI '
                        'wheel; install ros-jazzy-launch-ros to run this test)')
    from launch import LaunchDescription
    from launch.actions import DeclareLaunchArgument
    from launch_ros.actions import Node
    # An ament prefix holding this package's share directory (as colcon installs it).
    share = tmp_path / 'share'
    (share / 'ament_index' / 'resource_index' / 'packages').mkdir(parents=True)
    (share / 'ament_index' / 'resource_index' / 'packages' / 'gyro_char').write_text('')
    (share / 'gyro_char').mkdir()
    (share / 'gyro_char' / 'config').symlink_to(ROOT / 'config')
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(tmp_path))
    spec = importlib.util.spec_from_file_location('gyro_char_launch', LAUNCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    description = module.generate_launch_description()
    assert isinstance(description, LaunchDescription)
    arguments = {e.name for e in description.entities if isinstance(e, DeclareLaunchArgument)}
    assert arguments == {'namespace', 'sim'}
    nodes = [e for e in description.entities if isinstance(e, Node)]
    assert {n.node_executable for n in nodes} == NODES
    assert all(n.node_package == 'gyro_char' for n in nodes)
