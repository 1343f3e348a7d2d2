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
Before/after plots of a diagnosis (matplotlib, Agg backend, PNG).

All residuals plotted are held-out residuals: what the model got wrong on blocks of time it was not
fitted on. "baseline" is the simulation before the doctor, "extended" the model with the causes
found. A diagnosis of several outputs (the actuator's pressure and force) gets every plot for each:
the first output under the plain names, the others with `_<label>` appended (fit_force.png ...).
"""
from types import SimpleNamespace  # noqa: E402

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402

from bellows_ros.doctor.scoring import autocorrelation  # noqa: E402

MAX_POINTS = 6000


def _thin(n):
    return slice(None, None, max(1, n // MAX_POINTS))


def _inputs(diagnosis):
    r = diagnosis.record
    if diagnosis.system == 'actuator':
        return r['x_c'], 'air-chamber compression x_c (m)', r['p'], 'pressure p (Pa)'
    return r['psi'], 'segment angle Ψ (rad)', r['p1'] - r['p2'], 'p1 - p2 (Pa)'


def figures(diagnosis):
    """
    Yield (file name, figure): residuals.png, fit.png, hysteresis.png, autocorrelation.png.

    The same plots follow for each further output. The caller saves each figure and closes it
    (`matplotlib.pyplot.close`) before asking for the next.
    """
    for suffix, view in _views(diagnosis):
        for name, draw in (('residuals', _residuals), ('fit', _fit),
                           ('hysteresis', _hysteresis), ('autocorrelation', _autocorrelation)):
            yield f'{name}{suffix}.png', draw(view)


def _views(d):
    """(file suffix, object with the attributes the plots read) per output."""
    if not d.outputs:
        return [('', d)]
    views = []
    for index, o in enumerate(d.outputs):
        views.append(('' if index == 0 else f'_{o.label}', SimpleNamespace(
            record=d.record, system=d.system, causes=d.causes, signal=o.signal, unit=o.unit,
            what=o.label,
            baseline=SimpleNamespace(heldout=o.baseline_heldout, rmse=o.baseline_rmse),
            final=SimpleNamespace(heldout=o.final_heldout, rmse=o.final_rmse))))
    return views


def _label(diagnosis):
    return (f'extended ({" + ".join(diagnosis.causes)})' if diagnosis.causes
            else 'extended (= baseline)')


def _residuals(d):
    t = d.record['t']
    position, position_label, pressure, pressure_label = _inputs(d)
    rate = np.gradient(position, d.record.dt)
    direction = np.sign(np.where(np.abs(rate) > 0.02 * np.max(np.abs(rate)), rate, 0.0))
    thin = _thin(len(t))
    figure, axes = plt.subplots(2, 2, figsize=(12, 8))
    series = (('baseline', d.baseline.heldout, 'tab:red'),
              (_label(d), d.final.heldout, 'tab:blue'))
    for label, residual, colour in series:
        axes[0, 0].plot(t[thin], residual[thin], lw=0.6, color=colour, label=label)
        axes[0, 1].plot(rate[thin], residual[thin], '.', ms=1.5, color=colour, alpha=0.5)
        axes[1, 1].plot(pressure[thin], residual[thin], '.', ms=1.5, color=colour, alpha=0.5)
    groups = [(-1, 'moving down'), (0, 'holding'), (1, 'moving up')]
    data, ticks = [], []
    for value, name in groups:
        for label, residual, _ in series:
            data.append(residual[direction == value] if np.any(direction == value)
                        else np.zeros(1))
            ticks.append(f'{name}\n{label.split(" ")[0]}')
    axes[1, 0].boxplot(data, showfliers=False)
    axes[1, 0].set_xticks(range(1, len(ticks) + 1), ticks, fontsize=7)
    axes[0, 0].set(xlabel='time (s)', title='held-out residual against time')
    axes[0, 1].set(xlabel=f'rate of {position_label} per s', title='against rate')
    axes[1, 0].set(title='against direction of motion')
    axes[1, 1].set(xlabel=pressure_label, title='against pressure')
    for axis in axes.flat:
        axis.set_ylabel(f'{getattr(d, "what", "")} residual ({d.unit})')
        axis.grid(alpha=0.3)
    axes[0, 0].legend(loc='upper right', fontsize=8)
    figure.tight_layout()
    return figure


def _fit(d):
    t = d.record['t']
    thin = _thin(len(t))
    figure, axis = plt.subplots(figsize=(12, 4.5))
    axis.plot(t[thin], d.signal[thin], color='k', lw=0.8, label='measured')
    axis.plot(t[thin], (d.signal + d.baseline.heldout)[thin], color='tab:red', lw=0.8,
              label=f'baseline (held-out RMSE {d.baseline.rmse:.4g} {d.unit})')
    axis.plot(t[thin], (d.signal + d.final.heldout)[thin], color='tab:blue', lw=0.8,
              label=f'{_label(d)} (held-out RMSE {d.final.rmse:.4g} {d.unit})')
    what = getattr(d, 'what', 'driving torque τ_motion - τ_ext')
    axis.set(xlabel='time (s)', ylabel=f'{what} ({d.unit})',
             title='before and after, on held-out blocks')
    axis.legend(fontsize=8)
    axis.grid(alpha=0.3)
    figure.tight_layout()
    return figure


def _hysteresis(d):
    position, position_label, _, _ = _inputs(d)
    thin = _thin(len(position))
    figure, axes = plt.subplots(1, 2, figsize=(12, 4.5), sharey=True)
    for axis, (label, residual) in zip(axes, (('baseline', d.baseline.heldout),
                                              (_label(d), d.final.heldout))):
        axis.plot(position[thin], d.signal[thin], color='k', lw=0.6, label='measured')
        axis.plot(position[thin], (d.signal + residual)[thin], color='tab:blue', lw=0.6,
                  label=label)
        axis.set(xlabel=position_label, title=f'loops: {label}')
        axis.grid(alpha=0.3)
        axis.legend(fontsize=8)
    axes[0].set_ylabel(d.unit)
    figure.tight_layout()
    return figure


def _autocorrelation(d):
    lags = min(200, len(d.signal) // 4)
    figure, axis = plt.subplots(figsize=(8, 4))
    seconds = np.arange(lags + 1) * d.record.dt
    axis.plot(seconds, autocorrelation(d.baseline.heldout, lags), color='tab:red',
              label='baseline')
    axis.plot(seconds, autocorrelation(d.final.heldout, lags), color='tab:blue', label=_label(d))
    band = 2.0 / np.sqrt(len(d.signal))
    axis.axhspan(-band, band, color='0.85', label='white noise ±2/√n')
    axis.set(xlabel='lag (s)', ylabel='autocorrelation',
             title=f'held-out {getattr(d, "what", "")} residual autocorrelation')
    axis.legend(fontsize=8)
    axis.grid(alpha=0.3)
    figure.tight_layout()
    return figure
