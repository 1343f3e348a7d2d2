# Copyright 2026 bellows_ros maintainers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""ament_python package that also installs with plain `pip install .` (no ROS needed)."""
from glob import glob

from setuptools import find_packages, setup

package_name = 'bellows_ros'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*')),
        ('share/' + package_name + '/launch', glob('launch/*.launch.py')),
        ('share/' + package_name + '/scripts', glob('scripts/*.sh')),
        ('share/' + package_name + '/requirements', glob('requirements/*.txt')),
    ],
    python_requires='>=3.10',
    install_requires=[
        'numpy>=1.24',
        'scipy>=1.10',
        'PyYAML>=6',
        'matplotlib>=3.7',
        'tqdm>=4.60',
        'pyserial>=3.5',
        'python-can>=4.3',
        'msgpack>=1.0',  # python-can's udp_multicast interface needs it
        'cantools>=39',
        'cobs>=1.2',
        'rosbags>=0.10',
        'mcap>=1.1',  # bellows reindex reads a killed recording record by record
        'threadpoolctl>=3',  # one BLAS thread for the fits (bellows_ros/identify/blas.py)
    ],
    extras_require={'test': [
        'pytest>=7', 'hypothesis>=6', 'pytest-timeout>=2',
        'pytest-xdist>=3',  # scripts/test.sh: the tests not marked realtime on every core
        # the lint tests: flake8 with ament_flake8's plugins, pydocstyle as ament_pep257 runs it
        'flake8>=6', 'flake8-builtins', 'flake8-comprehensions', 'flake8-import-order',
        'flake8-quotes', 'pydocstyle>=6',
        'coverage>=7.10',  # scripts/coverage.sh: `patch = subprocess` follows the xdist workers
    ]},
    zip_safe=True,
    maintainer='bellows_ros maintainers',
    maintainer_email='maintainers@bellows-ros.invalid',
    description='Pneumatic bellows models, identification, model doctor and ROS 2 nodes',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'bellows = bellows_ros.cli:main',
            'driver_node = bellows_ros.nodes.driver_node:main',
            'model_node = bellows_ros.nodes.model_node:main',
            'stiffness_controller_node = bellows_ros.nodes.stiffness_controller_node:main',
            'arm_controller_node = bellows_ros.nodes.arm_controller_node:main',
            'sim_arm_node = bellows_ros.nodes.sim_arm_node:main',
            'sim_actuator_node = bellows_ros.nodes.sim_actuator_node:main',
            'scenario_node = bellows_ros.nodes.scenario_node:main',
            'arm_graph = bellows_ros.nodes.arm_graph:main',
        ],
    },
)
