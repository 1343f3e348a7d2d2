"""Waiting in tests for something another thread or process does."""
import time


def wait_for(condition, timeout=5.0):
    """Poll `condition` until true or `timeout` s (a bound, not an assertion about speed)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.005)
    return condition()
