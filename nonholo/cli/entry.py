"""Command line: ``nonholo derive | audit | mechanisms | plan | execute | animate | reproduce | sweep | atlas``."""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

from ..model import bounds, catalog
from . import animate_command as cli_animate
from . import execute_command as cli_execute
from . import plan_command as cli_plan
from . import reproduce_command as cli_reproduce
from . import sweep_command as cli_sweep


def _derive(args) -> int:
    from derivations import codegen

    from ..integrate import inliner

    t0 = time.perf_counter()
    outdir = Path(args.dir) if args.dir else codegen.GENERATED_DIR
    why = _derive_dir_error(outdir, args.check)
    if why is None:
        files = inliner.every_generated_file()
        try:
            if args.check:
                stale = codegen.check(outdir, files)
            else:
                written = codegen.write(outdir, files)
        except OSError as exc:
            why = f"cannot {'read' if args.check else 'write'} {exc.filename or outdir}: {exc.strerror or exc}"
    if why is not None:
        print(f"nonholo derive: error: --dir {outdir}: {why}", file=sys.stderr)
        return 2
    if args.check:
        for path, diff in stale:
            print(f"stale: {path}", file=sys.stderr)
            if args.verbose:
                print(diff, file=sys.stderr)
        if stale:
            print("generated code differs from a fresh derivation: run `nonholo derive`",
                  file=sys.stderr)
            return 1
        print(f"generated modules are up to date ({time.perf_counter() - t0:.1f} s)")
        return 0
    for path in written:
        print(f"wrote {path}")
    print(f"done in {time.perf_counter() - t0:.1f} s")
    return 0


def _derive_dir_error(outdir: Path, check: bool) -> str | None:
    """Why ``derive`` cannot use ``outdir`` (checked before the derivation): for ``--check``
    a directory that does not exist or is not one; for writing, one that is a file or
    below one, or not writable; ``None`` if it may be used."""
    if outdir.exists() and not outdir.is_dir():
        return "not a directory"
    if check:
        return None if outdir.is_dir() else "no such directory (nothing to check)"
    existing = outdir
    while not existing.exists():                 # the nearest existing ancestor is created from
        if existing.parent == existing:
            break
        existing = existing.parent
    if not existing.is_dir():
        return f"cannot be created: {existing} is not a directory"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"not writable ({existing})"
    return None


def _audit(args) -> int:
    from derivations import audit

    from ..paper import appendix_audit

    findings = appendix_audit.run()
    if args.json:
        print(json.dumps([{"equation": f.equation, "verdict": f.verdict, "note": f.note}
                          for f in findings], indent=2, ensure_ascii=False))
    else:
        print(audit.format_table(findings))
    return 0


def _mechanisms(args) -> int:
    for name in catalog.names():
        m = catalog.get(name)
        singular = "singular set Δ = 0" if m.singular.exists else "no singular set"
        state = "" if not m.space.k else f"state {m.state_space}: " + " ".join(
            (["φ", "ϑ", "ψ"] if m.space.has_orientation else []) + list(m.coordinates)) + ", "
        limits = bounds.describe(m)
        print(f"{name:<16} {m.description} ({state}{m.n_inputs} inputs, {singular}"
              + (f"; bounds {limits})" if limits else ")"))
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The command line's parser, one subcommand per command.

    Returns
    -------
    argparse.ArgumentParser
        The parser; each subcommand sets ``func``, the function that runs it.
    """
    parser = argparse.ArgumentParser(
        prog="nonholo", description="Motion planning of non-holonomic systems on SO(3).")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("derive", help="derive the kinematics symbolically and write nonholo/generated")
    p.add_argument("--check", action="store_true",
                   help="only compare the committed modules with a fresh derivation (exit 1 if stale)")
    p.add_argument("-v", "--verbose", action="store_true", help="print the diff of stale files")
    p.add_argument("--dir", help="generated-modules directory (default: nonholo/generated)")
    p.set_defaults(func=_derive)

    p = sub.add_parser("audit", help="hold the appendix formulas against the derivation")
    p.add_argument("--json", action="store_true", help="print a JSON list instead of a table")
    p.set_defaults(func=_audit)

    p = sub.add_parser("mechanisms", help="list the mechanisms")
    p.set_defaults(func=_mechanisms)

    cli_plan.add_parser(sub)
    cli_execute.add_parser(sub)
    cli_animate.add_parser(sub)
    cli_reproduce.add_parser(sub)
    cli_sweep.add_parsers(sub)
    return parser


def tolerate_any_encoding() -> None:
    """Let stdout and stderr write any text under any encoding (``PYTHONIOENCODING=ascii``,
    a C locale): a character the encoding lacks (``Δ``, ``γ``) is written escaped
    (``\\u0394``), not an error that would turn a successful command into a failure."""
    for stream in (sys.stdout, sys.stderr):
        reconfigure = getattr(stream, "reconfigure", None)
        if reconfigure is not None and getattr(stream, "errors", None) == "strict":
            try:
                reconfigure(errors="backslashreplace")
            except (ValueError, OSError):       # a closed or detached stream: leave it
                pass


def main(argv: list[str] | None = None) -> int:
    """Run ``nonholo`` with the arguments ``argv``.

    Parameters
    ----------
    argv : list of str, optional
        The arguments (default: the process's).

    Returns
    -------
    int
        The exit status.
    """
    tolerate_any_encoding()
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except BrokenPipeError:            # the reader closed stdout (``| head``): not an error
        cli_plan.discard_stdout()
        return 0


if __name__ == "__main__":
    sys.exit(main())
