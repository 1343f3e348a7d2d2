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
`bellows bench` (cli/bench.py): which benches `--only` runs, the table, the refusals.

The records it writes and renders are test_cli_bench_records.py's; the benches' figures are each
bench module's test.
"""
import pytest

from bellows_ros.bench import Result
from bellows_ros.cli import main
from bellows_ros.cli.bench import chosen_modules, format_table
from bellows_ros.errors import BellowsError


def test_a_pattern_selects_the_graph_benches_and_a_name_its_module():
    assert chosen_modules('graph*') == ['graph', 'graph_actuator', 'graph_floor']
    assert chosen_modules('graph') == ['graph']  # a name is that module alone


def test_one_seeded_run_takes_doctor_devices_and_the_arm_control_rows():
    """Issue 21's run: `bellows bench --only doctor_devices,'arm_control*'`, any order, spaces."""
    both = ['arm_control', 'arm_control_devices', 'doctor_devices']
    assert chosen_modules('doctor_devices,arm_control*') == both
    assert chosen_modules(' arm_control* , doctor_devices') == both
    assert 'graph' in chosen_modules(None) and 'graph' not in both
    # A name is that module alone: the 10-minute doctor bench is not the hours-long one.
    assert chosen_modules('doctor') == ['doctor']
    for typo in ('arm_cntrl', 'doctor_device', ''):
        with pytest.raises(BellowsError, match=f'{typo!r} is no benchmark module'):
            chosen_modules(f'segment,{typo}')


def test_every_bench_module_is_chosen_by_default_in_name_order():
    chosen = chosen_modules(None)
    assert chosen == sorted(chosen) and chosen == chosen_modules('')
    assert {'segment', 'graph_floor', 'doctor_devices'} <= set(chosen)


def test_fractions_in_extra_are_shown_without_the_figures_unit():
    table = format_table([Result('x.rate', 990.0, 'Hz', 1, extra={'steal': 0.125, 'p50': 980.0},
                                 extra_units={'steal': ''})])
    assert '    steal:      0.125 \n' in table + '\n'
    assert '    p50:        980 Hz' in table


def test_a_table_row_shows_the_ratio_and_target_only_where_given():
    rows = format_table([Result('a.step', 2e-6, 's', 10, reference='ref', ratio=4.0,
                                target=5e-6),
                         Result('b.total', 3.5, 's', 1)]).splitlines()
    assert rows[0].split() == ['benchmark', 'median', 'ratio', 'target', 'reference']
    assert rows[1].split() == ['a.step', '2.00', 'µs', '4.00', '5.00', 'µs', 'ref']
    assert rows[2].split() == ['b.total', '3.500', 's']


@pytest.mark.parametrize('argv, message', [
    (['--plot', 'x.png'], '--plot draws records: give them with --render FILE...'),
    # before any bench runs: doctor_devices takes --devices, segment does not
    (['--only', 'doctor_devices,segment', '--devices', '2'], 'bench segment takes no --devices'),
    (['--only', 'segmnt'], "'segmnt' is no benchmark module"),
])
def test_a_mistaken_command_is_one_line_and_exit_2(argv, message, capsys):
    assert main(['bench', *argv]) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and message in err


def test_an_output_that_is_a_special_file_is_refused_before_any_bench_runs(capsys):
    # check_output refuses /dev/null; no bench's 'bench: NAME ...' line is printed before it.
    assert main(['bench', '--only', 'segment', '--output', '/dev/null']) == 2
    err = capsys.readouterr().err
    assert 'bench: segment' not in err and '/dev/null' in err and err.count('\n') == 1
