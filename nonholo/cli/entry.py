"""Command line: ``nonholo derive | audit | mechanisms | plan | execute | animate | reproduce | sweep | atlas |
dynobench``.

The parser lists every command (:data:`nonholo.cli.commands.COMMANDS`), but adds the
arguments of the one command run (of all of them for :func:`build_parser` without
arguments): a command's module (``plan_command`` …) is imported only when that command runs
or shows its help, so that ``nonholo --help`` loads none of them.
"""
from __future__ import annotations

import argparse
import importlib
import json
import os
import sys
import time
from pathlib import Path

from .commands import COMMANDS


def _derive(args) -> int:
    from derivations import codegen

    from ..integrate import compiled

    t0 = time.perf_counter()
    outdir = Path(args.dir) if args.dir else codegen.GENERATED_DIR
    why = _derive_dir_error(outdir, args.check)
    if why is None:
        files = compiled.generated_files()
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
    from ..model import bounds, catalog

    names = catalog.names()
    width = max(16, *(len(n) for n in names))
    for name in names:
        m = catalog.get(name)
        singular = m.singular.summary + (", with drift" if m.has_drift else "")
        state = m.space.recorded("coordinates", f"state {m.state_space}: {' '.join(m.space.cli_names)}, ", "")
        limits = bounds.describe(m)
        print(f"{name:<{width}} {m.description} ({state}{m.n_inputs} inputs, {singular}"
              + (f"; bounds {limits})" if limits else ")"))
    return 0


def derive_arguments(p: argparse.ArgumentParser) -> None:
    """Give the ``derive`` command's parser ``p`` its arguments and the function that runs it.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    """
    p.add_argument("--check", action="store_true",
                   help="only compare the committed modules with a fresh derivation (exit 1 if stale)")
    p.add_argument("-v", "--verbose", action="store_true", help="print the diff of stale files")
    p.add_argument("--dir", help="generated-modules directory (default: nonholo/generated)")
    p.set_defaults(func=_derive)


def audit_arguments(p: argparse.ArgumentParser) -> None:
    """Give the ``audit`` command's parser ``p`` its arguments and the function that runs it.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    """
    p.add_argument("--json", action="store_true", help="print a JSON list instead of a table")
    p.set_defaults(func=_audit)


def mechanisms_arguments(p: argparse.ArgumentParser) -> None:
    """Give the ``mechanisms`` command's parser ``p`` the function that runs it.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    """
    p.set_defaults(func=_mechanisms)


def add_command(subparsers, name: str) -> argparse.ArgumentParser:
    """Add the command ``name`` with its arguments to an ``argparse`` sub-parsers object.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        What ``ArgumentParser.add_subparsers`` returned.
    name : str
        The command, a key of :data:`nonholo.cli.commands.COMMANDS`.

    Returns
    -------
    argparse.ArgumentParser
        The command's parser; it sets ``func``, the function that runs the command.
    """
    p = subparsers.add_parser(name, help=COMMANDS[name].help)
    _arguments(name)(p)
    return p


def _arguments(name: str):
    """The function that adds the command ``name``'s arguments to its parser (its module
    imported now)."""
    command = COMMANDS[name]
    return getattr(importlib.import_module(f".{command.module}", __package__), command.arguments)


def build_parser(commands=None) -> argparse.ArgumentParser:
    """The command line's parser, one subcommand per command.

    Parameters
    ----------
    commands : iterable of str, optional
        The commands whose arguments are added (default: every one); the others are listed,
        with no arguments.

    Returns
    -------
    argparse.ArgumentParser
        The parser; each subcommand with its arguments sets ``func``, the function that runs it.
    """
    commands = set(COMMANDS if commands is None else commands)
    parser = argparse.ArgumentParser(
        prog="nonholo", description="Motion planning of non-holonomic systems on SO(3).")
    sub = parser.add_subparsers(dest="command", required=True)
    for name, command in COMMANDS.items():
        if name in commands:
            add_command(sub, name)
        else:
            sub.add_parser(name, help=command.help)
    return parser


def command_named(argv: list[str]) -> str | None:
    """The command ``argv`` runs: its first argument not an option (``nonholo`` itself has
    no option that takes a value).

    Parameters
    ----------
    argv : list of str
        The command line's arguments.

    Returns
    -------
    str or None
        The command's name, or ``None``.
    """
    return next((arg for arg in argv if not arg.startswith("-")), None)


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
    argv = sys.argv[1:] if argv is None else list(argv)
    args = build_parser([command_named(argv)]).parse_args(argv)
    try:
        return args.func(args)
    except BrokenPipeError:            # the reader closed stdout (``| head``): not an error
        from .plan_command import discard_stdout

        discard_stdout()
        return 0


if __name__ == "__main__":
    sys.exit(main())
