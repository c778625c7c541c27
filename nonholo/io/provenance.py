"""What made an output: the nonholo version and commit, and the versions of Python, the
numerical libraries and the C compiler of the kernels.

:func:`made_by` is recorded in every plan file (``"made_by"``, see
:mod:`nonholo.io.plan_file`) and in ``paper_figures/summary.json``, so that a number can be
traced to the code and the libraries that computed it. It is read once per process.
The commit is that of the checkout the package runs from (``None`` for an installed copy
without ``.git``), with ``" + uncommitted changes"`` when the code differs from it
(outputs, ``paper_figures/`` and ``benchmarks/results/``, aside).
"""
from __future__ import annotations

import functools
import platform
import subprocess
from importlib import metadata
from pathlib import Path

__all__ = ["made_by", "git_revision", "KEYS"]

#: The keys of :func:`made_by`, in order.
KEYS = ("nonholo", "commit", "python", "numpy", "scipy", "sympy", "compiler", "kernels")
#: Where the package's checkout would be.
_ROOT = Path(__file__).resolve().parents[2]
#: Outputs, not code: a change there does not make the code differ from its commit.
_OUTPUTS = ("paper_figures", "benchmarks/results")


def git_revision(short: bool = True) -> str | None:
    """HEAD of the package's checkout, with ``" + uncommitted changes"`` if the code differs.

    Parameters
    ----------
    short : bool
        The short hash (else the full one).

    Returns
    -------
    str or None
        ``None`` outside a git checkout or without git.
    """
    if not (_ROOT / ".git").exists() or not (_ROOT / "nonholo" / "__init__.py").is_file():
        return None
    try:
        rev = subprocess.run(["git", "rev-parse", *(["--short"] if short else []), "HEAD"],
                             capture_output=True, text=True, cwd=_ROOT, timeout=10)
        if rev.returncode != 0:
            return None
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", ".",
                                *(f":(exclude){p}" for p in _OUTPUTS)],
                               capture_output=True, text=True, cwd=_ROOT, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return rev.stdout.strip() + (" + uncommitted changes" if dirty.stdout.strip() else "")


def _version(package: str) -> str | None:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return None


def _compiler() -> str | None:
    """The first line of ``<cc> --version`` of the compiler the native kernels use."""
    from ..codegen import build

    cc = build.compiler()
    if cc is None:
        return None
    try:
        out = subprocess.run([cc, "--version"], capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return cc
    first = out.stdout.strip().splitlines()
    return first[0] if out.returncode == 0 and first else cc


@functools.lru_cache(maxsize=1)
def _made_by() -> tuple:
    from ..codegen import build

    return (("nonholo", _version("nonholo")), ("commit", git_revision(short=False)),
            ("python", platform.python_version()), ("numpy", _version("numpy")),
            ("scipy", _version("scipy")), ("sympy", _version("sympy")),
            ("compiler", _compiler()), ("kernels", "native" if build.enabled() else "numba"))


def made_by() -> dict:
    """This process's record of what makes its outputs (keys :data:`KEYS`).

    Returns
    -------
    dict
        Strings, ``None`` where a part is not known (no checkout, no compiler).
    """
    return dict(_made_by())
