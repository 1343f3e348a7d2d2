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

"""`bellows stiffness DATA [--setpoint K]`: the actuator stiffness a record measured, per cycle."""


from bellows_ros.config.ranges import option_type


def add_arguments(parser):
    parser.add_argument('data', metavar='DATA', help='actuator CSV file or rosbag2 directory '
                        '(t, x_c, x_s, p, f; the spring cycled over 0-12 mm)')
    parser.add_argument('--params', metavar='P.yaml',
                        help='parameters laid over config/actuator.yaml (only the spring range '
                             'of the stiffness figure, actuator.stiffness.x_s_low/x_s_high, is '
                             'read)')
    parser.add_argument('--window', type=option_type('stiffness.window'), default=4.0,
                        metavar='S',
                        help='window length, s: one period of the spring motion (default 4.0)')
    parser.add_argument('--setpoint', type=option_type('stiffness.setpoint'), metavar='K',
                        help='stiffness set-point, N/m: also print the error against it')


def run(args):
    import math

    from bellows_ros.config.actuator import load_actuator_params
    from bellows_ros.io.data import read_table
    from bellows_ros.errors import BellowsError
    from bellows_ros.identify.measured_stiffness import measured_stiffness
    params = load_actuator_params(args.params)
    table = read_table(args.data, 'actuator')
    windows = measured_stiffness(table, params.x_s_low, params.x_s_high, args.window)
    if not windows:
        raise BellowsError(f'{args.data}: no window of {args.window:g} s where the chamber held '
                           f'still and the spring covered {params.x_s_low * 1e3:g}-'
                           f'{params.x_s_high * 1e3:g} mm')
    for w in windows:
        line = f't {w.t:8.2f} s  x_c {w.x_c * 1e3:7.2f} mm  stiffness {w.k:7.1f} N/m'
        if args.setpoint is not None:
            line += f'  error {w.k - args.setpoint:+7.1f} N/m'
        print(line)
    if args.setpoint is not None:
        rms = math.sqrt(sum((w.k - args.setpoint) ** 2 for w in windows) / len(windows))
        print(f'stiffness error against {args.setpoint:g} N/m over {len(windows)} cycles: '
              f'RMS {rms:.1f} N/m')
    return 0
