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
A stand-in for bench/graph.py's GraphRun: scripted /diagnostics, no process, no DDS.

The graph benches' `_measure` run unchanged against it, so a test holds what they make of the
reports a graph sends (medians, ratios, counts, the records) without running a graph.
`StubGraphRun(script, logs)` is called as the class is (`GraphRun(domain, name)`) and returns
itself. `script` holds {status name: {key: value}} maps: `running` is delivered on every `spin`,
each of `window` once in turn by `cpu_window` (which returns `cpu`, `steal`), and `stopped`
becomes what `spin` delivers once a process is stopped.
"""
from types import SimpleNamespace


def diagnostic_array(statuses):
    """Return a /diagnostics array as a subscriber sees it: {name: {key: value}} -> .status."""
    return SimpleNamespace(status=[
        SimpleNamespace(name=name, values=[SimpleNamespace(key=key, value=str(value))
                                           for key, value in values.items()])
        for name, values in statuses.items()])


class StubGraphRun:
    """GraphRun's interface over a script of reports; records what the bench started."""

    def __init__(self, script, logs):
        self.script, self.logs = script, logs
        self.node = self
        self.domain = self.name = None
        self.callbacks, self.topics = [], []
        self.started, self.stopped = {}, []
        self.running = script['running']

    def __call__(self, domain, name='bench_graph'):
        self.domain, self.name = domain, name
        return self

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def create_subscription(self, kind, topic, callback, depth):
        self.topics.append(topic)
        self.callbacks.append(callback)

    def _deliver(self, statuses):
        for callback in self.callbacks:
            callback(diagnostic_array(statuses))

    def spin(self, seconds):
        self._deliver(self.running)

    def start(self, name, command, env):
        self.started[name] = (command, env)

    def cpu_window(self, seconds):
        for statuses in self.script['window']:
            self._deliver(statuses)
        return dict(self.script['cpu']), self.script['steal']

    def stop(self, name, timeout=10.0):
        self.stopped.append(name)
        self.running = self.script['stopped']
        return 0
