"""
`bellows simulate`: the model, or the plant with effects, over an input file.

    bellows simulate {segment|actuator} --input IN.csv --output OUT.csv [--params P.yaml]
        [--effect ...]
"""
import importlib

from bellows_ros.cli.effects import parse_effect


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
    effects = dict(parse_effect(text) for text in args.effect)
    system = importlib.import_module(f'bellows_ros.cli.{args.system}')
    return system.simulate(args.input, args.output, args.params, effects)
