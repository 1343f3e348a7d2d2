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
The drivers' configuration (config/hardware.py): config/hardware.yaml -> the drivers' objects.

Built from the YAML alone (no physics object), the shared limits read from their one home
(the chamber's travel of config/actuator.yaml, p0 and p_max of config/segment.yaml), and every
unusable value refused in one line naming the file and the parameter.
"""
import pytest

from bellows_ros.config.actuator import load_actuator
from bellows_ros.config.hardware import (actuator_board_config, arm_bus_config, drive_from_flat,
                                         load_drive, vent_pressure)
from bellows_ros.config.segment import load_segment
from bellows_ros.errors import ParameterError
from bellows_ros.interfaces import COMMAND_WATCHDOG
from bellows_ros.io import params as param_files
from bellows_ros.models.actuator import ActuatorParams
from bellows_ros.models.segment import SegmentParams


def write(path, text):
    path.write_text(text)
    return path


def hardware_file(path, body):
    """Write a user hardware file with `body` (YAML) under `hardware:`."""
    return write(path, f'/**:\n  ros__parameters:\n    hardware:\n      {body}\n')


def test_the_driver_configuration_builds_no_physics_object(monkeypatch):
    """The drivers' config comes from the YAML alone: no ActuatorParams, no SegmentParams."""
    expected_actuator = load_actuator()
    expected_segment = load_segment().model

    def refuse(*args, **kwargs):
        raise AssertionError('a physics object was built for the driver configuration')
    monkeypatch.setattr(ActuatorParams, '__init__', refuse)
    monkeypatch.setattr(SegmentParams, '__init__', refuse)
    with pytest.raises(AssertionError):
        load_actuator()    # the patch bites where physics is built
    board = actuator_board_config()
    bus = arm_bus_config()
    # ... and gives the values of the one source, config/actuator.yaml and config/segment.yaml
    margin = param_files.load('hardware')['hardware.actuator_board.end_stop_margin']
    assert board.metres_per_count == expected_actuator.plant.drive.metres_per_count
    assert board.x_c_min == pytest.approx(expected_actuator.model.chamber.x_min + margin)
    assert board.x_c_max == pytest.approx(expected_actuator.model.chamber.x_max - margin)
    assert (bus.pressure_min, bus.pressure_max) == (expected_segment.p0, expected_segment.p_max)
    assert vent_pressure() == expected_segment.p0


def test_the_driver_configuration_follows_the_users_files(tmp_path):
    hardware = write(tmp_path / 'h.yaml', '/**:\n  ros__parameters:\n    hardware:\n'
                     '      actuator_board: {drive: {counts_per_rev: 128}}\n')
    actuator = write(tmp_path / 'a.yaml', '/**:\n  ros__parameters:\n    actuator:\n'
                     '      air_chamber: {x_max: 0.04}\n')
    segment = write(tmp_path / 's.yaml', '/**:\n  ros__parameters:\n    segment: {p_max: 6.0e5}\n')
    default = actuator_board_config()
    board = actuator_board_config(hardware, actuator)
    assert board.metres_per_count == pytest.approx(default.metres_per_count / 2)
    assert board.x_c_max == pytest.approx(default.x_c_max - 0.008)
    # the simulated actuator's encoder is the same drive train, from the same file
    assert load_actuator(hardware_params_path=hardware).plant.drive.metres_per_count == \
        board.metres_per_count
    assert arm_bus_config(segment_params_path=segment).pressure_max == 6.0e5


@pytest.mark.parametrize('name, body, needle', [
    ('h.yaml', 'hardware: {actuator_board: {drive: {lead: 0.0}}}',
     "'hardware.actuator_board.drive.lead' is 0, outside its physical range"),
    ('a.yaml', 'actuator: {air_chamber: {x_min: true}}', "'actuator.air_chamber.x_min'"),
    ('s.yaml', 'segment: {p_max: 9.0e4}', "'segment.p_max' must exceed p0"),
    ('h.yaml', 'hardware: {actuator_board: {end_stop_margin: 0.05}}', 'leaves no travel'),
])
def test_a_bad_shared_value_is_named_by_the_driver_configuration(tmp_path, name, body, needle):
    path = write(tmp_path / name, f'/**:\n  ros__parameters:\n    {body}\n')
    keyword = {'a.yaml': 'actuator_params_path', 'h.yaml': 'params_path'}.get(name)
    with pytest.raises(ParameterError, match=needle):
        if name == 's.yaml':
            arm_bus_config(segment_params_path=path)
        else:
            actuator_board_config(**{keyword: path})


def test_the_encoder_scale_is_one_lead_per_motor_turns_of_counts():
    # m/count = lead / (gear_ratio * counts_per_rev): one count is one encoder step of the motor,
    # and the lead screw advances one lead per output turn.
    drive = load_drive()
    assert drive.metres_per_count == pytest.approx(0.00127 / (100.0 * 64))
    assert actuator_board_config().metres_per_count == drive.metres_per_count


def test_the_users_drive_is_laid_over_the_default(tmp_path):
    path = hardware_file(tmp_path / 'h.yaml', 'actuator_board: {drive: {lead: 0.002}}')
    drive = load_drive(path)
    assert drive.lead == 0.002
    assert drive.gear_ratio == load_drive().gear_ratio  # the rest from config/hardware.yaml


@pytest.mark.parametrize('values, needle', [
    ({'gear_ratio': 0.0}, "'hardware.actuator_board.drive.gear_ratio' must be > 0"),
    ({'counts_per_rev': -64}, "'hardware.actuator_board.drive.counts_per_rev' must be > 0"),
    ({'inductance': -1e-3}, "'hardware.actuator_board.drive.inductance' must be >= 0"),
    ({'counts_per_rev': 64.5}, 'must be a whole number, got 64.5'),
    ({'lead': True}, "'lead' must be a number, got True"),
    ({'lead': 'fast'}, "'lead' must be a number, got 'fast'"),
])
def test_an_unusable_drive_value_is_refused_naming_it(values, needle):
    flat = param_files.section(param_files.load('hardware'), 'hardware.actuator_board.drive')
    flat.update(values)
    with pytest.raises(ParameterError, match=rf'^drive\.yaml: .*{needle}') as error:
        drive_from_flat(flat, 'drive.yaml')
    assert '\n' not in str(error.value)


def test_a_whole_float_count_is_a_count():
    flat = param_files.section(param_files.load('hardware'), 'hardware.actuator_board.drive')
    flat['counts_per_rev'] = 64.0   # YAML `64.0`: the same encoder
    assert drive_from_flat(flat).metres_per_count == load_drive().metres_per_count


def test_a_command_timeout_shorter_than_the_watchdog_is_refused(tmp_path):
    # Inside its physical range (1 ms .. 60 s) but shorter than the contract's command watchdog:
    # the driver would vent the arm between two of a controller's commands.
    short = COMMAND_WATCHDOG / 2
    path = hardware_file(tmp_path / 'h.yaml', f'arm_bus: {{command_timeout: {short}}}')
    with pytest.raises(ParameterError, match=r"h\.yaml: parameter 'hardware\.arm_bus\."
                                             r"command_timeout' = 0\.05 s is shorter than the "
                                             r'command watchdog'):
        arm_bus_config(path)
    at = hardware_file(tmp_path / 'at.yaml', f'arm_bus: {{command_timeout: {COMMAND_WATCHDOG}}}')
    assert arm_bus_config(at).command_timeout == COMMAND_WATCHDOG


def test_the_vented_pressure_is_the_segments_ambient(tmp_path):
    assert vent_pressure() == load_segment().model.p0
    segment = write(tmp_path / 's.yaml', '/**:\n  ros__parameters:\n    segment: {p0: 9.5e4}\n')
    assert vent_pressure(segment) == 9.5e4
    assert arm_bus_config(segment_params_path=segment).pressure_min == 9.5e4


def test_a_length_in_mm_is_refused_in_one_line_naming_file_and_cause(tmp_path):
    # The drive's lead in mm: the range check of config/ranges.py names it with its likely cause.
    path = hardware_file(tmp_path / 'h.yaml', 'actuator_board: {drive: {lead: 1.27}}')
    with pytest.raises(ParameterError) as error:
        actuator_board_config(path)
    message = str(error.value)
    assert message.startswith(f'{path}: ') and '\n' not in message
    assert "'hardware.actuator_board.drive.lead' is 1.27" in message and 'mm?' in message
