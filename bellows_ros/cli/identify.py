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

"""`bellows identify {segment|actuator} DATA --output P.yaml`."""
import argparse
import importlib

from bellows_ros.errors import BellowsError
from bellows_ros.io.outputs import check_output


def add_arguments(parser):
    parser.add_argument('system', choices=('segment', 'actuator'))
    parser.add_argument('data', metavar='DATA', help='CSV file or rosbag2 directory')
    parser.add_argument('--output', required=True, metavar='P.yaml',
                        help='fitted parameters (ROS 2 YAML)')
    parser.add_argument('--params', metavar='P.yaml',
                        help='starting parameters laid over the defaults')
    parser.add_argument('--seed', type=seed, default=0,
                        help='seed for the multi-start search (0 .. 2**32 - 1)')
    parser.add_argument('--quiet', action='store_true', help='no progress bar')
    parser.add_argument('--leak', action='store_true',
                        help="actuator: fit an air leak's conductance too (a record that "
                             '`bellows diagnose actuator` found leaking)')


def seed(text):
    """Read a seed for NumPy's generators: a whole number 0 .. 2**32 - 1 (argparse type)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a whole number, got {text!r}') from None
    if not 0 <= value < 2 ** 32:
        raise argparse.ArgumentTypeError(f'expected 0 .. 2**32 - 1, got {value}')
    return value


def run(args):
    if args.leak and args.system != 'actuator':
        raise BellowsError('--leak: only the actuator holds a sealed gas that can leak')
    check_output(args.output, inputs=(args.data, args.params))  # before the fit, not after it
    system = importlib.import_module(f'bellows_ros.cli.{args.system}')
    return system.identify(args)
