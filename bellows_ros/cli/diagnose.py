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
