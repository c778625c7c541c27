"""Every command ends quietly when the reader closes its output (``| head``)."""
import subprocess

import pytest


@pytest.mark.parametrize("command", ["nonholo mechanisms | head -0", "nonholo mechanisms | true",
                                     "nonholo plan --from 0.1 0.2 0.3 --to 0.3 0.2 0.1 | head -1",
                                     "nonholo audit --help | true"])
def test_closed_stdout_is_not_an_error(command):
    out = subprocess.run(["bash", "-o", "pipefail", "-c", command], capture_output=True, text=True,
                         timeout=300)
    assert "Traceback" not in out.stderr and "BrokenPipe" not in out.stderr, out.stderr
    assert out.returncode == 0, out.stderr


def test_python_dash_m_nonholo_is_the_command_line():
    import sys

    script = subprocess.run(["nonholo", "mechanisms"], capture_output=True, text=True, timeout=300)
    module = subprocess.run([sys.executable, "-m", "nonholo", "mechanisms"], capture_output=True, text=True,
                            timeout=300)
    assert script.returncode == module.returncode == 0, module.stderr
    assert module.stdout == script.stdout and "car_trailer" not in module.stdout and "unicycle" in module.stdout
