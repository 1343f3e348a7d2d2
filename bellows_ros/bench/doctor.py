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
Benchmark of `bellows diagnose`: a 10-minute 1 kHz actuator record (600 000 rows).

Target (issue 6): under 60 s per diagnosis on the project machine. The reference, measured in the
same run, is reading the file and fitting and scoring the baseline only; the ratio says what the
search over the candidate causes costs on top of that.
"""
from pathlib import Path
import statistics
import tempfile
import time

import numpy as np

from bellows_ros.bench import Result
from bellows_ros.config.actuator import load_actuator
from bellows_ros.doctor.diagnosis import diagnose
from bellows_ros.io.data import read_table
from bellows_ros.papers.actuator_experiments import actuator_record

EFFECTS = {'air_leak': {'conductance': 3e-12}, 'sensor_lag': {'time_constant': 0.05}}


def _write(path, record, names=('t', 'x_c', 'x_s', 'p', 'f')):
    np.savetxt(path, np.column_stack([record[n] for n in names]), delimiter=',',
               header=','.join(names), comments='', fmt='%.10g')


def _median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def run(quick=False):
    duration, repeats = (60.0, 1) if quick else (600.0, 3)
    config = load_actuator()
    record = actuator_record(*config, EFFECTS, seed=1, duration=duration)
    with tempfile.TemporaryDirectory() as directory:
        path = Path(directory) / 'actuator_10min.csv'
        _write(path, record)

        def doctor(causes=None):
            # what `bellows diagnose` does before its report: read the file, then diagnose
            return diagnose('actuator', read_table(path, 'actuator'), config, causes=causes)
        reference_time, _ = _median_time(lambda: doctor(causes=()), repeats)
        full_time, result = _median_time(doctor, repeats)
    rows = len(record['t'])
    reference = Result('doctor: read + baseline only', reference_time, 's', repeats,
                       extra={'rows': rows})
    return [reference,
            Result(f'doctor: diagnose actuator, {rows} rows at 1 kHz', full_time, 's', repeats,
                   reference=reference.name, ratio=full_time / reference_time, target=60.0,
                   extra={'rows': rows, 'causes': list(result.causes),
                          'heldout_gain': f'{100 * result.gain:.1f} %',  # a fraction, not seconds
                          'fitted_samples': len(result.record)})]
