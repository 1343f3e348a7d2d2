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

"""`bellows export {segment|actuator} BAG --output OUT.csv`: a recording's data table as CSV."""


def add_arguments(parser):
    parser.add_argument('system', choices=('segment', 'actuator'))
    parser.add_argument('data', metavar='BAG', help='rosbag2 directory (or a CSV file)')
    parser.add_argument('--output', required=True, metavar='OUT.csv',
                        help='CSV with the columns `bellows identify` and `bellows diagnose` read')


def run(args):
    import sys

    from bellows_ros.data import read_table, write_csv
    from bellows_ros.outputs import check_output
    check_output(args.output, inputs=(args.data,))  # before any work
    table = read_table(args.data, args.system)
    write_csv(args.output, table, {})
    print(f'bellows export {args.system}: {len(table)} rows ({", ".join(table.names)}) -> '
          f'{args.output}', file=sys.stderr)
    return 0
