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
`python -m bellows_ros.papers.fig10`: paper A's Fig. 10 hysteresis, its table and its plot.

Run in this process (`main(argv)`). The table is the one docs/segment.md gives ("Calibration
against paper A's Fig. 10"): |τ_ext| 6.700 / 9.100 N·m measured and modelled, the previous model
(34) 10.055 both times, the contact length s̃_a,1 53.4 / 65.1 mm. The plot is written whole
(atomically); a bad --plot or --params is one line and exit status 2, with nothing written.
"""
import pytest

from bellows_ros.papers import fig10


def table(out):
    """Return {row name: (before, after)} of the printed table."""
    rows = {}
    for line in out.splitlines()[1:]:
        if not line.startswith('wrote '):  # a name in 28 columns, then two numbers
            before, after = line[28:].split()
            rows[line[:28].strip()] = (float(before), float(after))
    return rows


def test_the_table_is_the_calibrated_fig10_and_the_plot_is_written(tmp_path, capsys):
    plot = tmp_path / 'fig10.png'
    assert fig10.main(['--plot', str(plot)]) == 0
    out = capsys.readouterr().out
    assert 'paper A measured 6.7 / 9.1, previous model 9.9' in out.splitlines()[0]
    rows = table(out)
    assert rows['measured |tau_ext|'] == pytest.approx((6.7, 9.1), abs=1e-3)        # N·m
    assert rows['paper A model tau_drive'] == pytest.approx((6.7, 9.1), abs=1e-3)
    assert rows['previous model (34)'] == pytest.approx((10.055, 10.055), abs=1e-3)  # one value
    assert rows['contact length s~_a1, mm'] == pytest.approx((53.4, 65.1), abs=0.06)
    assert out.endswith(f'wrote {plot}\n')
    assert plot.read_bytes().startswith(b'\x89PNG\r\n\x1a\n')
    assert [p.name for p in tmp_path.iterdir()] == ['fig10.png']  # no temporary left


def test_sensor_noise_moves_the_measurement_not_the_scenario(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / 'fig10.png').write_bytes(b'an old plot')
    assert fig10.main(['--noise']) == 0   # the default plot, fig10.png here, replaced
    rows = table(capsys.readouterr().out)
    measured = rows['measured |tau_ext|']
    assert measured != pytest.approx((6.7, 9.1), abs=1e-3)
    assert measured == pytest.approx((6.7, 9.1), abs=0.3)   # τ noise: 0.05 N·m
    assert (tmp_path / 'fig10.png').read_bytes().startswith(b'\x89PNG')


@pytest.mark.parametrize('case', ['plot over params', 'missing params', 'missing directory'])
def test_a_bad_plot_or_params_is_one_line_and_nothing_is_written(tmp_path, capsys, case):
    params = tmp_path / 'p.yaml'
    params.write_text('/**:\n  ros__parameters: {}\n')
    argv, needle = {
        'plot over params': (['--params', str(params), '--plot', str(params)],
                             f'--plot {params}: that is an input'),
        'missing params': (['--params', str(tmp_path / 'no.yaml'), '--plot',
                            str(tmp_path / 'f.png')], str(tmp_path / 'no.yaml')),
        'missing directory': (['--plot', str(tmp_path / 'no' / 'f.png')],
                              str(tmp_path / 'no' / 'f.png')),
    }[case]
    assert fig10.main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ''
    assert captured.err.count('\n') == 1 and captured.err.startswith('fig10: error: ')
    assert needle in captured.err
    assert sorted(p.name for p in tmp_path.rglob('*')) == ['p.yaml']
    assert params.read_text() == '/**:\n  ros__parameters: {}\n'
