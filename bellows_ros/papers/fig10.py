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
Paper A's Fig. 10 hysteresis on the simulated segment: `python -m bellows_ros.papers.fig10`.

Chain 1 is pressurised to 4 bar abs at Ψ = 74.5° (chain 2 vented); an external force then moves the
segment down to -30° and back to the same (p, Ψ). Prints |τ_ext| before and after, with the paper-A
model and the previous model (34) evaluated on the measured inputs, and plots the run to a PNG.
"""
import argparse
import sys

import numpy as np

from bellows_ros.config.segment import load_segment
from bellows_ros.errors import BellowsError
from bellows_ros.io.outputs import atomic_file, check_output
from bellows_ros.models.segment import simulate_model
from bellows_ros.models.segment_plant import FULL_MODEL, NO_NOISE
from bellows_ros.papers.segment_experiments import fig10_record


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--params', metavar='P.yaml',
                        help='parameters laid over config/segment.yaml')
    parser.add_argument('--plot', metavar='PNG', default='fig10.png',
                        help='output plot (default fig10.png)')
    parser.add_argument('--noise', action='store_true',
                        help='sensor noise from segment.plant.noise')
    args = parser.parse_args(argv)
    try:
        check_output(args.plot, inputs=(args.params,), what='--plot')
        params, plant, _ = load_segment(args.params)
    except BellowsError as exc:
        print(f'fig10: error: {exc}', file=sys.stderr)
        return 2
    record, before, after = fig10_record(params, plant, FULL_MODEL,
                                         None if args.noise else NO_NOISE, seed=0)
    model = simulate_model(params, record['psi'], record['p1'], record['p2'], record['psi_dot'])
    print(f"{'':28}{'before':>10}{'after':>10}   "
          '(N·m; paper A measured 6.7 / 9.1, previous model 9.9)')
    for name, values in (('measured |tau_ext|', -record['tau_ext']),
                         ('paper A model tau_drive', model['tau_drive']),
                         ('previous model (34)', model['tau_prev'])):
        print(f'{name:28}{values[before]:10.3f}{values[after]:10.3f}')
    print(f"{'contact length s~_a1, mm':28}"
          f"{1e3 * model['sa1'][before]:10.3f}{1e3 * model['sa1'][after]:10.3f}")
    _plot(args.plot, record, model, before, after)
    print(f'wrote {args.plot}')
    return 0


def _plot(path, record, model, before, after):
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    t = record['t']
    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(8, 9))
    axes[0].plot(t, np.degrees(record['psi']))
    axes[0].set_ylabel('Ψ, deg')
    axes[1].plot(t, record['p1'] / 1e5, label='chain 1')
    axes[1].plot(t, record['p2'] / 1e5, label='chain 2')
    axes[1].set_ylabel('p, bar abs')
    axes[1].legend()
    axes[2].plot(t, 1e3 * model['sa1'])
    axes[2].set_ylabel('s̃_a,1, mm')
    axes[3].plot(t, -record['tau_ext'], label='measured |τ_ext|', color='k')
    axes[3].plot(t, model['tau_drive'], '--', label='paper A model')
    axes[3].plot(t, model['tau_prev'], ':', label='previous model (34)')
    for index in (before, after):
        axes[3].axvline(t[index], color='grey', lw=0.5)
    axes[3].set_ylabel('torque, N·m')
    axes[3].set_xlabel('t, s')
    axes[3].legend()
    fig.tight_layout()
    with atomic_file(path, 'wb') as stream:
        fig.savefig(stream, format='png', dpi=100)
    plt.close(fig)


if __name__ == '__main__':
    sys.exit(main())
