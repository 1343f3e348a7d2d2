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
Before/after plots of a diagnosis (doctor/plots.py), drawn with matplotlib's Agg backend.

Real diagnoses of short records (a segment and an actuator with a sensor lag) are drawn into
pytest's tmp_path as the `bellows diagnose` command saves them; what each plot shows is read back
from its figure: the measured signal, and the model's held-out prediction (measured + held-out
residual) before and after. A long record is thinned to at most about `MAX_POINTS` points a line.
"""
from types import SimpleNamespace

import matplotlib.image
import matplotlib.pyplot as plt
import numpy as np
import pytest

from bellows_ros.config.actuator import load_actuator
from bellows_ros.config.segment import load_segment
from bellows_ros.doctor import checks, diagnosis, plots
from bellows_ros.papers.actuator_experiments import actuator_record
from bellows_ros.papers.segment_experiments import quasi_static_record

NAMES = ['residuals.png', 'fit.png', 'hysteresis.png', 'autocorrelation.png']


@pytest.fixture(scope='module')
def segment():
    config = load_segment()
    record = quasi_static_record(config.model, config.plant, {'sensor_lag': {'tau': 0.04}},
                                 seed=7, duration=10.0, pressure_hold=(0.5, 2.0))
    return diagnosis.diagnose('segment', record, config, causes=('sensor_lag',))


def saved(d, directory, only=None):
    """Save the figures of `d` (those named in `only`) as the command does, closing each."""
    names = []
    for name, figure in plots.figures(d):
        if only is None or name in only:
            figure.savefig(directory / name, dpi=40)
        plt.close(figure)
        names.append(name)
    return names


def lines(figure):
    """Return {label: (x, y)} of the lines of every axis of `figure`."""
    return {line.get_label(): (np.asarray(line.get_xdata()), np.asarray(line.get_ydata()))
            for axis in figure.axes for line in axis.get_lines()}


def test_four_pngs_are_drawn_for_one_output(segment, tmp_path):
    assert saved(segment, tmp_path) == NAMES
    for name in NAMES:
        image = matplotlib.image.imread(tmp_path / name)      # raises unless it is a PNG
        colours = np.unique(image.reshape(-1, image.shape[-1]), axis=0)
        assert min(image.shape[:2]) > 100 and len(colours) > 10, name    # drawn on, not blank
    assert plt.get_fignums() == []


def test_the_fit_plot_shows_the_held_out_predictions_before_and_after(segment):
    figure = next(figure for name, figure in plots.figures(segment) if name == 'fit.png')
    try:
        drawn = lines(figure)
        t = segment.record['t']
        np.testing.assert_allclose(drawn['measured'][1], segment.signal)
        np.testing.assert_array_equal(drawn['measured'][0], t)
        before = next(v for k, v in drawn.items() if k.startswith('baseline (held-out RMSE'))
        after = next(v for k, v in drawn.items()
                     if k.startswith('extended (sensor_lag) (held-out RMSE'))
        np.testing.assert_allclose(before[1], segment.signal + segment.baseline.heldout)
        np.testing.assert_allclose(after[1], segment.signal + segment.final.heldout)
        assert f'{segment.final.rmse:.4g} N·m' in next(k for k in drawn if k.startswith('ext'))
    finally:
        plt.close('all')


def test_each_further_output_gets_its_own_plots(tmp_path):
    config = load_actuator()
    record = actuator_record(config.model, config.plant, None, seed=3, duration=6.0)
    d = diagnosis.diagnose('actuator', record, config, causes=())
    names = saved(d, tmp_path, only=['fit_force.png'])
    assert names == NAMES + [name.replace('.png', '_force.png') for name in NAMES]
    assert (tmp_path / 'fit_force.png').stat().st_size > 1000
    assert plt.get_fignums() == []        # each closed before the next was drawn
    figure = dict(plots.figures(d))['fit_force.png']
    try:
        axis = figure.axes[0]
        assert axis.get_ylabel() == 'force (N)'
        np.testing.assert_allclose(lines(figure)['measured'][1], d.record['f'])
        assert any(k.startswith('extended (= baseline)') for k in lines(figure))   # no cause
    finally:
        plt.close('all')


def test_a_long_record_is_thinned():
    n = 3 * plots.MAX_POINTS + 5
    t = np.arange(n) * 1e-3
    residual = SimpleNamespace(heldout=np.sin(t), rmse=0.7)
    d = SimpleNamespace(
        system='segment', causes=[], unit='N·m', outputs=[], signal=np.cos(t),
        record=checks.Record('segment', 'x', 1e-3, {
            't': t, 'psi': 0.3 * np.sin(t), 'p1': 3e5 + 0 * t, 'p2': 2e5 + 0 * t}),
        baseline=residual, final=residual)
    figures = dict(plots.figures(d))
    try:
        x, y = lines(figures['fit.png'])['measured']
        np.testing.assert_array_equal(x, t[::3])
        np.testing.assert_array_equal(y, d.signal[::3])
        # the autocorrelation runs to 200 lags of the fitted copy, in seconds
        lag, r = next(v for k, v in lines(figures['autocorrelation.png']).items()
                      if k == 'baseline')
        assert lag[-1] == pytest.approx(0.2) and r[0] == pytest.approx(1.0)
    finally:
        plt.close('all')
