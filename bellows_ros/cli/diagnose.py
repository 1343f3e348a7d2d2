"""`bellows diagnose {segment|actuator} DATA --report DIR` (owned by the model-doctor work)."""


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
    from bellows_ros.doctor.report import diagnose_command
    return diagnose_command(args)
