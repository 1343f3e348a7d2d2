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
`bellows simulate`: the model, or the plant with effects, over an input file.

    bellows simulate {segment|actuator} --input IN.csv --output OUT.csv [--params P.yaml]
        [--effect ...]
"""
import importlib

from bellows_ros.cli.effects import parse_effects
from bellows_ros.io.outputs import check_output


def add_arguments(parser):
    parser.add_argument('system', choices=('segment', 'actuator'))
    parser.add_argument('--input', required=True, metavar='IN.csv',
                        help='input samples (docs/interfaces.md)')
    parser.add_argument('--output', required=True, metavar='OUT.csv',
                        help='input columns plus model outputs')
    parser.add_argument('--params', metavar='P.yaml',
                        help='parameters laid over config/<system>.yaml')
    parser.add_argument('--effect', action='append', default=[], metavar='NAME[:k=v,...]',
                        help='run the plant with this physical effect switched on (repeatable)')


def run(args):
    check_output(args.output, inputs=(args.input, args.params))  # before any work
    effects = parse_effects(args.effect, args.system)
    system = importlib.import_module(f'bellows_ros.cli.{args.system}')
    return system.simulate(args.input, args.output, args.params, effects)
