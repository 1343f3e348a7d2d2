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
`bellows export {segment|actuator} BAG --output OUT.csv [--start S] [--end S]`: a table as CSV.

--start/--end keep the rows whose time t (s, the record's own column) lies between them: how a
record with a gap (which the doctor refuses) is split into parts it can diagnose.
"""
import argparse
import math


def time_s(text):
    """Parse a finite time, s (an argparse type)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a time in s, got {text!r}') from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f'expected a finite time in s, got {text!r}')
    return value


def add_arguments(parser):
    parser.add_argument('system', choices=('segment', 'actuator'))
    parser.add_argument('data', metavar='BAG', help='rosbag2 directory (or a CSV file)')
    parser.add_argument('--output', required=True, metavar='OUT.csv',
                        help='CSV with the columns `bellows identify` and `bellows diagnose` read')
    parser.add_argument('--start', type=time_s, metavar='S',
                        help='keep the rows from this time t on, s (default: the first)')
    parser.add_argument('--end', type=time_s, metavar='S',
                        help='keep the rows up to this time t, s (default: the last)')


def run(args):
    import sys

    from bellows_ros.io.data import read_table, write_csv
    from bellows_ros.errors import ParameterError
    from bellows_ros.io.outputs import check_output
    start = -math.inf if args.start is None else args.start
    end = math.inf if args.end is None else args.end
    if not start < end:
        raise ParameterError(f'--start {args.start:g} s must be before --end {args.end:g} s')
    check_output(args.output, inputs=(args.data,))  # before any work
    # The rows between --start and --end are cut before a channel's gaps are looked for: how a
    # record whose wrench stopped is exported up to where it stopped.
    span = None if args.start is None and args.end is None else (start, end)
    table = read_table(args.data, args.system, span=span)
    write_csv(args.output, table, {})
    print(f'bellows export {args.system}: {len(table)} rows ({", ".join(table.names)}) -> '
          f'{args.output}', file=sys.stderr)
    return 0
