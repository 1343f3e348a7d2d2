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

"""The config layer: one file per system, one object per layer, and files that round-trip."""
import dataclasses

import pytest

from bellows_ros.config.actuator import load_actuator
from bellows_ros.config.segment import load_segment
from bellows_ros.errors import ParameterError
from bellows_ros.io import params as param_files
from bellows_ros.models.segment import SegmentParams


def write(path, text):
    path.write_text(text)
    return path


def test_the_segment_file_splits_into_model_plant_and_identification():
    config = load_segment()
    flat = param_files.section(param_files.load('segment'), 'segment')
    assert config.plant.valve_tau == flat['plant.valve_tau']
    assert config.plant.noise_psi_dot == flat['plant.noise.psi_dot']
    assert config.identify.input_cutoff == flat['identify.input_cutoff']
    assert config.model.ogden_mu == tuple(flat['ogden.mu'])
    model_names = {f.name for f in dataclasses.fields(SegmentParams)}
    assert not any(name.startswith(('plant', 'identify')) for name in model_names)
    # every name of the file lands in exactly one object
    assert set(config.flat()) == {f'segment.{name}' for name in flat}


@pytest.mark.parametrize('body, needle', [
    ('plant: {valve_tau: 0.0}', "'segment.plant.valve_tau' is 0, outside its physical range"),
    ('plant: {noise: {psi: -1.0}}', "'segment.plant.noise.psi' is -1, outside its physical range"),
    ('identify: {input_cutoff: -1.0}', "'segment.identify.input_cutoff' is -1, outside its "
     'physical range'),
    ('ogden: {gamma: [1.5, 6.0]}', "'segment.ogden.gamma' item 1 is 1.5, outside its physical "
     'range 2..30'),
    ('ogden: {gamma: [2.0, 6.0]}', "'segment.ogden.gamma' needs two values > 2"),
])
def test_each_part_of_the_segment_file_is_checked(tmp_path, body, needle):
    path = write(tmp_path / 'p.yaml', f'/**:\n  ros__parameters:\n    segment:\n      {body}\n')
    with pytest.raises(ParameterError, match=needle):
        load_segment(path)


def test_a_written_segment_file_reads_back_the_same(tmp_path):
    config = load_segment()
    changed = config._replace(
        model=config.model.replace(ogden_mu=(5000.0, 300.0), actuator_theta=(1.0,) * 8),
        plant=config.plant.replace(valve_tau=0.07, noise_p=1500.0))
    path = tmp_path / 'segment.yaml'
    param_files.write_file(path, changed.flat(), 'header')
    assert load_segment(path) == changed


def test_a_written_actuator_file_reads_back_the_same(tmp_path):
    config = load_actuator()
    model = dataclasses.replace(config.model, v_tube=2.0e-5, p_ref=1.05e5)
    plant = dataclasses.replace(config.plant, sensors=dataclasses.replace(
        config.plant.sensors, pressure_noise=20.0))
    path = tmp_path / 'actuator.yaml'
    param_files.write_file(path, type(config)(model, plant).flat())
    loaded = load_actuator(path)
    assert loaded.model.v_tube == model.v_tube and loaded.model.p_ref == model.p_ref
    assert loaded.plant == plant
    assert loaded.model.chamber == model.chamber and loaded.model.buckling == model.buckling
