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
Files in and out: tables, CSV records, rosbag2 recordings, ROS 2 parameter files, atomic outputs.

The base layer of the package (test/test_import_layers.py): everything here may be used by every
other part, and it imports none of them but `errors` and `interfaces`.
"""
__all__ = [
    'table',       # Table: named columns of a record, with the checks every reader applies
    'data',        # CSV records: read (bounded, chunked, checked), write, the CSV outputs
    'bag',         # rosbag2 recordings read into a Table (rosbags)
    'bag_lock',    # the lock a recording holds while it is written
    'bag_repair',  # `bellows reindex`: a killed recording made readable again
    'params',      # ROS 2 parameter files (rcl's YAML rules), read and written
    'outputs',     # outputs written atomically, never over an input or a special file
]
