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

"""`bellows simulate|identify actuator` (docs/interfaces.md, docs/actuator.md)."""
import sys

import numpy as np

from bellows_ros.config.actuator import load_actuator, params_to_flat
from bellows_ros.errors import BellowsError, DataError, ParameterError
from bellows_ros.identify.actuator import (fit_actuator, GasLost, LaggedCorrelation, LEAK_HINT,
                                           parameter_count, STRUCTURE_LAG, volume_error)
from bellows_ros.io import params as param_files
from bellows_ros.io.data import check_moves, check_range, CsvOutput, read_chunks, read_record
from bellows_ros.models.actuator import evaluate_array
from bellows_ros.models.actuator_plant import ActuatorPlant, effect_parameters


def _check_compressions(table, params):
    """Compressions must lie within the travel limits of the YAML (geometry and end stops)."""
    c, s = params.chamber, params.spring
    check_range(table, 'x_c', c.x_min, c.x_max, 'm')
    check_range(table, 'x_s', s.x_min, s.x_max, 'm')


def simulate(input_path, output_path, params_path, effects):
    """
    Model (no effects) or plant (effects) over the input's x_c, x_s; writes input + p, f, k.

    With effects the plant is driven by the input: x_c moves the lead-screw nut (the plate follows
    through the backlash, if any), x_s is imposed; sensors are noise-free so the output shows the
    effects alone. p and f columns of the input, if any, are replaced by the simulated ones.
    Read, run and written a chunk at a time (data.read_chunks), the plant's state carried on.
    """
    config = load_actuator(params_path)
    params = config.model
    chosen = effect_parameters(config.plant, effects) if effects else {}
    plant, last, rows = None, None, 0
    with CsvOutput(output_path) as output:
        # p and f are outputs here, not inputs
        for table in read_chunks(input_path, 'actuator', ('t', 'x_c', 'x_s')):
            _check_compressions(table, params)
            x_c, x_s, t = table['x_c'], table['x_s'], table['t']
            if not chosen:
                p, f, k = evaluate_array(params, x_c, x_s)
            else:
                if plant is None:
                    plant = ActuatorPlant(params, config.plant, chosen, noise=False, x_c0=x_c[0],
                                          x_s0=x_s[0])
                p, f, k = _run_plant(plant, t, x_c, x_s, last)
                last = t[-1]
            output.write(table, {'p': p, 'f': f, 'k': k})
            rows += len(t)
    what = 'model' if not chosen else 'plant with ' + ', '.join(chosen)
    print(f'bellows simulate actuator: {rows} rows, {what} -> {output_path}', file=sys.stderr)
    return 0


def _run_plant(plant, t, x_c, x_s, last=None):
    """Return the plant's p, f, k at each row; `last`: the previous chunk's last time, or None."""
    n = len(t)
    p, f, k = np.empty(n), np.empty(n), np.empty(n)
    start = 0
    if last is None:  # the first row is the plant's initial state
        p[0], f[0], k[0] = plant.pressure, plant.force, plant.stiffness
        start, last = 1, t[0]
    for i in range(start, n):
        sample = plant.step_nut(t[i] - last, x_c[i], x_s_imposed=x_s[i])
        p[i], f[i], k[i] = sample.p, sample.f, plant.stiffness
        last = t[i]
    return p, f, k


# Rows per fitted number: with fewer the fit follows the noise (and 1 row fits anything).
ROWS_PER_PARAMETER = 10


def _check_identifiable(record, params, run, leak=False):
    """Refuse a record that cannot determine the parameters: too short, or inputs that stay put."""
    table, stats = record.table, record.stats
    runs = 1 if run is None else len(np.unique(run))
    count = parameter_count(params, runs, leak=leak)
    needed = ROWS_PER_PARAMETER * count
    if record.rows < needed:
        raise DataError(table.path, f'only {record.rows} rows: identification fits '
                        f'{count} numbers and needs at least {needed} '
                        f'rows ({ROWS_PER_PARAMETER} per number)')
    check_moves(table, 'x_c', 'the air-chamber compression must vary to separate the tube '
                'volume from the gas amount', stats)
    check_moves(table, 'x_s', 'the spring compression must vary to fit its force', stats)
    check_moves(table, 'p', 'the pressure must vary with the compressions in a sealed volume',
                stats)


def _not_sealed(data, evidence, leak=False):
    """Refuse a record that breaks the gas assumption (sealed, or leaking), naming the evidence."""
    gas = 'one leaking' if leak else 'one sealed'
    hint = '' if leak else LEAK_HINT
    return BellowsError(
        f'{data}: identification refused: the record does not behave as {gas}, isothermal '
        f'gas volume ({evidence}; an air leak, heat exchange, a lagging sensor, backlash?); run '
        f'`bellows diagnose actuator` on it to find what it shows{hint}')


def _raw_structure(path, fit, rate):
    """`leftover_structure` of the fitted model's volume error over every raw row of `path`."""
    structure = LaggedCorrelation(rate)
    lost = GasLost()
    for chunk in read_chunks(path, 'actuator'):
        run = chunk['run'] if 'run' in chunk else None
        taken = None if fit.leak is None else fit.leak * lost.add(chunk['t'], chunk['p'], run)
        structure.add(volume_error(fit.params, fit.amounts, chunk['x_c'], chunk['x_s'],
                                   chunk['p'], run, taken))
    return structure.result()


def _check_fit(path, data, leak):
    """Read the fitted file back with the actuator loader; a refusal explains the record."""
    try:
        load_actuator(path)
    except ParameterError as exc:
        problem = str(exc).split(': ', 1)[-1]
        raise _not_sealed(data, f'the fit gives an impossible value: {problem}', leak) from None


def identify(args):
    """Fit V_tube, P0 (p_ref), E_V, F_MTS and E_F to DATA; write them as a ROS 2 parameter file."""
    config = load_actuator(args.params)
    params = config.model
    # A record of any length: its raw chunks checked, block means fitted (data.read_record).
    record = read_record(args.data, 'actuator',
                         per_chunk=lambda chunk: _check_compressions(chunk, params))
    table = record.table
    run = table['run'] if 'run' in table else None
    _check_identifiable(record, params, run, args.leak)
    rate = 1.0 / float(np.median(np.diff(table['t'])))
    try:
        fit = fit_actuator(params, table['x_c'], table['x_s'], table['p'], table['f'], run=run,
                           seed=args.seed, progress=not args.quiet, rate=rate,
                           t=table['t'] if args.leak else None)
    except ParameterError as exc:  # the fitted numbers describe no device (a gas law with no root)
        raise _not_sealed(args.data, f'the fitted parameters are impossible: {exc}',
                          args.leak) from None
    correlation, bound = fit.structure
    if record.factor > 1:  # block means hide the noise: the raw rows' error, chunk by chunk
        correlation, bound = _raw_structure(args.data, fit, rate * record.factor)
    if correlation > bound:
        raise _not_sealed(args.data, f'the volume error stays correlated over {STRUCTURE_LAG:g} '
                          f's: {correlation:.2f}, where noise stays below {bound:.3f}', args.leak)
    fitted = fit.params
    leak = '' if fit.leak is None else f', air leak G = {fit.leak:.3g} m^3/(s Pa)'
    header = (f'bellows identify actuator {args.data}\n'
              f'volume error rms {fit.volume_error_ml[0]:.3f} mL, '
              f'force error rms {fit.force_error_n[0]:.3f} N{leak}')
    # The whole file (drive, sensors and effects as given): one file to read back. It replaces
    # the output only once its own loader has read it (an impossible fit is refused, not written).
    param_files.write_file(args.output, params_to_flat(fitted, config.plant), header,
                           check=lambda path: _check_fit(path, args.data, args.leak))
    rms, low, high = fit.volume_error_ml
    print(f'volume error: {low:+.2f} mL to {high:+.2f} mL (rms {rms:.3f} mL) '
          f'over {fit.rows} samples')
    if record.factor > 1:
        print(f'record of {record.rows} rows fitted as {len(table)} block means of '
              f'{record.factor} rows (over data.FIT_ROWS)')
    rms, low, high = fit.force_error_n
    print(f'force error: {low:+.2f} N to {high:+.2f} N (rms {rms:.3f} N)')
    print(f'V_tube = {fitted.v_tube * 1e6:.2f} mL, '
          f'P0 (p_ref at x_c = {fitted.x_c_ref * 1e3:g} mm) = '
          f'{fitted.p_ref:.0f} Pa, F_MTS = [{", ".join(f"{v:.5g}" for v in fitted.f_mts)}], '
          f'E_F = [{", ".join(f"{v:.5g}" for v in fitted.e_f)}]')
    if fit.leak is not None:
        print(f'air leak conductance G = {fit.leak:.3g} m^3/(s Pa) (dN/dt = -G P (P - P_atm))'
              + ('; P0 is the gas at the first row' if fit.leak else
                 ': none found, fitted as sealed'))
    print(f'wrote {args.output}')
    return 0
