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
No silent wrong numbers: identification refuses what a record cannot determine.

Each case gives the command only the data; the answer (refused or not, and why) is what the code
must find. Records come from devices drawn over wide ranges (tube volume, gas amount, sample
rate, the leak's size), not only the default one.
"""
import csv
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from bellows_ros import params as param_files
from bellows_ros.cli import main
from bellows_ros.config.actuator import load_actuator_params, load_actuator_plant_params
from bellows_ros.errors import ParameterError
from bellows_ros.models.actuator_experiments import actuator_record

PARAMS, PLANT = load_actuator_params(), load_actuator_plant_params()


def write_csv(path, columns):
    with open(path, 'w', newline='') as stream:
        writer = csv.writer(stream)
        writer.writerow(list(columns))
        writer.writerows(zip(*columns.values()))
    return str(path)


def error_line(capsys):
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0]


def drawn_device(seed):
    """Draw a device and a record setting over wide ranges."""
    rng = np.random.default_rng(seed)
    params = dataclasses.replace(PARAMS, v_tube=float(rng.uniform(1e-6, 30e-6)))
    return params, {'gas': float(rng.uniform(0.85, 1.15)) * PARAMS.p_ref,
                    'dt': float(rng.choice([1e-3, 2e-3, 5e-3, 1e-2])),
                    'duration': float(rng.uniform(15.0, 30.0))}


def record_of(params, setting, effects, seed):
    return actuator_record(params, PLANT, effects=effects, seed=seed, **setting)


@pytest.mark.parametrize('seed', range(4))
def test_a_sealed_record_of_a_drawn_device_is_identified(seed, tmp_path, capsys):
    params, setting = drawn_device(seed)
    data = write_csv(tmp_path / 'r.csv', record_of(params, setting, ['wall_bulging'], seed))
    assert main(['identify', 'actuator', data, '--output', str(tmp_path / 'p.yaml'),
                 '--quiet']) == 0, capsys.readouterr().err
    assert (tmp_path / 'p.yaml').is_file()


@pytest.mark.parametrize('seed', range(4))
@pytest.mark.parametrize('strength', [0.3, 1.0, 3.0])
def test_a_leaking_record_of_a_drawn_device_is_refused_and_sent_to_the_doctor(
        seed, strength, tmp_path, capsys):
    params, setting = drawn_device(seed)
    leak = strength * PLANT.effect_defaults()['air_leak']['conductance']
    data = write_csv(tmp_path / 'r.csv', record_of(params, setting,
                                                   {'air_leak': {'conductance': leak}}, seed))
    output = tmp_path / 'p.yaml'
    assert main(['identify', 'actuator', data, '--output', str(output), '--quiet']) == 2
    line = error_line(capsys)
    assert 'sealed' in line and 'bellows diagnose actuator' in line, line
    assert not output.exists()


def test_one_row_is_refused_with_how_many_are_needed(tmp_path, capsys):
    record = actuator_record(PARAMS, PLANT, seed=1, duration=1.0)
    data = write_csv(tmp_path / 'r.csv', {k: v[:1] for k, v in record.items()})
    assert main(['identify', 'actuator', data, '--output', str(tmp_path / 'p.yaml')]) == 2
    assert 'only 1 rows' in error_line(capsys)


@pytest.mark.parametrize('column', ['x_c', 'x_s'])
def test_an_input_that_never_moves_is_refused_naming_it(column, tmp_path, capsys):
    record = actuator_record(PARAMS, PLANT, seed=1, duration=10.0)
    record[column] = np.full_like(record[column], np.median(record[column]))
    data = write_csv(tmp_path / 'r.csv', record)
    assert main(['identify', 'actuator', data, '--output', str(tmp_path / 'p.yaml')]) == 2
    line = error_line(capsys)
    assert f"column '{column}': never moves" in line


def test_a_segment_angle_that_never_moves_is_refused(tmp_path, capsys):
    rows = 2000
    data = write_csv(tmp_path / 's.csv', {'t': np.arange(rows) * 1e-3, 'psi': np.zeros(rows),
                                          'p1': np.full(rows, 2e5), 'p2': np.full(rows, 1.2e5),
                                          'tau_ext': np.zeros(rows)})
    assert main(['identify', 'segment', data, '--output', str(tmp_path / 'p.yaml')]) == 2
    assert "column 'psi': never moves" in error_line(capsys)


def test_a_parameter_file_with_a_key_twice_is_refused_with_file_and_line(tmp_path, capsys):
    twice = tmp_path / 'twice.yaml'
    twice.write_text('/**:\n  ros__parameters:\n    actuator:\n      gas:\n'
                     '        v_tube: 1.0e-6\n        p_ref: 101325.0\n        v_tube: 2.0e-6\n')
    record = actuator_record(PARAMS, PLANT, seed=1, duration=1.0)
    data = write_csv(tmp_path / 'r.csv', record)
    assert main(['simulate', 'actuator', '--input', data, '--output',
                 str(tmp_path / 'o.csv'), '--params', str(twice)]) == 2
    assert f"{twice}:7: key 'v_tube' is given twice" in error_line(capsys)
    with pytest.raises(ParameterError, match='given twice'):
        param_files.read_sections(twice)


def test_a_file_its_loader_refuses_is_never_written(tmp_path):
    path = tmp_path / 'p.yaml'
    path.write_text('old\n')

    def loader(written):
        raise ParameterError(f"{written}: parameter 'actuator.gas.v_tube' must be >= 0")
    with pytest.raises(ParameterError):
        param_files.write_file(path, {'actuator.gas.v_tube': -2.7e-5}, check=loader)
    assert path.read_text() == 'old\n'
    assert [p.name for p in Path(tmp_path).iterdir()] == ['p.yaml']


@pytest.mark.parametrize('value', ['1.01325', '101.325', '1013.25'])
def test_an_ambient_pressure_in_bar_kpa_or_hpa_is_refused(value, tmp_path, capsys):
    params = tmp_path / 'p.yaml'
    params.write_text(f'/**:\n  ros__parameters:\n    segment:\n      p0: {value}\n')
    t = np.arange(100) * 1e-3
    data = write_csv(tmp_path / 's.csv', {'t': t, 'psi': 0.1 * np.sin(t), 'p1': 2e5 + 0 * t,
                                          'p2': 1.5e5 + 0 * t, 'tau_ext': 0 * t})
    assert main(['simulate', 'segment', '--input', data, '--output', str(tmp_path / 'o.csv'),
                 '--params', str(params)]) == 2
    line = error_line(capsys)
    assert "parameter 'segment.p0'" in line and 'ambient' in line, line


def test_a_driver_refuses_a_command_timeout_below_the_contracts_watchdog(tmp_path):
    """A controller keeps to interfaces.COMMAND_WATCHDOG: a shorter timeout is refused."""
    from bellows_ros import interfaces
    from bellows_ros.config.hardware import arm_bus_config
    section = '/**:\n  ros__parameters:\n    hardware:\n      arm_bus:\n        command_timeout: '
    short = tmp_path / 'hardware.yaml'
    short.write_text(f'{section}{interfaces.COMMAND_WATCHDOG / 2}\n')
    with pytest.raises(ParameterError, match='command watchdog of the interface contract'):
        arm_bus_config(short)
    longer = tmp_path / 'longer.yaml'
    longer.write_text(f'{section}0.5\n')
    assert arm_bus_config(longer).command_timeout == 0.5


ABSURD = [('segment', 'segment:\n      geometry:\n        n_lambda: 1000000000\n',
           "'segment.geometry.n_lambda' must be a whole number in 1..100000"),
          ('segment', 'segment:\n      geometry:\n        l0: 50.0\n',
           "'segment.geometry.l0' must lie in (0, 1] m, got 50 (in mm?)"),
          ('actuator', 'actuator:\n      spring:\n        h0: 12.0\n',
           "'actuator.spring.h0' must lie in (0, 1] m, got 12 (in mm?)"),
          ('actuator', 'actuator:\n      air_chamber:\n        n: 100000\n',
           "'actuator.air_chamber.n' must be a whole number of segments in 1..1000")]


@pytest.mark.parametrize('system, section, message', ABSURD)
def test_an_absurd_geometry_is_refused_before_any_work(system, section, message, tmp_path,
                                                       capsys):
    """A size in mm or an absurd count: one line naming it, exit 2, nothing written."""
    params = tmp_path / 'absurd.yaml'
    params.write_text('/**:\n  ros__parameters:\n    ' + section)
    source = tmp_path / 'in.csv'
    if system == 'segment':
        t = np.arange(200) * 1e-3
        write_csv(source, {'t': t, 'psi': 0.1 * np.sin(t), 'p1': 2e5 + 0 * t, 'p2': 2e5 + 0 * t})
    else:
        t = np.arange(200) * 1e-3
        write_csv(source, {'t': t, 'x_c': -0.02 + 0 * t, 'x_s': 0.001 + 0 * t})
    output = tmp_path / 'out.csv'
    assert main(['simulate', system, '--input', str(source), '--output', str(output),
                 '--params', str(params)]) == 2
    line = error_line(capsys)
    assert str(params) in line and message in line, line
    assert not output.exists()
