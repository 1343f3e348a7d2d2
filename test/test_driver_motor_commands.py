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


"""driver_node hands motor commands to a writer thread: a board that blocks cannot hold it up."""
import threading

from bellows_ros.nodes.driver_node import NewestWriter

GUARD = 10.0  # s; a hang guard, not a timing assertion


def test_put_returns_while_the_send_blocks_and_only_the_newest_waiting_value_is_sent():
    entered, release, done = threading.Event(), threading.Event(), threading.Event()
    sent = []

    def send(value):  # a serial write that blocks until the board reads
        sent.append(value)
        entered.set()
        release.wait(GUARD)
        if len(sent) == 2:
            done.set()

    writer = NewestWriter(send, 'test-writer')
    try:
        writer.put(0.1)
        assert entered.wait(GUARD)  # the writer is inside the blocked send
        writer.put(0.2)  # returns although the send still blocks (else the test hangs)
        writer.put(0.3)  # replaces 0.2, never sent
        release.set()
        assert done.wait(GUARD)
        assert sent == [0.1, 0.3]
    finally:
        release.set()
        writer.close()


def test_close_stops_the_thread_and_drops_what_was_not_sent():
    sent = []
    writer = NewestWriter(sent.append, 'test-writer')
    writer.close()
    writer.put(0.5)  # after close: accepted, never sent
    assert not writer._thread.is_alive()
    assert sent == []
