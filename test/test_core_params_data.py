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

"""The shared parameter and data-file layers: the errors a user sees, and that nothing is lost."""
import numpy as np
import pytest

from bellows_ros.cli import main as bellows
from bellows_ros.errors import DataError
from bellows_ros.io import data, params


def write(path, text):
    path.write_text(text)
    return path


def test_the_simulated_arms_model_has_the_simulated_segments_rigid_body():
    """config/segment_sim_arm.yaml restates segment.plant's M, C, N: held equal here."""
    from bellows_ros.config.segment import load_segment
    url = params.read_file(params.default_file('nodes_sim'), 'arm_controller_node')['params_file']
    model, plant = load_segment(url).model, load_segment().plant
    assert (model.dynamics_inertia, model.dynamics_damping, model.dynamics_gravity) == \
        (plant.inertia, plant.damping, plant.gravity)
    assert load_segment().model.dynamics_inertia == 0.0  # the shipped model stays quasi-static


def test_csv_errors_name_file_line_and_column(tmp_path):
    path = write(tmp_path / 'in.csv', 't,a\n0,1\n0.1,nan\n')
    with pytest.raises(DataError, match=r"in\.csv:3: column 'a': nan is not a finite number"):
        data.read_csv(path, ('t', 'a'))
    path = write(tmp_path / 'in.csv', 't,a\n0,1\n\n0.1,x1\n')
    with pytest.raises(DataError, match=r"in\.csv:4: column 'a': not a number: 'x1'"):
        data.read_csv(path, ('t', 'a'))
    path = write(tmp_path / 'in.csv', 't,b\n0,1\n')
    with pytest.raises(DataError, match=r"in\.csv:1: missing column 'a'"):
        data.read_csv(path, ('t', 'a'))


def test_time_must_increase_and_ranges_checked(tmp_path):
    table = data.read_csv(write(tmp_path / 'in.csv', 't,a\n0,1\n1,2\n\n1,3\n'), ('t', 'a'))
    with pytest.raises(DataError, match=r"in\.csv:5: column 't': not increasing"):
        data.check_increasing(table)
    with pytest.raises(DataError, match=r"in\.csv:3: column 'a': 2 Pa is outside \[0, 1.5\] Pa"):
        data.check_range(table, 'a', 0.0, 1.5, 'Pa')


def test_write_keeps_every_input_column(tmp_path):
    table = data.read_csv(write(tmp_path / 'in.csv', 't,label,a\n0,x,1\n1,y,2\n'), ('t', 'a'))
    data.write_csv(tmp_path / 'out.csv', table, {'b': np.array([3.0, 4.0])})
    assert (tmp_path / 'out.csv').read_text().splitlines() == ['t,label,a,b', '0.0,x,1.0,3.0',
                                                               '1.0,y,2.0,4.0']


def test_cli_turns_user_error_into_one_line_and_status_2(tmp_path, capsys):
    status = bellows(['simulate', 'segment', '--input', str(tmp_path / 'missing.csv'),
                      '--output', str(tmp_path / 'o.csv'), '--effect', 'x:k=notanumber'])
    err = capsys.readouterr().err
    assert status == 2
    assert err.count('\n') == 1 and 'Traceback' not in err


def test_fast_and_careful_readers_agree(tmp_path):
    rows = '\n'.join(f'{i * 1e-3!r},{i * 0.5!r},{-i / 7!r}' for i in range(200))
    plain = write(tmp_path / 'plain.csv', 't,a,b\n' + rows + '\n')
    # An extra text column sends the reader down the careful (csv module) path.
    labelled = write(tmp_path / 'labelled.csv', 't,a,b,note\n'
                     + '\n'.join(f'{line},x' for line in rows.splitlines()) + '\n')
    fast = data.read_csv(plain, ('t', 'a', 'b'))
    careful = data.read_csv(labelled, ('t', 'a', 'b'))
    assert fast.extras == {} and careful.extras['note'][0] == 'x'
    for name in ('t', 'a', 'b'):
        np.testing.assert_array_equal(fast[name], careful[name])
    assert fast.line(199) == careful.line(199) == 201
