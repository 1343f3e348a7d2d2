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

r"""
A bellows node that reports what rcl made of its `--ros-args`: name, parameters, topics.

    PROBE_SPEC='{"parameters": {...}, "bounds": {...}, "topics": [...]}' \
        python parameter_probe.py --ros-args ...

Declares the spec's parameters as a bellows node does (`declare_specs`: a Spec per parameter, its
default's type is the parameter's type, `bounds` {name: [low, high]} its inclusive bounds),
creates a Float64 publisher on each topic, and prints one JSON line: the node's name and namespace,
every declared parameter's value (and `use_sim_time`), and each topic as the publisher resolved it.
Mistakes end as any node's do: one line on stderr, exit status 2 (`run`).
"""
import json
import os
import sys

from bellows_ros.runtime import Node, run
from bellows_ros.runtime.parameters import Spec


class Probe(Node):
    """Declares, publishes, prints, and is done."""

    done = True

    def __init__(self, **kwargs):
        spec = json.loads(os.environ['PROBE_SPEC'])
        super().__init__(spec.get('node', 'probe'), **kwargs)
        bounds = spec.get('bounds', {})
        self.values = self.declare_specs([
            Spec(name, default, f"the probe's {name}", *bounds.get(name, (None, None)))
            for name, default in spec['parameters'].items()])
        self.topics = {topic: self.create_publisher(self.msg.Float64, topic, 10).topic_name
                       for topic in spec.get('topics', [])}

    def finish(self):
        self.values['use_sim_time'] = self.get_parameter('use_sim_time').value
        print(json.dumps({'name': self.get_name(),
                          'namespace': self.get_namespace(), 'parameters': self.values,
                          'topics': self.topics}), flush=True)


if __name__ == '__main__':
    sys.exit(run(Probe))
