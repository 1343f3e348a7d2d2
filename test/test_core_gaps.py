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
Gaps are never filled silently (issue #30, class 3).

A bag whose channel (the spring force, the chamber pressure: NaN in the samples, or in an older
recording the wrench and chambers topics' messages) stops part-way, starts late or has a hole
longer than a few samples: export, identify, diagnose and stiffness refuse it in one line naming
the channel, the column and the times, and point to `bellows export --start/--end`; export with
that span writes the part that was recorded. A few dropped values stay a normal record.
"""
from bag_messages import write_actuator_bag
import numpy as np
import pytest
from rosbags.rosbag2.enums import StoragePlugin

from bellows_ros.cli import main
from bellows_ros.errors import DataError
from bellows_ros.io.data import read_table

RATE = 200.0   # Hz
PERIOD = 4.0   # s: one spring cycle, the stiffness command's default window
K = 1900.0     # N/m


def spring_record(cycles=2):
    """Return a stiffness experiment: chamber still, spring cycling 0-14 mm, f = K x_s + c."""
    t = np.arange(int(cycles * PERIOD * RATE)) / RATE
    phase = (t / PERIOD) % 1.0
    x_s = 0.014 * (1.0 - np.abs(2.0 * phase - 1.0))
    rng = np.random.default_rng(1)
    return {'t': t, 'x_c': 0.01 + 0 * t, 'x_s': x_s,
            'p': 1.3e5 + 50.0 * np.sin(t) + rng.normal(0, 5.0, len(t)),
            'f': 2.0 + K * x_s + rng.normal(0, 0.05, len(t))}


# The channels' names in the refusal, by layout (bag_messages): the samples' own, or (recorded
# before) the topics of their own.
FORCE = {'sample': 'effort of spring on /actuator/joint_states', 'split': '/bellows/wrench'}
PRESSURE = {'sample': 'effort of actuator on /actuator/joint_states',
            'split': '/actuator/chambers'}


def write_bag(path, data, wrench=None, chambers=None, layout='sample'):
    """Write `data` as the actuator's samples; `wrench`/`chambers`: rows with a force, pressure."""
    n = len(data['t'])
    wrench = np.ones(n, bool) if wrench is None else wrench
    chambers = np.ones(n, bool) if chambers is None else chambers
    start = 5 * 10 ** 9
    rows = [(start + int(round(data['t'][k] * 1e9)), data['x_c'][k], data['x_s'][k],
             data['p'][k] if chambers[k] else None, data['f'][k] if wrench[k] else None)
            for k in range(n)]
    return write_actuator_bag(path, rows, StoragePlugin.MCAP, layout=layout, version=9)


def keep(n, kind):
    rows = np.ones(n, bool)
    if kind == 'stops at the midpoint':
        rows[n // 2:] = False
    elif kind == 'starts late':
        rows[:n // 4] = False
    elif kind == 'a hole':
        rows[n // 3:n // 3 + 50] = False
    return rows


@pytest.fixture(scope='module')
def data():
    return spring_record()


GAPS = ['stops at the midpoint', 'starts late', 'a hole']
COMMANDS = {
    'export': 'export actuator {bag} --output {tmp}/o.csv',
    'identify': 'identify actuator {bag} --output {tmp}/p.yaml --quiet',
    'diagnose': 'diagnose actuator {bag} --report {tmp}/report --quiet',
    'stiffness': 'stiffness {bag} --setpoint 1900',
}


@pytest.mark.parametrize('gap', GAPS)
@pytest.mark.parametrize('command', sorted(COMMANDS))
def test_a_wrench_with_a_gap_is_refused_naming_channel_and_time(data, tmp_path, capsys, gap,
                                                                command):
    bag = write_bag(tmp_path / 'bag', data, wrench=keep(len(data['t']), gap))
    assert main(COMMANDS[command].format(bag=bag, tmp=tmp_path).split()) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and 'Traceback' not in err, err
    assert FORCE['sample'] in lines[0] and "column 'f'" in lines[0], lines[0]
    assert 'bellows export' in lines[0] and ' s' in lines[0], lines[0]
    assert not (tmp_path / 'o.csv').exists() and not (tmp_path / 'p.yaml').exists()


@pytest.mark.parametrize('layout', sorted(FORCE))
def test_chambers_that_stop_are_refused_too(data, tmp_path, layout):
    bag = write_bag(tmp_path / 'bag', data, chambers=keep(len(data['t']), 'stops at the midpoint'),
                    layout=layout)
    with pytest.raises(DataError, match=rf"column 'p': {PRESSURE[layout]} stops early: no "
                                        r'message after t = 3\.995 s'):
        read_table(bag, 'actuator')


@pytest.mark.parametrize('gap', GAPS)
def test_a_wrench_with_a_gap_in_an_older_recording_is_refused(data, tmp_path, gap):
    bag = write_bag(tmp_path / 'bag', data, wrench=keep(len(data['t']), gap), layout='split')
    with pytest.raises(DataError, match="column 'f': /bellows/wrench .*bellows export"):
        read_table(bag, 'actuator')


def test_the_export_span_before_the_stop_is_written_whole(data, tmp_path, capsys):
    bag = write_bag(tmp_path / 'bag', data, wrench=keep(len(data['t']), 'stops at the midpoint'))
    assert main(['export', 'actuator', str(bag), '--output', str(tmp_path / 'o.csv')]) == 2
    suggested = capsys.readouterr().err.split('`--end ')[1].split('`')[0]
    assert main(['export', 'actuator', str(bag), '--output', str(tmp_path / 'o.csv'), '--end',
                 suggested]) == 0
    table = read_table(tmp_path / 'o.csv', 'actuator')
    assert len(table) == len(data['t']) // 2
    assert np.allclose(table['f'], data['f'][:len(table)])


def test_the_stiffness_of_the_recorded_part_is_measured(tmp_path, capsys):
    """The cut record gives its cycles' stiffness; no cycle is computed from a held force."""
    data = spring_record(cycles=3)
    n = len(data['t'])
    wrench = np.arange(n) < 2 * n // 3
    bag = write_bag(tmp_path / 'bag', data, wrench=wrench)
    assert main(['stiffness', str(bag)]) == 2
    assert 'stops early' in capsys.readouterr().err
    assert main(['export', 'actuator', str(bag), '--output', str(tmp_path / 'o.csv'), '--end',
                 f'{data["t"][2 * n // 3 - 1]:.6g}']) == 0
    capsys.readouterr()
    assert main(['stiffness', str(tmp_path / 'o.csv')]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines and all(abs(float(line.split('stiffness')[1].split()[0]) - K) < 50
                         for line in lines), lines


@pytest.mark.parametrize('layout', sorted(FORCE))
def test_a_few_dropped_values_are_a_normal_record(data, tmp_path, layout):
    rows = np.ones(len(data['t']), bool)
    rows[100:104] = False   # 4 samples: a busy moment, under MAX_HELD_STEPS
    rows[900:905] = False
    bag = write_bag(tmp_path / 'bag', data, wrench=rows, chambers=rows, layout=layout)
    assert len(read_table(bag, 'actuator')) == len(data['t'])
