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

"""`bellows reindex BAG`: rebuild what readers need in a recording that was killed."""


def add_arguments(parser):
    parser.add_argument('bag', metavar='BAG', help='rosbag2 directory written by bellows record')


def run(args):
    from bellows_ros.io.bag_repair import DAMAGED_SUFFIX, repair
    result = repair(args.bag)
    total = sum(result.counts.values())
    if not result.repaired:
        print(f'bellows reindex: {args.bag} opens as it is ({total} messages); nothing to do')
        return 0
    for topic, count in result.counts.items():
        print(f'{topic}: {count} messages')
    print(f'bellows reindex: rebuilt {args.bag}: {total} messages kept; the damaged file is kept '
          f'beside it (*.mcap{DAMAGED_SUFFIX})')
    return 0
