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
One BLAS thread for the fits.

The identification's and the doctor's linear algebra is on tall, narrow matrices (thousands of
rows, a few parameters), where OpenBLAS's threads cost more than they share: on two cores an
actuator diagnosis took half the time on one thread, and two side by side a fifth
(bench_results/0.1.0/notebook.md, 2026-11-29).
"""


def one_blas_thread():
    """
    Return a context in which NumPy's and SciPy's BLAS libraries each run one thread.

    SciPy ships an OpenBLAS of its own, loaded with `scipy.linalg`; it is imported here, so the
    limit reaches it too (threadpoolctl limits the libraries loaded when it is called). The limit
    holds from the call on, and leaving the context puts the threads back: a process that keeps
    it for life (a pool's `initializer`) only calls it.
    """
    import numpy  # noqa: F401
    import scipy.linalg  # noqa: F401
    from threadpoolctl import threadpool_limits
    return threadpool_limits(limits=1, user_api='blas')
