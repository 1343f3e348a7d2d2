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

"""
The model doctor reads a rosbag2 recording (topics: docs/interfaces.md), names a hidden effect.

The bag is written here with rosbags' own writer and the ROS 2 Jazzy type store: joint states
(`air_chamber`, `spring`), chamber pressure (`actuator`) and the spring force (wrench, frame
`actuator`), each message stamped with its sample time, as the driver node publishes them.
"""
import json

import numpy as np
import pytest
from rosbags.rosbag2 import Writer
from rosbags.typesys import get_typestore, Stores

from bellows_ros.cli import main
from bellows_ros.config.actuator import load_actuator_params, load_actuator_plant_params
from bellows_ros.models.actuator_experiments import actuator_record

PLANT = load_actuator_plant_params()

STORE = get_typestore(Stores.ROS2_JAZZY)
JOINT_STATE = 'sensor_msgs/msg/JointState'
WRENCH = 'geometry_msgs/msg/WrenchStamped'


def header(t, frame=''):
    ns = int(round(t * 1e9)) + 5 * 10 ** 9
    Time = STORE.types['builtin_interfaces/msg/Time']
    return STORE.types['std_msgs/msg/Header'](stamp=Time(sec=ns // 10 ** 9, nanosec=ns % 10 ** 9),
                                              frame_id=frame)


def joint_state(t, names, position=(), effort=()):
    return STORE.types[JOINT_STATE](header=header(t), name=list(names),
                                    position=np.array(position, float),
                                    velocity=np.array([], float),
                                    effort=np.array(effort, float))


def wrench(t, force_z):
    types = STORE.types
    vector = types['geometry_msgs/msg/Vector3']
    body = types['geometry_msgs/msg/Wrench'](force=vector(x=0.0, y=0.0, z=force_z),
                                             torque=vector(x=0.0, y=0.0, z=0.0))
    return types[WRENCH](header=header(t, 'actuator'), wrench=body)


def write_actuator_bag(path, record, every=4):
    with Writer(path, version=8) as writer:
        joints = writer.add_connection('/actuator/joint_states', JOINT_STATE, typestore=STORE)
        chambers = writer.add_connection('/actuator/chambers', JOINT_STATE, typestore=STORE)
        forces = writer.add_connection('/bellows/wrench', WRENCH, typestore=STORE)
        for k in range(0, len(record['t']), every):
            t = float(record['t'][k])
            ns = int(round(t * 1e9)) + 5 * 10 ** 9
            for connection, message, kind in (
                    (joints, joint_state(t, ('air_chamber', 'spring'),
                                         position=(record['x_c'][k], record['x_s'][k])),
                     JOINT_STATE),
                    (chambers, joint_state(t, ('actuator',), effort=(record['p'][k],)),
                     JOINT_STATE),
                    (forces, wrench(t, float(record['f'][k])), WRENCH)):
                writer.write(connection, ns, STORE.serialize_cdr(message, kind))


@pytest.mark.slow
def test_names_a_hidden_effect_from_a_rosbag2(tmp_path):
    params = load_actuator_params()
    record = actuator_record(params, PLANT, {'backlash': {'width': 4e-4}}, seed=41, duration=30.0)
    bag = tmp_path / 'recording'
    write_actuator_bag(bag, record)
    report_dir = tmp_path / 'report'
    assert main(['diagnose', 'actuator', str(bag), '--report', str(report_dir), '--quiet']) == 0
    report = json.loads((report_dir / 'report.json').read_text())
    assert report['cause'] == 'backlash'
    assert report['gain'] >= 0.30
    width = next(c for c in report['candidates'] if c['cause'] == 'backlash')['params']['width']
    assert abs(width - 4e-4) < 1.5e-4
