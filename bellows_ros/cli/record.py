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

"""`bellows record --output DIR [--topics T ...] [--namespace NS] [--duration S]`: rosbag2."""
from bellows_ros.config.ranges import option_type


def add_arguments(parser):
    parser.add_argument('--output', required=True, metavar='DIR',
                        help='rosbag2 directory to create (MCAP)')
    parser.add_argument('--topics', nargs='+', metavar='TOPIC',
                        help='topics to record (default: every topic of the contract)')
    parser.add_argument('--namespace', default='/', metavar='NS',
                        help="the graph's namespace: its relative topics are recorded under it "
                        "(default: '/')")
    parser.add_argument('--duration', type=option_type('record.duration'), metavar='S',
                        help='stop after S seconds (default: record until Ctrl-C)')


def run(args):
    from bellows_ros.runtime.record import record_command
    return record_command(args)
