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
Benchmarks for `bellows bench`.

Every module in this package exposes ``run(quick=False) -> list[Result]``. Each result carries a
median and, where it has one, a reference measured in the same run and the ratio to it: on a shared
2-core machine absolute times drift, ratios much less. Nothing here asserts a time.
"""
from dataclasses import asdict, dataclass, field
import statistics
import time

import numpy as np

# The helpers every bench uses; the benches are the package's other modules (`bellows bench`).
__all__ = ['Result', 'per_call', 'timing', 'median', 'quantile', 'log_uniform']


@dataclass
class Result:
    """
    One measured figure.

    name: what was measured; value: the median (seconds for timings); unit: of `value`;
    samples: how many calls or samples the median is over; reference: name of the reference figure;
    ratio: value / reference value; target: the issue's target in `unit`, if any; extra: more
    figures, in `unit` unless `extra_units` names another unit for them ('' for a fraction).
    """

    name: str
    value: float
    unit: str = 's'
    samples: int = 0
    reference: str = None
    ratio: float = None
    target: float = None
    extra: dict = field(default_factory=dict)
    extra_units: dict = field(default_factory=dict)

    def as_dict(self):
        return asdict(self)


def per_call(fn, calls, warmup=1000):
    """
    Time `calls` calls of `fn()` one by one; returns the sorted list of durations in seconds.

    Timing each call (rather than a batch) gives a true median and tail, at ~50 ns of clock
    overhead.
    """
    clock = time.perf_counter_ns
    for _ in range(warmup):
        fn()
    durations = []
    append = durations.append
    for _ in range(calls):
        start = clock()
        fn()
        append(clock() - start)
    durations.sort()
    return [d * 1e-9 for d in durations]


def log_uniform(rng, low, high):
    """Draw from `low` to `high` uniformly in the logarithm (numpy Generator `rng`)."""
    return float(np.exp(rng.uniform(np.log(low), np.log(high))))


def median(values):
    return statistics.median(values)


def quantile(sorted_values, q):
    """q-quantile of an already sorted list (nearest rank)."""
    index = min(len(sorted_values) - 1, max(0, int(round(q * (len(sorted_values) - 1)))))
    return sorted_values[index]


def timing(name, fn, calls, reference=None, target=None):
    """Time `fn` per call: median as the value, p99 in `extra`; `reference` is another Result."""
    durations = per_call(fn, calls)
    value = median(durations)
    result = Result(name, value, 's', calls, target=target,
                    extra={'p99': quantile(durations, 0.99)})
    if reference is not None:
        result.reference, result.ratio = reference.name, value / reference.value
    return result
