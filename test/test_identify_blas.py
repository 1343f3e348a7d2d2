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

"""The fits run one BLAS thread (identify/blas.py): NumPy's and SciPy's, in every command."""
import json
from multiprocessing import get_context
import os
import subprocess
import sys
import textwrap

from threadpoolctl import threadpool_info, threadpool_limits

from bellows_ros import cli
from bellows_ros.identify.blas import one_blas_thread


def blas_threads():
    """Return {library path: threads} of the BLAS libraries loaded in this process."""
    return {i['filepath']: i['num_threads'] for i in threadpool_info() if i['user_api'] == 'blas'}


FRESH = textwrap.dedent("""\
    import json
    import numpy
    from threadpoolctl import threadpool_info
    from bellows_ros.identify.blas import one_blas_thread

    def blas():
        return {i['filepath']: i['num_threads'] for i in threadpool_info()
                if i['user_api'] == 'blas'}

    before = blas()
    with one_blas_thread():
        inside = blas()
        import scipy.linalg, scipy.optimize  # what the fits import, after the limit
        later = blas()
    print(json.dumps([before, inside, later, blas()]))
""")


def test_one_thread_in_every_blas_the_fits_load_then_put_back():
    """In a fresh process, NumPy's BLAS loaded and SciPy's not yet, two threads each by default."""
    done = subprocess.run([sys.executable, '-c', FRESH], capture_output=True, text=True,
                          env=dict(os.environ, OPENBLAS_NUM_THREADS='2'), check=True)
    before, inside, later, after = json.loads(done.stdout)
    assert set(before.values()) == {2}, before
    # SciPy's own BLAS, where it ships one, was loaded and limited on entering, not after.
    assert later == inside and set(inside.values()) == {1}, (inside, later)
    assert after == dict.fromkeys(inside, 2), after


def test_a_command_runs_with_one_blas_thread(monkeypatch):
    seen = []
    monkeypatch.setattr('bellows_ros.cli.stiffness.run', lambda args: seen.append(blas_threads()))
    with threadpool_limits(limits=2, user_api='blas'):
        assert cli.main(['stiffness', 'unused.csv']) == 0
    assert seen and seen[0] and set(seen[0].values()) == {1}, seen


def test_a_worker_process_started_with_it_keeps_one_thread(monkeypatch):
    """As `bellows bench doctor` starts its workers, side by side."""
    monkeypatch.setenv('OPENBLAS_NUM_THREADS', '2')
    with get_context('spawn').Pool(1, initializer=one_blas_thread) as pool:
        threads = pool.apply(blas_threads)
    assert threads and set(threads.values()) == {1}, threads
