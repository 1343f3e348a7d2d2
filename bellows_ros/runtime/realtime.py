"""Real-time scheduling for the nodes that run 1 kHz loops (driver, model, simulated devices).

On a general-purpose Linux kernel a Python loop at normal priority is preempted by whatever else
runs; on a 2-core machine that is what turns a 0.3 ms median latency into a 5-10 ms p99. The usual
remedy in ROS 2 control (ros2_control's controller manager does the same) is SCHED_FIFO for the
process's threads, granted by an rtprio limit (`/etc/security/limits.conf`) or CAP_SYS_NICE. When
it is not granted the node says so once and carries on with normal scheduling.

API
---
- ``declare(node) -> int``: declares the node's `realtime_priority` parameter (default 0) and checks
  it (0 or 1-99, else ParameterError); call it with the node's other parameters.
- ``request(node) -> bool``: the node's `realtime_priority` parameter (when it declares one): 1-99
  = SCHED_FIFO at that priority for every thread of the process, and so for the threads it starts
  later (they inherit it); 0 leaves the scheduling alone. Logs the outcome on the node's logger.
  `rt.main` calls it once the node is built, so a node only declares the parameter.
- ``describe() -> str``: the calling thread's policy, e.g. ``'SCHED_FIFO 50'`` or ``'SCHED_OTHER'``
  (reported on /diagnostics).
"""
import os

from bellows_ros.errors import ParameterError

_POLICIES = {getattr(os, name): name for name in
             ('SCHED_OTHER', 'SCHED_FIFO', 'SCHED_RR', 'SCHED_BATCH', 'SCHED_IDLE')
             if hasattr(os, name)}


def set_fifo(priority):
    """SCHED_FIFO at `priority` for every thread of this process; returns how many threads.

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


def declare(node):
    """Declare and check `realtime_priority` (0 = normal scheduling, 1-99 = SCHED_FIFO)."""
    priority = node.declare_parameter('realtime_priority', 0).value
    if priority != 0 and not 1 <= priority <= 99:
        raise ParameterError(f"parameter 'realtime_priority': expected 0 (off) or 1..99, "
                             f'got {priority}')
    return priority


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
            f'"@realtime - rtprio 98" in /etc/security/limits.conf, or CAP_SYS_NICE): running with '
            'normal scheduling, expect millisecond latency spikes when the machine is busy')
        return False
    node.get_logger().info(f'SCHED_FIFO priority {priority} on {threads} threads')
    return True


def describe():
    """The calling thread's scheduling policy and priority, e.g. 'SCHED_FIFO 50'."""
    if not hasattr(os, 'sched_getscheduler'):
        return 'unknown'
    policy = os.sched_getscheduler(0)
    name = _POLICIES.get(policy, str(policy))
    if policy in (os.SCHED_FIFO, os.SCHED_RR):
        return f'{name} {os.sched_getparam(0).sched_priority}'
    return name
