"""runtime.realtime: SCHED_FIFO for every thread of a node's process, or one clear warning.

Each case runs in a child process, so the test runner itself never changes its scheduling. Whether
this machine grants SCHED_FIFO is asked of the kernel first (a throw-away child), and the node
must then do exactly what the kernel allows: switch every thread, or warn and carry on.
"""
import subprocess
import sys

CHILD = r'''
import os, sys, threading
from bellows_ros.runtime import realtime

class Param:
    def __init__(self, value): self.value = value

class Log:
    def info(self, m): print('INFO', m)
    def warn(self, m): print('WARN', m)

class Node:
    def __init__(self, p): self.p = p
    def has_parameter(self, name): return name == 'realtime_priority'
    def get_parameter(self, name): return Param(self.p)
    def get_logger(self): return Log()

before = threading.Thread(target=threading.Event().wait, args=(5,), daemon=True)
before.start()                                    # a thread that exists before the request
granted = realtime.request(Node(int(sys.argv[1])))
policies = {}
def report():
    policies['later'] = realtime.describe()       # a thread started after the request
later = threading.Thread(target=report)
later.start(); later.join()
policies['main'] = realtime.describe()
policies['before'] = (os.sched_getscheduler(before.native_id),
                      os.sched_getparam(before.native_id).sched_priority)
print('RESULT', granted, policies)
'''


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
