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
The simulated CAN bus (hardware/loopback_can.py): python-can's udp_multicast, on loopback only.

The channel is a multicast address written as one (nothing is looked up, no socket is made for
anything else); frames reach every bus of the group on this host, the sender's own included
(multicast loop), and no other group; the socket may not send off the host (TTL 0, loopback
interface); python-can's receive filters and CAN FD switch still work. Every bus is closed.
"""
import random
import socket

import can
import pytest

from bellows_ros.errors import ParameterError
from bellows_ros.hardware.arm_bus import open_can
from bellows_ros.hardware.loopback_can import check_channel, LoopbackUdpMulticastBus, \
    RECEIVE_BUFFER


@pytest.fixture
def buses():
    """Open loopback buses on one fresh group and port; shut every one down after the test."""
    made = []
    group, port = f'239.74.168.{random.randint(1, 250)}', 46000 + random.randint(0, 999)

    def make(**kwargs):
        bus = LoopbackUdpMulticastBus(group, port=port, **kwargs)
        made.append(bus)
        return bus
    make.group, make.port = group, port
    yield make
    for bus in made:
        bus.shutdown()


@pytest.mark.parametrize('channel', ['239.74.163.2', ' 239.74.163.2\n', '224.0.0.251'])
def test_a_multicast_address_is_a_channel(channel):
    assert check_channel(channel) == channel.strip()


@pytest.mark.parametrize('channel', ['localhost', 'arm-bus.example', 'can0', '127.0.0.1',
                                     '10.0.0.1', 'ff02::1', '239.74.163', '239.74.163.256', ''])
def test_anything_else_is_refused_in_one_line(channel):
    with pytest.raises(ParameterError, match='multicast group') as error:
        check_channel(channel)
    assert f"'{channel}'" in str(error.value) and '\n' not in str(error.value)


def test_a_refused_channel_reaches_no_resolver_and_makes_no_socket(monkeypatch):
    calls = []

    def spy(name):
        def call(*args, **kwargs):
            calls.append(name)
            raise AssertionError(f'{name} called')
        return call
    monkeypatch.setattr(socket, 'getaddrinfo', spy('getaddrinfo'))
    monkeypatch.setattr(socket, 'socket', spy('socket'))
    for make in (lambda: LoopbackUdpMulticastBus('arm-bus.example', port=46999),
                 lambda: open_can('udp_multicast', 'arm-bus.example', port=46999)):
        with pytest.raises(ParameterError):
            make()
    assert calls == []


def test_the_socket_may_not_leave_the_host(buses):
    sock = buses()._multicast._socket
    assert sock.getsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL) == 0
    assert sock.getsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP) == 1
    # bound to the group, not the wildcard: only the group's datagrams come in
    assert sock.getsockname() == (buses.group, buses.port)


def test_a_frame_reaches_every_bus_of_the_group_and_echoes_to_its_sender(buses):
    sender, peer = buses(), buses()
    frame = can.Message(arbitration_id=0x101, data=bytes([1, 2, 3, 4, 5, 6, 7, 8]),
                        is_extended_id=False)
    sender.send(frame)
    for bus in (peer, sender):  # multicast loop: the sender hears itself too
        got = bus.recv(timeout=2.0)
        assert got is not None and got.arbitration_id == 0x101 and got.data == frame.data
        assert not got.is_extended_id and got.timestamp > 0  # the kernel's receive time
    assert peer.recv(timeout=0.2) is None  # once each


def test_receive_filters_pass_only_the_ids_asked_for(buses):
    sender = buses()
    listener = buses(can_filters=[{'can_id': 0x100, 'can_mask': 0x7FF, 'extended': False}])
    for frame_id in (0x101, 0x100, 0x102):
        sender.send(can.Message(arbitration_id=frame_id, data=b'\x00', is_extended_id=False))
    got = listener.recv(timeout=2.0)
    assert got is not None and got.arbitration_id == 0x100
    assert listener.recv(timeout=0.2) is None


def test_can_fd_frames_travel_unless_the_bus_is_classic(buses):
    fd_frame = can.Message(arbitration_id=0x120, data=bytes(range(64)), is_fd=True,
                           is_extended_id=False)
    sender, classic = buses(), buses(fd=False)
    assert sender.protocol is can.CanProtocol.CAN_FD
    assert classic.protocol is can.CanProtocol.CAN_20
    with pytest.raises(can.CanOperationError):
        classic.send(fd_frame)
    sender.send(fd_frame)
    got = sender.recv(timeout=2.0)
    assert got is not None and got.is_fd and got.data == fd_frame.data


@pytest.mark.realtime  # as in test_hw_arm_bus.py, where it was written
def test_a_stalled_reader_keeps_its_frames():
    """
    Frames that arrive while the reader is not scheduled wait in the kernel's buffer, not lost.

    The default buffer held 256 frames (51 ms of the arm's traffic); the arm bus asks for about a
    second's worth, which the kernel grants up to net.core.rmem_max.
    """
    with open('/proc/sys/net/core/rmem_max') as stream:
        rmem_max = int(stream.read())
    port = 44000 + random.randint(0, 999)
    reader = open_can('udp_multicast', '239.74.166.12', port=port)
    writer = open_can('udp_multicast', '239.74.166.12', port=port)
    try:
        granted = reader._multicast._socket.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)
        assert granted == 2 * min(RECEIVE_BUFFER, rmem_max)
        sent = 2000 if rmem_max >= RECEIVE_BUFFER else 400    # 0.4 s of 4 segments + status
        message = can.Message(arbitration_id=0x101, data=bytes(8), is_extended_id=False)
        for _ in range(sent):                          # nobody reads meanwhile
            writer.send(message)
        kept = 0
        while reader.recv(timeout=0.2) is not None:
            kept += 1
        assert kept == sent
    finally:
        reader.shutdown()
        writer.shutdown()


@pytest.mark.realtime
def test_a_bus_hears_only_its_own_multicast_group():
    """Linux gives a wildcard-bound socket every group joined on its port, unless told not to."""
    port = 43000 + random.randint(0, 999)
    talker = open_can('udp_multicast', '239.74.166.10', port=port)
    listener = open_can('udp_multicast', '239.74.166.11', port=port)
    other = open_can('udp_multicast', '239.74.166.10', port=port)
    try:
        message = can.Message(arbitration_id=0x123, data=b'\x01', is_extended_id=False)
        talker.send(message)
        assert other.recv(timeout=2.0) is not None     # the group works...
        assert listener.recv(timeout=0.5) is None      # ...and does not leak into another group
        # The simulated bus stays on this host: frames leave through the loopback interface.
        sock = talker._multicast._socket
        assert sock.getsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, 4) == \
            socket.inet_aton('127.0.0.1')
    finally:
        for bus in (talker, listener, other):
            bus.shutdown()
