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
`bellows diagnose {segment|actuator} DATA --report DIR`: all the doctor's file work.

Reads the parameters (config/<system>.yaml with --params laid over it) and the record (CSV or
rosbag2 directory), hands both to the doctor (`bellows_ros.doctor.diagnosis.diagnose`, which
takes data and returns a `Diagnosis`), and writes DIR/report.json, details.json, report.md,
extended.yaml and the PNG plots (their contents: `bellows_ros.doctor.report`).
"""
import json
import time


def add_arguments(parser):
    parser.add_argument('system', choices=('segment', 'actuator'))
    parser.add_argument('data', metavar='DATA', help='CSV file or rosbag2 directory')
    parser.add_argument('--report', required=True, metavar='DIR',
                        help='where report.json, report.md and plots go')
    parser.add_argument('--params', metavar='P.yaml',
                        help='parameters laid over config/<system>.yaml '
                             '(geometry, material, nominal values)')
    parser.add_argument('--quiet', action='store_true', help='no progress bar')


def run(args):
    from bellows_ros.doctor.report import summary_line
    from bellows_ros.io.outputs import check_report_directory
    check_report_directory(args.report, inputs=(args.data, args.params))  # before any work
    started = time.perf_counter()
    params = load_params(args.system, args.params)
    table, extra = read_for_doctor(args.data, args.system, params.model)
    read = time.perf_counter() - started
    from bellows_ros.doctor.diagnosis import diagnose
    result = diagnose(args.system, table, params, progress=not args.quiet, **extra)
    result.timings = {name: seconds + read for name, seconds in result.timings.items()}
    write_report(result, args.report)
    print(summary_line(result, args.report))
    return 0


def read_for_doctor(path, system, model):
    """
    Read a record of any length for the doctor: (table, extra arguments of `diagnose`).

    `data.read_record`: a record of up to data.FIT_ROWS rows whole, a longer one as block means,
    its raw chunks checked (`checks.RawChecks`) and their noise floors taken
    (`diagnosis.raw_noise`; the median over the chunks), since averaging hides the noise.
    """
    import numpy as np

    from bellows_ros.io.data import read_record
    from bellows_ros.doctor.checks import RawChecks
    from bellows_ros.doctor.diagnosis import raw_noise
    check = RawChecks(system)

    def per_chunk(table):
        check(table)
        return raw_noise(system, table, model)
    record = read_record(path, system, per_chunk=per_chunk)
    if record.factor == 1:
        return record.table, {}
    floors = {name: float(np.median([chunk[name] for chunk in record.chunks]))
              for name in record.chunks[0]}
    return record.table, {'raw_noise': floors, 'factor': record.factor}


def load_params(system, params_path):
    """Return the parameter objects of `system`: config/<system>.yaml, `params_path` over it."""
    if system == 'actuator':
        from bellows_ros.config.actuator import load_actuator
        return load_actuator(params_path)
    from bellows_ros.config.segment import load_segment
    return load_segment(params_path)


def write_report(d, report):
    """
    Write every output file of the diagnosis `d` as the report directory `report`.

    The report is built in a new directory beside it and swapped in whole (io/outputs.py): a reader
    never finds a new report.json beside an old report's plots.
    """
    import matplotlib.pyplot as plt

    from bellows_ros.io import params as param_files
    from bellows_ros.doctor.plots import figures
    from bellows_ros.doctor.report import (details_dict, extended_header, EXTENDED_FILE,
                                           markdown, report_dict)
    from bellows_ros.io.outputs import report_directory
    with report_directory(report) as directory:
        (directory / 'report.json').write_text(json.dumps(report_dict(d), indent=2) + '\n')
        (directory / 'details.json').write_text(json.dumps(details_dict(d), indent=2,
                                                           default=float) + '\n')
        param_files.write_file(directory / EXTENDED_FILE, d.extended_flat, extended_header(d))
        plots = []
        for name, figure in figures(d):
            figure.savefig(directory / name, dpi=90)
            plt.close(figure)
            plots.append(name)
        (directory / 'report.md').write_text(markdown(d, plots))
