import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from oceanloc.errors import DataError
from oceanloc.io.journal import Journal

WRITER = """
import sys
from oceanloc.io.journal import Journal
j = Journal(sys.argv[1])
for k in range(100000):
    j.add_fix(1.5e9 + k, 32.7 + 1e-6 * k, -117.2, 0.0)
    j.add_range(1.5e9 + k + 0.5, 1 + k % 2, 10.0 + 0.001 * k)
    if k == 50:
        print("running", flush=True)
"""


def test_readd_is_idempotent_and_bad_values_rejected(tmp_path: Path):
    with Journal(tmp_path / "j.db") as j:
        assert j.add_fix(1.0, 32.7, -117.2, 0.0) is True
        assert j.add_fix(1.0, 32.7, -117.2, 0.0) is False
        assert j.add_range(1.5, 1, 9.0) and not j.add_range(1.5, 1, 9.0)
        with pytest.raises(DataError, match="negative"):
            j.add_range(2.0, 1, -1.0)
        assert j.fixes().shape == (1, 4) and j.ranges().shape == (1, 3)


def test_killed_writer_loses_nothing_committed_and_resumes_identically(tmp_path: Path):
    path = tmp_path / "survey.db"
    proc = subprocess.Popen([sys.executable, "-c", WRITER, str(path)], stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "running"
    time.sleep(0.3)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    with Journal(path) as j:
        fixes, ranges = j.fixes(), j.ranges()
    n = fixes.shape[0]
    assert n > 50
    # Committed records form an unbroken prefix of the stream: nothing committed was lost.
    np.testing.assert_array_equal(fixes[:, 0], 1.5e9 + np.arange(n))
    assert ranges.shape[0] in (n - 1, n)
    # Replaying the whole stream prefix again is idempotent: the state is identical.
    with Journal(path) as j:
        for k in range(n):
            j.add_fix(1.5e9 + k, 32.7 + 1e-6 * k, -117.2, 0.0)
        np.testing.assert_array_equal(j.fixes(), fixes)
