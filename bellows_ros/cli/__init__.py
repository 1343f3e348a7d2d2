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
The `bellows` command (docs/interfaces.md): one entry point, one module per subcommand.

Each subcommand module has `add_arguments(parser)` and `run(args) -> int`. A `BellowsError` (a user
mistake: bad file, bad parameter, absent device) becomes one line on stderr and exit status 2.
SIGTERM and SIGHUP unwind like Ctrl-C (io.outputs.signals_as_exceptions), so no temporary file is
left behind; the exit status is then 128 + the signal's number, as the shell reports a signal.
"""
import argparse
import importlib
import signal
import sys

from bellows_ros.errors import BellowsError
from bellows_ros.identify.blas import one_blas_thread
from bellows_ros.io.outputs import Signalled, signals_as_exceptions

__all__ = ['main', 'build_parser', 'SUBCOMMANDS']

SUBCOMMANDS = {
    'simulate': 'run the model or the plant over an input file',
    'identify': 'fit model parameters to measured data',
    'diagnose': 'find what the simulation gets wrong, name the cause, extend the model',
    'bench': 'benchmarks: medians and ratios against a reference measured in the same run',
    'record': 'record the bellows topics to a rosbag2 (MCAP) without ROS',
    'reindex': 'rebuild what readers need in a recording that was killed (ros2 bag reindex)',
    'export': "a recording's data table (segment or actuator) as CSV",
    'stiffness': 'the actuator stiffness a record measured, per spring cycle',
}


class Parser(argparse.ArgumentParser):
    """argparse with its errors as one line (`bellows identify: error: ...`), exit status 2."""

    def error(self, message):
        print(f'{self.prog}: error: {message} (see {self.prog} --help)', file=sys.stderr)
        sys.exit(2)


def build_parser():
    parser = Parser(prog='bellows', description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest='command', required=True, metavar='COMMAND')
    for name, help_text in SUBCOMMANDS.items():
        module = importlib.import_module(f'bellows_ros.cli.{name}')
        module.add_arguments(sub.add_parser(name, help=help_text, description=help_text))
    return parser


def main(argv=None):
    args = build_parser().parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)   # what was asked, for records
    module = importlib.import_module(f'bellows_ros.cli.{args.command}')
    # `record` takes SIGINT and SIGTERM itself (runtime/record.py): an exception raised into its
    # writer would corrupt the chunk being written.
    signals = () if args.command == 'record' else (signal.SIGTERM, signal.SIGHUP)
    try:
        with signals_as_exceptions(signals), one_blas_thread():
            return module.run(args) or 0
    except Signalled as exc:
        print(f'bellows {args.command}: stopped by {exc}; nothing half written was kept',
              file=sys.stderr)
        return 128 + exc.signum
    except BellowsError as exc:
        print(f'bellows {args.command}: error: {exc}', file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f'bellows {args.command}: interrupted', file=sys.stderr)
        return 130


if __name__ == '__main__':
    sys.exit(main())
