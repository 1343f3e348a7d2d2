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
runtime.realtime: SCHED_FIFO for every thread of a node's process, and the CPU latency limit.

The limit is held while the node runs; where either is refused, one clear warning each.

Each case runs in a child process, so the test runner itself never changes its scheduling nor
holds a latency request. Whether this machine grants SCHED_FIFO is asked of the kernel first (a
throw-away child), and the node must then do exactly what the kernel allows: switch every thread,
or warn and carry on. The latency limit is read back from the kernel (/dev/cpu_dma_latency).
"""
import math
import os
import subprocess
import sys

from bellows_ros.runtime import realtime

# What `realtime` asks of a node: its declared parameters and its logger (printed here).
NODE = r"""
import os, sys, threading
from bellows_ros.runtime import realtime

class Param:
    def __init__(self, value): self.value = value

class Log:
    def info(self, m): print('INFO', m)
    def warn(self, m): print('WARN', m)

class Node:
    def __init__(self, **parameters): self.parameters = parameters
    def has_parameter(self, name): return name in self.parameters
    def get_parameter(self, name): return Param(self.parameters[name])
    def get_logger(self): return Log()
"""

CHILD = NODE + r"""
before = threading.Thread(target=threading.Event().wait, args=(5,), daemon=True)
before.start()                                    # a thread that exists before the request
granted = realtime.request(Node(realtime_priority=int(sys.argv[1])))
policies = {}
def report():
    policies['later'] = realtime.describe()       # a thread started after the request
later = threading.Thread(target=report)
later.start(); later.join()
policies['main'] = realtime.describe()
policies['before'] = (os.sched_getscheduler(before.native_id),
                      os.sched_getparam(before.native_id).sched_priority)
print('RESULT', granted, policies)
"""


def fifo_allowed():
    probe = subprocess.run([sys.executable, '-c', 'import os; os.sched_setscheduler(0, '
                            'os.SCHED_FIFO, os.sched_param(10))'], capture_output=True)
    return probe.returncode == 0


def run_child(priority):
    result = subprocess.run([sys.executable, '-c', CHILD, str(priority)], capture_output=True,
                            text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    return result.stdout


def test_every_thread_gets_fifo_or_one_warning():
    out = run_child(17)
    if fifo_allowed():
        assert 'RESULT True' in out, out
        assert "'main': 'SCHED_FIFO 17'" in out and "'later': 'SCHED_FIFO 17'" in out, out
        assert f"'before': ({__import__('os').SCHED_FIFO}, 17)" in out, out
        assert 'INFO SCHED_FIFO priority 17 on' in out
    else:
        assert 'RESULT False' in out, out
        assert "'main': 'SCHED_OTHER'" in out, out
        warnings = [line for line in out.splitlines() if line.startswith('WARN')]
        assert len(warnings) == 1 and 'rtprio' in warnings[0], out


def test_zero_leaves_scheduling_alone():
    out = run_child(0)
    assert 'RESULT False' in out and "'main': 'SCHED_OTHER'" in out, out
    assert 'WARN' not in out and 'INFO' not in out, out


LATENCY_CHILD = NODE + r"""
if 'unprivileged' in sys.argv:    # root drops to nobody: the device is then as closed as to a user
    os.setgid(65534)
    os.setuid(65534)
before = realtime.cpu_latency_in_force()
fd = realtime.limit_cpu_latency(Node(cpu_latency_limit=float(sys.argv[1])))
held = realtime.cpu_latency_in_force()
if fd is not None:
    os.close(fd)
print('RESULT', fd is not None, repr(before), repr(held), repr(realtime.cpu_latency_in_force()))
"""


def run_latency_child(limit, *flags):
    result = subprocess.run([sys.executable, '-c', LATENCY_CHILD, repr(limit), *flags],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    line = [line for line in result.stdout.splitlines() if line.startswith('RESULT')][0]
    held, before, during, after = line.split()[1:]
    return held == 'True', float(before), float(during), float(after), result.stdout


def test_the_cpu_latency_limit_holds_while_the_request_is_open_or_warns_once():
    held, before, during, after, out = run_latency_child(123e-6)
    if os.access(realtime.CPU_LATENCY_DEVICE, os.W_OK):
        assert held, out
        # The kernel keeps the least request: ours, unless another process holds a lower one.
        assert during == min(before, 123e-6), out
        assert after == before, out                      # closing withdrew it
        assert 'INFO CPU wake-up latency limited to 123 µs' in out, out
    else:
        assert not held and (during == before or math.isnan(during) and math.isnan(before)), out
        warnings = [line for line in out.splitlines() if line.startswith('WARN')]
        assert len(warnings) == 1 and realtime.CPU_LATENCY_DEVICE in warnings[0], out


def test_an_unprivileged_node_warns_once_and_runs_on():
    flags = ['unprivileged'] if os.geteuid() == 0 else []
    held, _, _, _, out = run_latency_child(0.0, *flags)
    assert not held, out
    warnings = [line for line in out.splitlines() if line.startswith('WARN')]
    assert len(warnings) == 1, out
    assert f'cpu_latency_limit 0 s not applied ({realtime.CPU_LATENCY_DEVICE}: ' in warnings[0], \
        out


def test_a_negative_limit_leaves_the_cpus_alone():
    held, before, during, after, out = run_latency_child(-1.0)
    assert not held and 'WARN' not in out and 'INFO' not in out, out
    assert during == before or (math.isnan(during) and math.isnan(before)), out
