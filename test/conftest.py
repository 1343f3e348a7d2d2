"""Test session set-up: DDS on loopback, and the `runtime` fixture that runs a test on both runtimes.

Every test keeps its DDS traffic on this machine: ROS 2's own switch
(`ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`, which rclpy and the DDS runtime both honour) plus a
Cyclone configuration bound to the loopback interface with multicast off. The simulated CAN bus
joins its multicast group on loopback by itself (hardware/arm_bus.py).

The pytest process itself never imports rclpy (it uses the DDS runtime for its probes: one Cyclone
DDS library per process). A test that takes the `runtime` fixture runs twice, `[dds]` and
`[rclpy]`, and starts its nodes with `BELLOWS_RUNTIME` set accordingly (runtimes.py).
"""
import os

import pytest

from runtimes import LOOPBACK_ENVIRONMENT, require_rclpy

os.environ.setdefault('MPLBACKEND', 'Agg')
os.environ.update(LOOPBACK_ENVIRONMENT)
os.environ['BELLOWS_RUNTIME'] = 'dds'  # in-process nodes and probes; children get their own


@pytest.fixture(params=['dds', 'rclpy'])
def runtime(request):
    """The runtime the test's nodes run on ('dds' or 'rclpy'), in the test's id."""
    if request.param == 'rclpy':
        require_rclpy()
    return request.param
