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

The bag is written here with rosbags' own writer and the ROS 2 Jazzy type store (bag_messages):
one `/actuator/joint_states` message per sample, compressions (`air_chamber`, `spring`), the
spring force (`spring`'s effort) and the chamber pressure (`actuator`'s effort), stamped with its
sample time, as the driver node publishes them.
"""
import json

from bag_messages import write_actuator_bag as write_rows
import pytest

from bellows_ros.cli import main
from bellows_ros.config.actuator import load_actuator_params, load_actuator_plant_params
from bellows_ros.papers.actuator_experiments import actuator_record

PLANT = load_actuator_plant_params()


def write_actuator_bag(path, record, every=4):
    """Write every `every`-th sample of `record` (t from 5 s on) as an actuator bag."""
    rows = [(int(round(float(record['t'][k]) * 1e9)) + 5 * 10 ** 9,
             *(float(record[name][k]) for name in ('x_c', 'x_s', 'p', 'f')))
            for k in range(0, len(record['t']), every)]
    return write_rows(path, rows)


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
