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
rows, a few parameters), where OpenBLAS's threads cost more than they share.

Measured on this project's 2-core machine, 2026-11-29, the same 32 s actuator record (the
workflow test's): `bellows diagnose actuator` took 48.3 s with OpenBLAS's default two threads and
25.6 s with one (SciPy's SVD in `least_squares` and NumPy's `lstsq` are most of it);
`bellows identify` and diagnose on the segment's big records took the same wall time either way
(85 s) and 22 % less CPU with one. Two diagnoses side by side took 143 s with the default threads
and 30 s with one each.
"""


def one_blas_thread():
    """
    Return a context in which NumPy's and SciPy's BLAS libraries each run one thread.

    SciPy ships an OpenBLAS of its own, loaded with `scipy.linalg`; it is imported here, so the
    limit reaches it too (threadpoolctl limits the libraries loaded when the context is entered).
    """
    import numpy  # noqa: F401
    import scipy.linalg  # noqa: F401
    from threadpoolctl import threadpool_limits
    return threadpool_limits(limits=1, user_api='blas')
