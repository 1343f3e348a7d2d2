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
Exceptions for mistakes a user can make (bad files, bad parameters, absent devices).

The CLI and the nodes turn a `BellowsError` into a one-line message and exit status 2; anything
else is a bug and keeps its traceback.
"""


class BellowsError(Exception):
    """A user-facing error: the message alone must tell what is wrong and where."""


class DataError(BellowsError):
    """
    A problem at a known place in a data file.

    Parameters
    ----------
    path : str
        The file.
    message : str
        What is wrong.
    line : int, optional
        1-based line of the file (the CSV header is line 1), or None for the whole file.
    column : str, optional
        Column name, or None.

    """

    def __init__(self, path, message, line=None, column=None):
        self.path, self.line, self.column = str(path), line, column
        where = self.path if line is None else f'{self.path}:{line}'
        what = message if column is None else f"column '{column}': {message}"
        super().__init__(f'{where}: {what}')


class ParameterError(BellowsError):
    """A bad, missing or unknown parameter (in a YAML file, on the command line, in --effect)."""
