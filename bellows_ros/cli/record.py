"""`bellows record` (owned by the node-graph work)."""


def add_arguments(parser):
    parser.add_argument('--output', required=True, metavar='DIR', help='rosbag2 directory to create (MCAP)')


def run(args):
    from bellows_ros.runtime.record import record_command
    return record_command(args)
