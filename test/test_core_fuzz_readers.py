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
Fuzzing the file readers (CSV, rosbag2, parameter YAML) with hypothesis.

The property throughout: a reader returns what the file says, or raises the one-line BellowsError
the CLI turns into exit 2 -- never another exception. "What the file says" has an oracle that does
not share the reader's code: Python's csv module and float() for a CSV, the values written for a
bag. rosbag2 storage (sqlite3, and MCAP as rosbags writes it) carries no checksum over message
data, so a flipped bit inside a stored number cannot be noticed by any reader; for spoilt bytes the
property is therefore "one line, or a table that passes every check a CSV must pass".
"""
import csv
import datetime
import io
import math
from pathlib import Path
import random
import shutil
import tempfile

from hypothesis import given, HealthCheck, settings
from hypothesis import strategies as st
import numpy as np
import pytest
from rosbags.rosbag2 import StoragePlugin
from test_core_bad_input import actuator_rows, write_actuator_bag
import yaml

from bellows_ros.config.actuator import load_actuator_params
from bellows_ros.config.segment import load_segment_params
from bellows_ros.errors import BellowsError, DataError, ParameterError
from bellows_ros.io import data, params

FUZZ = settings(max_examples=100, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])


def assert_one_line_naming(error, path):
    message = str(error)
    assert isinstance(error, BellowsError), repr(error)
    assert '\n' not in message and message.startswith(str(path)), message


# --- CSV ----------------------------------------------------------------------------------------

ODD_CELLS = ['', ' ', 'nan', 'inf', '-inf', '1e400', '-1e400', '1e-400', '1_0', '0x10', '#',
             '1 # c', '"1"', '"1,2"', 'abc', ' 2.5 ', '+3', '.5', '5.', '1e5', '1E5', '\u0661',
             '1,5', '--1', 'infinity', '0.0.1', '\t7', '\x00']
numbers = st.one_of(st.floats(allow_nan=False, allow_infinity=False).map(repr),
                    st.integers(-10 ** 20, 10 ** 20).map(str))
# mostly numbers, so that whole files get through to the numeric parsing
cells = st.one_of(numbers, numbers, numbers, numbers, numbers, numbers, st.floats().map(repr),
                  st.sampled_from(ODD_CELLS), st.text(max_size=4))
extra_names = st.sampled_from(['p'] * 6 + ['note'] * 6 + [' t ', '', 'x_c', 'T', 't'])


@st.composite
def csv_texts(draw):
    header = draw(st.permutations(['t', 'x_c'] + draw(st.lists(extra_names, max_size=2))))
    if draw(st.integers(0, 9)) == 0:
        header.pop(draw(st.integers(0, len(header) - 1)))
    width = len(header)
    # mostly rows of the header's width, so that the numeric parsing is reached
    widths = st.sampled_from([width] * 30 + [max(width - 1, 0), width + 1])
    rows = draw(st.lists(widths.flatmap(lambda n: st.lists(cells, min_size=n, max_size=n)),
                         min_size=1, max_size=6))
    end = draw(st.sampled_from(['\n', '\r\n']))
    lines = [','.join(header)] + [','.join(row) for row in rows]
    if draw(st.booleans()):
        lines.insert(draw(st.integers(1, len(lines))), '')
    text = end.join(lines) + (end if draw(st.booleans()) else '')
    return ('\ufeff' if draw(st.booleans()) else '') + text


def reference_columns(text, wanted):
    """
    Read `text` the oracle's way: csv module and float(), cell by cell.

    Blank rows are skipped, names stripped.
    """
    rows = list(csv.reader(io.StringIO(text.removeprefix('\ufeff'), newline='')))
    header = [name.strip() for name in rows[0]]
    body = [row for row in rows[1:] if row and any(cell.strip() for cell in row)]
    return {name: [float(row[header.index(name)]) for row in body] for name in wanted}


@pytest.mark.filterwarnings('error')  # a warning printed before the error is a second line
@FUZZ
@given(csv_texts())
def test_csv_reader_returns_what_the_file_says_or_one_line(tmp_path, text):
    path = tmp_path / 'fuzz.csv'
    path.write_bytes(text.encode('utf-8', errors='surrogatepass'))
    try:
        table = data.read_csv(path, ('t', 'x_c'), ('p',))
    except DataError as error:
        assert_one_line_naming(error, path)
        return
    expected = reference_columns(text, list(table.values))
    assert {'t', 'x_c'} <= set(table.values)
    for name, column in table.values.items():
        assert np.isfinite(column).all()
        np.testing.assert_array_equal(column, expected[name], err_msg=name)


@pytest.mark.filterwarnings('error')
@FUZZ
@given(csv_texts())
def test_fast_and_careful_csv_paths_agree_on_any_file(tmp_path, text):
    """An extra text column sends a file down the csv-module path; both must read it alike."""
    plain, labelled = tmp_path / 'plain.csv', tmp_path / 'labelled.csv'
    plain.write_bytes(text.encode('utf-8', errors='surrogatepass'))
    lines = text.split('\n')
    labelled.write_bytes('\n'.join(line + (',extra' if i == 0 else ',x') if line.strip(',\r')
                                   else line for i, line in enumerate(lines))
                         .encode('utf-8', errors='surrogatepass'))
    outcomes = []
    for path in (plain, labelled):
        try:
            outcomes.append(data.read_csv(path, ('t', 'x_c'), ('p',)).values)
        except DataError as error:
            assert_one_line_naming(error, path)
            outcomes.append(None)
    if outcomes[0] is not None and outcomes[1] is not None:
        assert outcomes[0].keys() == outcomes[1].keys()
        for name in outcomes[0]:
            np.testing.assert_array_equal(outcomes[0][name], outcomes[1][name])


@pytest.mark.filterwarnings('error')
@FUZZ
@given(st.binary(max_size=400))
def test_csv_reader_survives_any_bytes(tmp_path, raw):
    path = tmp_path / 'bytes.csv'
    path.write_bytes(b't,x_c\n' + raw if raw[:1] != b'!' else raw)
    try:
        table = data.read_table(path, 'actuator', ('t', 'x_c'))
    except DataError as error:
        assert_one_line_naming(error, path)
        return
    assert np.all(np.diff(table['t']) > 0) and np.isfinite(table['x_c']).all()


# --- rosbag2 ------------------------------------------------------------------------------------

finite = st.floats(-1e3, 1e3)
values = st.one_of(finite, finite, finite, st.sampled_from([math.nan, math.inf, -math.inf]))
pressures = st.one_of(st.floats(2.5e3, 1e6), st.floats(2.5e3, 1e6), st.floats(0.0, 1.9e3),
                      st.sampled_from([math.nan, math.inf]))


@pytest.mark.slow  # writes a bag per example
@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(st.integers(-2_000_000, 3_000_000), values, values, pressures, values),
                min_size=1, max_size=12), st.sampled_from(['sample', 'split']))
def test_bag_reader_returns_the_values_written_or_one_line(samples, layout):
    """
    Stamps go where hypothesis says (log time stays in write order).

    Values may be non-finite and pressures implausibly low. Expected: exactly what was written, or
    the one-line error. In a sample message (layout 'sample', bag_messages) a NaN pressure or
    force is a value the device did not measure: its row holds another's, which may be refused
    as held over a gap (table.check_held), so only the other rows are compared.
    """
    stamps = 5 * 10 ** 9 + np.cumsum([step for step, *_ in samples])
    rows = [(int(ns), *rest) for ns, (_, *rest) in zip(stamps, samples)]
    columns = np.array([row[1:] for row in rows], float)
    absent = np.zeros(columns.shape, bool)
    if layout == 'sample':
        absent[:, 2:] = np.isnan(columns[:, 2:])
    pressures = columns[~absent[:, 2], 2]
    bad = (np.any(np.diff(stamps) <= 0) or not np.isfinite(columns[~absent]).all()
           or absent[:, 2:].all(axis=0).any()  # a channel without a value: refused
           or pressures.max() < data.MIN_PLAUSIBLE_PRESSURE
           or pressures.min() < data.MIN_ABSOLUTE_PRESSURE)
    with tempfile.TemporaryDirectory() as directory:
        bag = Path(directory) / 'bag'
        write_actuator_bag(bag, rows, layout=layout, log_time=lambda k, ns: k + 1)
        try:
            table = data.read_table(bag, 'actuator')
        except DataError as error:
            assert bad or absent.any(), f'refused a good bag: {error}'
            assert_one_line_naming(error, bag)
            return
    assert not bad, 'read a bag that should be refused'
    np.testing.assert_array_equal(table['t'], (stamps - stamps[0]) * 1e-9)
    for i, name in enumerate(('x_c', 'x_s', 'p', 'f')):
        np.testing.assert_array_equal(table[name][~absent[:, i]], columns[~absent[:, i], i])
        assert np.isfinite(table[name]).all()


@pytest.fixture(scope='module')
def good_bags(tmp_path_factory):
    bags = {}
    for storage in (StoragePlugin.SQLITE3, StoragePlugin.MCAP):
        bag = tmp_path_factory.mktemp('bags') / storage.name.lower()
        write_actuator_bag(bag, actuator_rows(40), storage)
        bags[storage.name.lower()] = bag
    return bags


@pytest.mark.slow  # copies and reads a bag per example
@settings(max_examples=200, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.sampled_from(['sqlite3', 'mcap']), st.booleans(),
       st.sampled_from(['flip', 'truncate', 'overwrite']), st.integers(0, 2 ** 32), st.data())
def test_spoilt_bags_are_one_line_or_a_table_that_passes_every_check(
        good_bags, storage, metadata, how, seed, draw):
    rng = random.Random(seed)
    with tempfile.TemporaryDirectory() as directory:
        bag = Path(directory) / 'bag'
        shutil.copytree(good_bags[storage], bag)
        target = bag / 'metadata.yaml' if metadata else next(
            f for f in bag.iterdir() if f.name != 'metadata.yaml')
        raw = bytearray(target.read_bytes())
        if how == 'flip':
            for _ in range(draw.draw(st.integers(1, 8))):
                raw[rng.randrange(len(raw))] ^= 1 << rng.randrange(8)
        elif how == 'truncate':
            del raw[rng.randrange(len(raw)):]
        else:
            start = rng.randrange(len(raw))
            raw[start:start + rng.randint(1, 64)] = draw.draw(st.binary(min_size=1, max_size=64))
        target.write_bytes(bytes(raw))
        try:
            table = data.read_table(bag, 'actuator')
        except DataError as error:
            assert_one_line_naming(error, bag)
            return
    assert len(table) > 0 and table['t'][0] == 0.0 and np.all(np.diff(table['t']) > 0)
    for name in ('x_c', 'x_s', 'p', 'f'):
        assert np.isfinite(table[name]).all()
    assert table['p'].max() >= data.MIN_PLAUSIBLE_PRESSURE
    assert table['p'].min() >= data.MIN_ABSOLUTE_PRESSURE


def test_a_message_count_that_is_not_a_number_is_one_line(good_bags, tmp_path):
    # What the fuzzer above found (seed 510509): a flipped bit turned a count into text.
    bag = tmp_path / 'bag'
    shutil.copytree(good_bags['sqlite3'], bag)
    metadata = bag / 'metadata.yaml'
    text = metadata.read_text()
    assert '- message_count: 40' in text  # a topic's (the first is the file's)
    metadata.write_text(text.replace('- message_count: 40', '- message_count: 4p', 1))
    with pytest.raises(DataError) as error:
        data.read_table(bag, 'actuator')
    assert_one_line_naming(error.value, bag)
    assert "message_count '4p' is not a count" in str(error.value)


# --- parameter YAML -----------------------------------------------------------------------------

scalars = st.one_of(st.none(), st.booleans(), st.integers(-2 ** 1030, 2 ** 1030), st.floats(),
                    st.text(max_size=8), st.dates())
trees = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=6), inner, max_size=3)),
    max_leaves=12)


def allowed(value):
    items = value if isinstance(value, list) else [value]
    return all(isinstance(item, (bool, int, float, str)) and not (
        isinstance(item, float) and not math.isfinite(item)) for item in items)


@FUZZ
@given(st.one_of(trees, st.fixed_dictionaries({'/**': st.fixed_dictionaries(
    {'ros__parameters': trees})})))
def test_parameter_file_reader_gives_plain_values_or_one_line(tmp_path, document):
    path = tmp_path / 'p.yaml'
    path.write_text(yaml.safe_dump(document))
    try:
        flat = params.read_file(path)
    except ParameterError as error:
        assert_one_line_naming(error, path)
        return
    assert flat == params.flatten(_dates_as_text(document['/**']['ros__parameters']))
    assert all(allowed(value) for value in flat.values())


def _dates_as_text(tree):
    """Return the tree as rcl reads it: an unquoted YAML date is its text (rcl has no dates)."""
    if isinstance(tree, dict):
        return {key: _dates_as_text(value) for key, value in tree.items()}
    if isinstance(tree, list):
        return [_dates_as_text(item) for item in tree]
    return tree.isoformat() if isinstance(tree, datetime.date) else tree


@FUZZ
@given(st.text(max_size=200))
def test_parameter_file_reader_survives_any_text(tmp_path, text):
    path = tmp_path / 'p.yaml'
    path.write_text('/**:\n  ros__parameters:\n    ' + text, errors='surrogatepass')
    try:
        params.read_file(path)
    except ParameterError as error:
        assert_one_line_naming(error, path)


def _user_files(section):
    defaults = params.section(params.load(section), section)
    value = st.one_of(scalars.filter(lambda v: not isinstance(v, dict)),
                      st.lists(scalars, max_size=9), st.sampled_from([0, -1.0, 1e300, 2, 9]))
    return st.dictionaries(st.sampled_from(sorted(defaults)), value, min_size=1, max_size=4)


@pytest.mark.slow  # reads the default YAML per example
@pytest.mark.parametrize('loader, section', [(load_segment_params, 'segment'),
                                             (load_actuator_params, 'actuator')])
def test_model_parameter_files_build_or_say_which_parameter(tmp_path, loader, section):
    """Any value of any kind for any model parameter: a parameter object or one line naming it."""
    @settings(max_examples=150, deadline=None)
    @given(_user_files(section))
    def check(overrides):
        path = tmp_path / 'u.yaml'
        tree = {section: params.unflatten(overrides)}
        path.write_text(yaml.safe_dump({'/**': {'ros__parameters': tree}}))
        try:
            loader(path)
        except ParameterError as error:
            assert_one_line_naming(error, path)
            # a relation (p_max > p0) may name the other side of it; a parameter is named
            assert f"parameter '{section}." in str(error), error
    check()
