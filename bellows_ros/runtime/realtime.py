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
Real-time scheduling for the nodes that run 1 kHz loops (driver, model, simulated devices).

On a general-purpose Linux kernel a Python loop at normal priority is preempted by whatever else
runs; on a 2-core machine that is what turns a 0.3 ms median latency into a 5-10 ms p99. The usual
remedy in ROS 2 control (ros2_control's controller manager does the same) is SCHED_FIFO for the
process's threads, granted by an rtprio limit (`/etc/security/limits.conf`) or CAP_SYS_NICE. When
it is not granted the node says so once and carries on with normal scheduling.

A loop that sleeps between ticks also pays for waking its CPU. An idle CPU sleeps in an idle state
(on a virtual machine: the vCPU halts and the hypervisor deschedules it), and leaving it costs from
tens of microseconds to milliseconds. The kernel's PM QoS request `/dev/cpu_dma_latency` bounds
that exit latency for as long as the requesting file stays open; 0 keeps idle CPUs polling.
cyclictest makes the same request by default, and real-time tuning guides (tuned's
latency-performance profile) set it. Measured on this project's 2-core VM on one day: a lone 1 kHz
loop's p99 wake-up lateness 0.27-11.6 ms without it, 0.08-1.5 ms with 0 (docs/nodes.md). The price
is power: idle CPUs spin while the node runs.

API
---
- ``declare(node) -> int``: declares the node's `realtime_priority` (default 0) and
  `cpu_latency_limit` (s, default -1 = leave the CPUs' idle states alone) parameters and checks
  them (ParameterError); call it with the node's other parameters. Returns the priority.
- ``request(node) -> bool``: the node's `realtime_priority` parameter (when it declares one): 1-99
  = SCHED_FIFO at that priority for every thread of the process, and so for the threads it starts
  later (they inherit it); 0 leaves the scheduling alone. Logs the outcome on the node's logger.
  `runtime.run` calls it once the node is built, so a node only declares the parameter.
- ``limit_cpu_latency(node) -> int | None``: the node's `cpu_latency_limit` (>= 0) requested from
  the kernel; returns the file descriptor that holds the request (`runtime.run` closes it at
  shutdown), or None when off or not permitted (one warning).
- ``hold_cpu_latency(limit) -> int``, ``cpu_latency_in_force() -> float``: the PM QoS request
  itself, and the limit in force now (the least of every process's request), s.
- ``describe() -> str``: the calling thread's policy, e.g. ``'SCHED_FIFO 50'`` or ``'SCHED_OTHER'``
  (reported on /diagnostics).
"""
import os
import struct

from bellows_ros.runtime.parameters import Spec

CPU_LATENCY_DEVICE = '/dev/cpu_dma_latency'
CPU_LATENCY_MAX = 2000.0  # s: the kernel's ceiling (2e9 µs in a signed 32-bit word)

_POLICIES = {getattr(os, name): name for name in
             ('SCHED_OTHER', 'SCHED_FIFO', 'SCHED_RR', 'SCHED_BATCH', 'SCHED_IDLE')
             if hasattr(os, name)}


def set_fifo(priority):
    """
    SCHED_FIFO at `priority` for every thread of this process; returns how many threads.

    Raises PermissionError when neither an rtprio limit nor CAP_SYS_NICE allows it.
    """
    threads = 0
    # The main thread first: the threads started later (device readers, DDS) inherit its policy.
    for tid in [os.getpid()] + sorted(int(t) for t in os.listdir('/proc/self/task')
                                      if int(t) != os.getpid()):
        try:
            os.sched_setscheduler(tid, os.SCHED_FIFO, os.sched_param(priority))
            threads += 1
        except ProcessLookupError:
            pass  # the thread ended in between
    return threads


def _priority_problem(priority):
    return '' if priority == 0 or 1 <= priority <= 99 else 'expected 0 (off) or 1..99'


def _latency_problem(limit):
    return '' if limit < 0 or 0 <= limit <= CPU_LATENCY_MAX else (
        f'expected a negative value (off) or 0..{CPU_LATENCY_MAX:g} s')


PARAMETERS = (
    Spec('realtime_priority', 0, 'SCHED_FIFO priority of the node threads, 1..99; 0 = normal '
         'scheduling', check=_priority_problem),
    Spec('cpu_latency_limit', -1.0, 'CPU wake-up latency held while the node runs, s; 0 = idle '
         'CPUs poll, negative = off', check=_latency_problem),
)


def declare(node):
    """Declare and check `realtime_priority` and `cpu_latency_limit`; return the priority."""
    return node.declare_specs(PARAMETERS)['realtime_priority']


def request(node):
    """SCHED_FIFO at the node's `realtime_priority` (0 or undeclared: normal scheduling)."""
    if not node.has_parameter('realtime_priority'):
        return False
    priority = node.get_parameter('realtime_priority').value
    if priority == 0:
        return False
    if not hasattr(os, 'sched_setscheduler'):
        node.get_logger().warn(f'realtime_priority {priority}: no SCHED_FIFO on this platform; '
                               'running with normal scheduling')
        return False
    try:
        threads = set_fifo(priority)
    except PermissionError:
        node.get_logger().warn(
            f'realtime_priority {priority} not granted (needs an rtprio limit >= {priority}, e.g. '
            '"@realtime - rtprio 98" in /etc/security/limits.conf, or CAP_SYS_NICE): '
            'running with '
            'normal scheduling, expect millisecond latency spikes when the machine is busy')
        return False
    node.get_logger().info(f'SCHED_FIFO priority {priority} on {threads} threads')
    return True


def hold_cpu_latency(limit, device=CPU_LATENCY_DEVICE):
    """
    Ask the kernel to keep every CPU's idle-state exit latency within `limit` s.

    Linux PM QoS (Documentation/power/pm_qos_interface.rst): the request holds while the returned
    file descriptor stays open and ends when it is closed or the process exits, so it cannot
    outlive the node. Raises OSError when `device` is absent or not writable (root by default).
    """
    fd = os.open(device, os.O_WRONLY)
    try:
        os.write(fd, struct.pack('=i', round(limit * 1e6)))  # a native s32 in µs
    except OSError:
        os.close(fd)
        raise
    return fd


def cpu_latency_in_force(device=CPU_LATENCY_DEVICE):
    """
    Return the CPU latency limit in force now, s: the least of every process's request.

    nan where it cannot be read.
    """
    try:
        fd = os.open(device, os.O_RDONLY)
    except OSError:
        return float('nan')
    try:
        return struct.unpack('=i', os.read(fd, 4))[0] / 1e6
    finally:
        os.close(fd)


def limit_cpu_latency(node):
    """
    Hold the node's `cpu_latency_limit` (negative or undeclared: off) while it runs.

    Returns the file descriptor holding the request, for the caller to close at shutdown, or None.
    """
    if not node.has_parameter('cpu_latency_limit'):
        return None
    limit = node.get_parameter('cpu_latency_limit').value
    if limit < 0:
        return None
    try:
        fd = hold_cpu_latency(limit)
    except OSError as exc:
        node.get_logger().warn(
            f'cpu_latency_limit {limit:g} s not applied ({CPU_LATENCY_DEVICE}: {exc.strerror}; '
            'needs root or write access to it): idle CPUs may sleep deeply, expect wake-ups late '
            'by up to milliseconds')
        return None
    node.get_logger().info(
        f'CPU wake-up latency limited to {limit * 1e6:.0f} µs while the node runs')
    return fd


def describe():
    """Return the calling thread's scheduling policy and priority, e.g. 'SCHED_FIFO 50'."""
    if not hasattr(os, 'sched_getscheduler'):
        return 'unknown'
    policy = os.sched_getscheduler(0)
    name = _POLICIES.get(policy, str(policy))
    if policy in (os.SCHED_FIFO, os.SCHED_RR):
        return f'{name} {os.sched_getparam(0).sched_priority}'
    return name
