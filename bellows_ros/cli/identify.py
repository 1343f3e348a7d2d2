"""`bellows identify {segment|actuator} DATA --output P.yaml`."""
import importlib


def add_arguments(parser):
    parser.add_argument('system', choices=('segment', 'actuator'))
    parser.add_argument('data', metavar='DATA', help='CSV file or rosbag2 directory')
    parser.add_argument('--output', required=True, metavar='P.yaml',
                        help='fitted parameters (ROS 2 YAML)')
    parser.add_argument('--params', metavar='P.yaml',
                        help='starting parameters laid over the defaults')
    parser.add_argument('--seed', type=int, default=0, help='seed for the multi-start search')
    parser.add_argument('--quiet', action='store_true', help='no progress bar')


def run(args):
    system = importlib.import_module(f'bellows_ros.cli.{args.system}')
    return system.identify(args)
