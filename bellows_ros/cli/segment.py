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
`bellows simulate segment` and `bellows identify segment` (docs/interfaces.md).

simulate: without --effect the paper-A model runs over the input rows (strain memory carried from
row to row) and the columns sa1, sa2, tau_a, tau_s, tau_f, tau_drive, tau_prev are appended. With
--effect the simulated segment (`SegmentPlant`, seed 0) runs instead: the input psi is imposed, the
input p1/p2 are the pressure *commands* (kept as p1_cmd, p2_cmd); psi, psi_dot, p1, p2, tau_ext and
tau_motion are replaced by the plant's measurements (noise from `segment.plant.noise`), and the 7
output columns are the plant's true values.
"""

import numpy as np

from bellows_ros import data
from bellows_ros.config.segment import load_segment
from bellows_ros.errors import DataError
from bellows_ros.identify.segment import fit_segment, MIN_RATE_PER_CUTOFF
from bellows_ros.models.derivatives import rates
from bellows_ros.models.segment import OUTPUTS, simulate_model
from bellows_ros.models.segment_plant import check_effects, SegmentPlant

INPUT_REQUIRED = ('t', 'psi', 'p1', 'p2')  # a simulation input needs no measured torque


def _read(path, params, required=None):
    """Read a segment file (data.read_table) and check 0 ≤ p ≤ p_max on both chains."""
    table = data.read_table(path, 'segment', required)
    for name in ('p1', 'p2'):
        data.check_range(table, name, 0.0, params.p_max, 'Pa')
    return table


def _psi_dot(table):
    return table['psi_dot'] if 'psi_dot' in table else rates(table['t'], table['psi'])


def simulate(input_path, output_path, params_path, effects):
    """Run the model (no effects) or the plant (effects: name -> {param: float}); write the CSV."""
    config = load_segment(params_path)
    params = config.model
    effects = check_effects(effects)
    table = _read(input_path, params, INPUT_REQUIRED)
    if not effects:
        outputs = simulate_model(params, table['psi'], table['p1'], table['p2'], _psi_dot(table))
    else:
        outputs = _run_plant(params, config.plant, effects, table)
    data.write_csv(output_path, table, outputs)
    return 0


def _run_plant(params, plant_params, effects, table):
    t = table['t']
    steps = np.diff(t, prepend=t[0] - (t[1] - t[0] if len(t) > 1 else 1e-3))
    plant = SegmentPlant(params, plant_params, effects, seed=0, psi0=float(table['psi'][0]))
    measured, true = [], []
    for dt, psi, p1, p2 in zip(steps.tolist(), table['psi'].tolist(), table['p1'].tolist(),
                               table['p2'].tolist()):
        sample = plant.step(dt, p1, p2, psi_imposed=psi)
        measured.append((sample.psi, sample.psi_dot, sample.p1, sample.p2, sample.tau_ext,
                         plant.tau_motion))
        # the plant's own τ_drive: paper A's with contact_hysteresis, else the previous model's
        true.append(plant.outputs._replace(tau_drive=plant.tau_drive))
    measured, true = np.array(measured), np.array(true)
    outputs = {'p1_cmd': table['p1'], 'p2_cmd': table['p2']}
    for k, name in enumerate(('psi', 'psi_dot', 'p1', 'p2', 'tau_ext', 'tau_motion')):
        outputs[name] = measured[:, k]
    for k, name in enumerate(OUTPUTS):
        outputs[name] = true[:, k]
    return outputs


def _filter_summary(fit, wanted):
    """One line: which input low-pass the fit used (`wanted`: the file's cutoff, Hz)."""
    if fit.input_cutoff is not None:
        return (f'inputs p1, p2, psi, psi_dot low-passed at {fit.input_cutoff:g} Hz (zero-phase '
                f'Butterworth, data at {fit.rate:.4g} Hz); tau_ext not filtered')
    if not wanted:
        return 'inputs not filtered (segment.identify.input_cutoff = 0)'
    return (f'inputs NOT filtered: data at {fit.rate:.4g} Hz is below '
            f'{MIN_RATE_PER_CUTOFF:g} x the '
            f'segment.identify.input_cutoff of {wanted:g} Hz')


def identify(args):
    """Fit paper A's model to DATA, write the parameters, print held-out errors of both models."""
    config = load_segment(args.params)
    params = config.model
    table = _read(args.data, params)
    if len(table) < 50:
        raise DataError(table.path, f'only {len(table)} rows: identification needs at least 50')
    # The membrane's torque changes with the angle at a held pressure: only the angle must move.
    data.check_moves(table, 'psi', 'the angle must move to show the restoring and friction '
                     'torques')
    fit = fit_segment(params, table.values, config.identify.input_cutoff, seed=args.seed,
                      progress=not args.quiet)
    header = (f'bellows identify segment {args.data}\n'
              f'held-out RMSE {fit.heldout["model"][0]:.4g} N·m (previous model '
              f'{fit.heldout["previous"][0]:.4g} N·m) on the last {fit.heldout_rows} rows; '
              f'{_filter_summary(fit, config.identify.input_cutoff)}')
    from bellows_ros.params import write_file
    # The whole file (the plant and identification settings as given): one file to read back.
    write_file(args.output, config._replace(model=fit.params).flat(), header=header,
               check=load_segment)
    mu, gamma = fit.params.ogden_mu, fit.params.ogden_gamma
    print(f'fitted: mu = [{mu[0]:.6g}, {mu[1]:.6g}] N/m, '
          f'gamma = [{gamma[0]:.4g}, {gamma[1]:.4g}], '
          f'c_psi0 = {fit.params.restoring_c_psi0:.4g}, '
          f'c_psi0_p = {fit.params.restoring_c_psi0_p:.4g} rad '
          f'({fit.evaluations} evaluations)')
    print(_filter_summary(fit, config.identify.input_cutoff))
    print(f'held-out error on the last {fit.heldout_rows} of '
          f'{fit.train_rows + fit.heldout_rows} rows '
          f'(against the raw measured tau_ext):')
    print(f'  {"model":<34} {"RMSE N·m":>10} {"MAE N·m":>10}')
    print(f'  {"paper A (29) with strain memory":<34} '
          f'{fit.heldout["model"][0]:10.4f} {fit.heldout["model"][1]:10.4f}')
    print(f'  {"previous model (34), refitted":<34} '
          f'{fit.heldout["previous"][0]:10.4f} {fit.heldout["previous"][1]:10.4f}')
    print(f'wrote {args.output}')
    return 0
