"""Every command ends quietly when the reader closes its output (``| head``)."""
import subprocess

import pytest


@pytest.mark.parametrize("command", ["nonholo mechanisms | head -0", "nonholo audit | true",
                                     "nonholo audit --json | head -1"])
def test_closed_stdout_is_not_an_error(command):
    out = subprocess.run(["bash", "-o", "pipefail", "-c", command], capture_output=True, text=True,
                         timeout=300)
    assert "Traceback" not in out.stderr and "BrokenPipe" not in out.stderr, out.stderr
    assert out.returncode == 0, out.stderr
