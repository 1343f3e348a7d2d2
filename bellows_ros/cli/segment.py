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

from bellows_ros.config.segment import load_segment
from bellows_ros.errors import DataError
from bellows_ros.identify.segment import fit_segment, MIN_RATE_PER_CUTOFF
from bellows_ros.io import data
from bellows_ros.models.derivatives import rates
from bellows_ros.models.segment import OUTPUTS, SegmentModel, simulate_model
from bellows_ros.models.segment_plant import check_effects, SegmentPlant

INPUT_REQUIRED = ('t', 'psi', 'p1', 'p2')  # a simulation input needs no measured torque


def _read(path, params, required=None):
    """
    Read a segment file for a fit (data.read_record) and check 0 ≤ p ≤ p_max on both chains.

    Each raw chunk is checked, so an error names the file's own line. Returns a `data.Record`.
    """
    def check(table):
        for name in ('p1', 'p2'):
            data.check_range(table, name, 0.0, params.p_max, 'Pa')
    return data.read_record(path, 'segment', required, per_chunk=check)


def reduction_summary(record):
    """One line: what a fit of a `data.Record` ran on, or '' if on every row of the file."""
    if record.factor == 1:
        return ''
    return (f'record of {record.rows} rows fitted as {len(record.table)} block means of '
            f'{record.factor} rows (over data.FIT_ROWS = {data.FIT_ROWS} rows)')


def simulate(input_path, output_path, params_path, effects):
    """
    Run the model (no effects) or the plant (effects: name -> {param: float}); write the CSV.

    The input is read, run and written a chunk at a time (data.read_chunks), the model's or
    plant's state carried from one chunk to the next: the output is the same as from one pass,
    and memory does not grow with the record.
    """
    config = load_segment(params_path)
    params = config.model
    effects = check_effects(effects)
    run = _PlantRun(params, config.plant, effects) if effects else _ModelRun(params)
    with data.CsvOutput(output_path) as output:
        for table in data.read_chunks(input_path, 'segment', INPUT_REQUIRED):
            for name in ('p1', 'p2'):
                data.check_range(table, name, 0.0, params.p_max, 'Pa')
            output.write(table, run.chunk(table))
    return 0


class _ModelRun:
    """Paper A's model over a record's chunks: strain memory and the Ψ̇ estimate carried on."""

    def __init__(self, params):
        self.params, self.model = params, SegmentModel(params)
        self.last = None  # (t, psi, psi_dot) of the previous chunk's last row

    def chunk(self, table):
        t, psi = table['t'], table['psi']
        if 'psi_dot' in table:
            psi_dot = table['psi_dot']
        elif self.last is None:
            psi_dot = rates(t, psi)
        else:  # the backward difference of the first row needs the previous chunk's last
            last_t, last_psi, last_rate = self.last
            psi_dot = rates(np.r_[last_t, t], np.r_[last_psi, psi], initial=last_rate)[1:]
        self.last = (t[-1], psi[-1], psi_dot[-1])
        return simulate_model(self.params, psi, table['p1'], table['p2'], psi_dot, self.model)


class _PlantRun:
    """The simulated segment over a record's chunks, imposed Ψ, commanded pressures."""

    def __init__(self, params, plant_params, effects):
        self.params, self.plant_params, self.effects = params, plant_params, effects
        self.plant = self.last_t = None

    def chunk(self, table):
        t = table['t']
        if self.plant is None:
            self.plant = SegmentPlant(self.params, self.plant_params, self.effects, seed=0,
                                      psi0=float(table['psi'][0]))
            before = t[0] - (t[1] - t[0] if len(t) > 1 else 1e-3)
        else:
            before = self.last_t
        self.last_t = t[-1]
        return _run_plant(self.plant, np.diff(t, prepend=before), table)


def _run_plant(plant, steps, table):
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
    record = _read(args.data, params)
    table = record.table
    if record.rows < 50:
        raise DataError(table.path, f'only {record.rows} rows: identification needs at least 50')
    # The membrane's torque changes with the angle at a held pressure: only the angle must move.
    data.check_moves(table, 'psi', 'the angle must move to show the restoring and friction '
                     'torques', record.stats)
    fit = fit_segment(params, table.values, config.identify.input_cutoff, seed=args.seed,
                      progress=not args.quiet)
    header = (f'bellows identify segment {args.data}\n'
              f'held-out RMSE {fit.heldout["model"][0]:.4g} N·m (previous model '
              f'{fit.heldout["previous"][0]:.4g} N·m) on the last {fit.heldout_rows} rows; '
              f'{_filter_summary(fit, config.identify.input_cutoff)}')
    from bellows_ros.io.params import write_file
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
    if record.factor > 1:
        print(reduction_summary(record))
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
