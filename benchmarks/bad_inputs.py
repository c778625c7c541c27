"""Bad input refused at once: every case of the public API's hostile-input list, each in a
fresh process, with the exception it ends in, whether the message names the argument, the
call's time and the process's peak memory.

A case passes when it ends in the expected kind of outcome — a ``ValueError`` or
``TypeError`` whose message names the argument (or, for far goals, a failed result with a
reason; for NumPy scalars, a plan) — within :data:`TIME_LIMIT` seconds and
:data:`MEMORY_LIMIT` bytes of peak resident memory (the whole process, imports included).
Run as::

    python -m benchmarks.bad_inputs

Writes ``benchmarks/results/bad_inputs.md``; exit status 1 if any case fails.
"""
from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time

from .report import Report

TIME_LIMIT = 10.0
#: What a refusal of bad input raises.
REFUSALS = ("ValueError", "TypeError")
MEMORY_LIMIT = 2 * 2**30

#: (label, what it should end in — ``"refused"``: a ValueError or TypeError; a result; a
#: failed result —, the word the message must contain, the code of the call).
#: The code runs after ``import numpy as np, nonholo`` with ``R0``, ``Rd`` (a platform
#: start and goal) and ``tmp`` (an empty temporary folder) defined; it sets ``out``.
CASES = [
    ("plan(settings=Settings(harmonics=10000, steps=20000))", "refused", "harmonics",
     "out = nonholo.plan(R0, Rd, settings=nonholo.Settings(harmonics=10000, steps=20000))"),
    ("plan(settings=Settings(method='nonparametric', grid=10**6, steps=10**6), mechanism='car')", "refused",
     "grid",
     ("out = nonholo.plan([0, 0, 0, 0], [0, 1, 0, 0], mechanism='car', "
      "settings=nonholo.Settings(method='nonparametric', grid=10**6, steps=10**6))")),
    ("plan(settings=Settings(method='nonparametric', grid=10**6, steps=10**6), mechanism='rolling_ball')",
     "refused", "grid",
     ("out = nonholo.plan((np.eye(3), [0, 0]), (np.eye(3), [0, 1]), mechanism='rolling_ball', "
      "settings=nonholo.Settings(method='nonparametric', grid=10**6, steps=10**6))")),
    ("car goal at x = 1e15", "failed result", "",
     "out = nonholo.plan([0, 0, 0, 0], [1e15, 0, 0, 0], mechanism='car')"),
    ("ball goal at p = (1e15, 0)", "failed result", "",
     "out = nonholo.plan((np.eye(3), [0, 0]), (np.eye(3), [1e15, 0]), mechanism='rolling_ball')"),
    ("Mechanism.from_symbolic(None)", "refused", "mechanism",
     "out = nonholo.Mechanism.from_symbolic(None)"),
    ("Mechanism.from_symbolic('platform')", "refused", "mechanism",
     "out = nonholo.Mechanism.from_symbolic('platform')"),
    ("sweep(rows, out, client='tcp://x')", "refused", "client",
     ("from nonholo.batch.sweep import sweep\n"
      "out = sweep([{'start': R0.tolist(), 'goal': Rd.tolist()}], tmp + '/r.parquet', client='tcp://x')")),
    ("sweep(None, out)", "refused", "problems",
     "from nonholo.batch.sweep import sweep\nout = sweep(None, tmp + '/r.parquet')"),
    ("sweep(rows, an existing folder)", "refused", "out",
     ("from nonholo.batch.sweep import sweep\n"
      "out = sweep([{'start': R0.tolist(), 'goal': Rd.tolist()}], tmp)")),
    ("mechanism.L(np.eye(2))", "refused", "R",
     "out = nonholo.mechanism_named('platform').L(np.eye(2))"),
    ("mechanism.L(a NaN matrix)", "refused", "R",
     "out = nonholo.mechanism_named('platform').L(np.full((3, 3), np.nan))"),
    ("leg_lengths(np.eye(4))", "refused", "R",
     "out = nonholo.mechanism_named('platform').leg_lengths(np.eye(4))"),
    ("plan(callback=5)", "refused", "callback",
     "out = nonholo.plan(R0, Rd, callback=5)"),
    ("plan(T='1')", "refused", "T", "out = nonholo.plan(R0, Rd, T='1')"),
    ("plan(T=True)", "refused", "T", "out = nonholo.plan(R0, Rd, T=True)"),
    ("plan(complex goal)", "refused", "goal", "out = nonholo.plan(R0, Rd.astype(complex))"),
    ("car goal of booleans", "refused", "goal",
     "out = nonholo.plan([0, 0, 0, 0], [True, False, False, False], mechanism='car')"),
    ("plan(settings=Settings(tol=np.float32(1e-6)))", "result", "",
     "out = nonholo.plan(R0, Rd, settings=nonholo.Settings(tol=np.float32(1e-6)))"),
]

CHILD = """
import json, sys, time
import numpy as np
import nonholo
from nonholo.spaces import so3
R0, Rd = so3.from_rpy(0.1, 0.2, 0.3), so3.from_rpy(0.3, 0.2, 0.1)
tmp = sys.argv[1]
started = time.perf_counter()
try:
    exec(sys.argv[2])
    kind = "result" if not hasattr(out, "success") else ("result" if out.success else "failed result")
    message = "" if not hasattr(out, "reason") else out.reason
except Exception as exc:
    kind, message = type(exc).__name__, str(exc)
import resource
print(json.dumps({"kind": kind, "message": message, "seconds": time.perf_counter() - started,
                  "peak": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}))
"""


def run_case(code: str) -> dict:
    """The outcome of ``code`` in a fresh process: kind, message, the call's seconds, the
    process's peak resident memory (bytes) and its wall time (imports included)."""
    with tempfile.TemporaryDirectory() as tmp:
        started = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-c", CHILD, tmp, code], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        try:
            stdout, stderr = proc.communicate(timeout=120)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()
            return {"kind": "timeout", "message": "", "seconds": 120.0, "peak": 0, "wall": 120.0}
        wall = time.perf_counter() - started
    if proc.returncode != 0 or not stdout.strip():
        last = stderr.strip().splitlines()[-1:] or [""]
        return {"kind": "crash", "message": last[0], "seconds": wall, "peak": 0, "wall": wall}
    return {**json.loads(stdout.strip().splitlines()[-1]), "wall": wall}


def main() -> int:
    report = Report("bad_inputs.md", "Bad input refused at once", "benchmarks.bad_inputs")
    report.paragraph(
        "Each case in a fresh process (`python -c`, the package imported first). *Call s*: the "
        "call's time; *peak*: the process's largest resident memory (`getrusage`, imports "
        "included); *names it*: "
        f"the message contains the argument's name. Limits: {TIME_LIMIT:g} s for the call, "
        f"{MEMORY_LIMIT / 2**30:g} GiB peak.")
    rows, failed = [], 0
    for label, expected, word, code in CASES:
        out = run_case(code)
        names = (word in out["message"]) if word else True
        got = "refused" if out["kind"] in REFUSALS else out["kind"]
        ok = (got == expected and names and out["seconds"] <= TIME_LIMIT
              and out["peak"] <= MEMORY_LIMIT)
        failed += not ok
        message = out["message"]
        rows.append([f"`{label}`", expected, out["kind"], "yes" if names else "no", f"{out['seconds']:.2f}",
                     f"{out['peak'] / 2**20:.0f} MiB", "pass" if ok else "FAIL",
                     message[:140] + ("…" if len(message) > 140 else "")])
        print(f"{label}: {out['kind']} in {out['seconds']:.2f} s ({'pass' if ok else 'FAIL'})", file=sys.stderr)
    report.table(["case", "expected", "got", "names it", "call s", "peak", "verdict", "message"], rows,
                 align=["l", "l", "l", "l", "r", "r", "l", "l"])
    report.paragraph(f"{len(CASES) - failed} of {len(CASES)} cases pass.")
    report.write()
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
