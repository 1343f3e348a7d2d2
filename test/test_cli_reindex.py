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
`bellows reindex BAG` (cli/reindex.py): what it says and leaves for a whole and a killed bag.

Run in this process through the `bellows` entry point. A killed recording is made as a SIGKILL
leaves one: no metadata.yaml and the MCAP file cut inside its records (io/bag_repair.py does the
repair; this module reports it). Its storage file is dated in the past, so reindex does not wait
to see whether a writer is still at it.
"""
import os
import re
import time

from bag_messages import write_actuator_bag
import numpy as np
import pytest
from rosbags.rosbag2 import Reader, StoragePlugin

from bellows_ros.cli import main


def write_bag(path, n=400):
    """Write an actuator bag of `n` samples at 1 kHz (20000: 3.6 MB, 4 MCAP chunks of 1 MiB)."""
    start = 5 * 10 ** 9
    rows = [(start + k * 1_000_000, 0.01 + 1e-5 * np.sin(k / 30), 0.002 + 1e-3 * np.sin(k / 50),
             1.2e5 + 100.0 * np.sin(k / 40), 3.0 + np.sin(k / 50)) for k in range(n)]
    return write_actuator_bag(path, rows, StoragePlugin.MCAP, version=9)


def kill(bag):
    """Leave what a SIGKILL leaves, written a minute ago: no metadata.yaml, the MCAP cut."""
    (bag / 'metadata.yaml').unlink()
    mcap = next(bag.glob('*.mcap'))
    os.truncate(mcap, int(mcap.stat().st_size * 0.7))
    past = time.time() - 60.0
    os.utime(mcap, (past, past))
    return mcap


def tree(directory):
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob('*'))
            if p.is_file()}


def counts(bag):
    with Reader(bag) as reader:
        return {c.topic: c.msgcount for c in reader.connections}


def test_a_bag_that_opens_is_left_as_it_is(tmp_path, capsys):
    bag = write_bag(tmp_path / 'bag')
    before = tree(bag)
    total = sum(counts(bag).values())
    assert main(['reindex', str(bag)]) == 0
    out = capsys.readouterr().out
    assert out == (f'bellows reindex: {bag} opens as it is ({total} messages); '
                   'nothing to do\n')
    assert tree(bag) == before


def test_a_killed_bag_is_rebuilt_and_the_damaged_file_kept(tmp_path, capsys):
    bag = write_bag(tmp_path / 'bag', n=20000)  # the cut leaves whole chunks before it
    recorded = sum(counts(bag).values())
    mcap = kill(bag)
    damaged = mcap.read_bytes()
    assert main(['reindex', str(bag)]) == 0
    lines = capsys.readouterr().out.splitlines()
    # One line per topic with the messages kept, then the total, which is their sum.
    per_topic = dict(re.fullmatch(r'(/\S+): (\d+) messages', line).groups()
                     for line in lines[:-1])
    kept = {topic: int(count) for topic, count in per_topic.items()}
    total = int(re.search(r': rebuilt .*: (\d+) messages kept', lines[-1]).group(1))
    assert total == sum(kept.values()) and 0 < total < recorded
    assert str(bag) in lines[-1] and '*.mcap.damaged' in lines[-1]
    # What it says is what a reader finds; the cut file is kept byte for byte beside it.
    assert counts(bag) == kept
    assert (bag / (mcap.name + '.damaged')).read_bytes() == damaged
    # Once rebuilt, the bag opens: a second reindex has nothing to do.
    assert main(['reindex', str(bag)]) == 0
    assert 'opens as it is' in capsys.readouterr().out


@pytest.mark.parametrize('make, needle', [
    (lambda path: path.write_text('not a bag\n'), 'not a directory'),
    (lambda path: path.mkdir(), 'expected one .mcap file in the bag, found 0'),
])
def test_what_is_not_a_bag_is_named_in_one_line(tmp_path, capsys, make, needle):
    target = tmp_path / 'target'
    make(target)
    assert main(['reindex', str(target)]) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err, err
    assert err.startswith('bellows reindex: error:') and str(target) in err and needle in err


def test_the_bag_argument_is_required(capsys):
    with pytest.raises(SystemExit) as stop:
        main(['reindex'])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'BAG' in err, err
