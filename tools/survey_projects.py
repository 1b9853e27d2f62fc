"""Survey public TwinCAT / CODESYS projects: how many of their source files stvm checks clean,
and which messages block the rest (docs/survey.md).

    python tools/survey_projects.py --dialect twincat DIR [DIR ...] [--library NAME=DIR]
                                    [--mode project|alone] [--top 15] [--json OUT]

Each DIR is one project (a folder of TwinCAT XML sources or `.st` files, or a `.plcproj`): the
snapshot stays outside the repository. What is measured per source file:

- `--mode project` (the default): every file is first parsed alone (a syntax error makes the file
  not clean); then all files that parse are checked together, as `stvm check` checks a project,
  and a file is clean when no error of that check lies in it. The other files of the project are
  context, so a call to a POU of the same project is not counted against the file.
- `--mode alone`: `stvm check FILE` on each file by itself (any reference to another file of the
  project is an error): the stricter measure of an earlier survey.

The top messages are counted by their text with quoted names kept (`undefined name 'F_X'`), so
the list shows which platform functions the code calls that stvm lacks.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

from stvm.project import Options, check, parse_unit, read_files, resolve

SUFFIXES = (".st", ".tcpou", ".tcdut", ".tcgvl", ".tcio")


def project_files(root: Path) -> list[Path]:
    if root.is_file():
        return [root]
    return sorted(p for p in root.rglob("*") if p.is_file() and p.suffix.lower() in SUFFIXES
                  and "_Boot" not in p.parts)


_HEADER = re.compile(r"^\s*(PROGRAM|FUNCTION_BLOCK|FUNCTION|INTERFACE|TYPE)\b", re.IGNORECASE | re.MULTILINE)


def closed_copies(files: list[Path], root: Path, scratch: Path) -> list[Path]:
    """`--append-end`: copies of `.st` files under `scratch` with the END_ keyword of their POU
    added when the file lacks it, as a CODESYS export writes a POU (declaration and body, no
    END_PROGRAM). A rewrite made for measuring only: the survey reports how many files are clean
    given that one line."""
    out = []
    for path in files:
        target = scratch / "closed" / root.name / path.relative_to(root if root.is_dir() else root.parent)
        target.parent.mkdir(parents=True, exist_ok=True)
        text = path.read_text(encoding="utf-8", errors="replace")
        header = _HEADER.search(text)
        if path.suffix.lower() == ".st" and header is not None:
            end = "END_" + header.group(1).upper()
            if end not in text.upper():
                text = text.rstrip() + f"\n{end}\n"
        target.write_text(text, encoding="utf-8")
        out.append(target)
    return out


def _errors(diags) -> list:
    return [d for d in diags if d.is_error]


def _key(diag) -> str:
    return f"{diag.message} [{diag.code}]" if diag.code else diag.message


def _options(dialect: str, libraries: list[tuple[str, str]]) -> Options:
    return Options(dialect=dialect, libraries=tuple(libraries))


def parseable_libraries(libraries, dialect: str, scratch: Path) -> list[tuple[str, str]]:
    """Each library as a folder (under `scratch`) of links to those of its files that parse: one
    file of a library that stvm cannot parse would stop the check of every project using it, and
    the survey measures the project's files, not its libraries'."""
    from stvm.libraries import Library, library_files   # lazy: only with --library
    out = []
    for name, folder in libraries:
        files = library_files(Library(name, Path(folder)))
        settings = resolve(files[:1], _options(dialect, [])).settings
        target = scratch / name
        for path, (_, text) in zip(files, read_files(files)[0]):
            if _errors(parse_unit(str(path), text, settings)[1]):
                continue
            link = target / f"{len(list(target.glob('*'))) if target.exists() else 0}_{path.name}"
            link.parent.mkdir(parents=True, exist_ok=True)
            link.symlink_to(path.resolve())
        out.append((name, str(target)))
    return out


def survey_alone(files: list[Path], dialect: str, libraries) -> tuple[dict[Path, list], Counter]:
    per_file, messages = {}, Counter()
    for path in files:
        _, diags, _ = check(resolve([path], _options(dialect, libraries)))
        errs = [d for d in _errors(diags) if Path(d.span.file).resolve() == path.resolve()] or _errors(diags)
        per_file[path] = errs
        messages.update(_key(d) for d in errs)
    return per_file, messages


def survey_project(files: list[Path], dialect: str, libraries, context: list[Path] = ()) -> tuple[dict[Path, list], Counter]:
    settings = resolve(files[:1], _options(dialect, libraries)).settings
    per_file: dict[Path, list] = {p: [] for p in files}
    parseable = []
    texts, read_diags = read_files(files)
    # context: the files of another project this one uses (its errors are not counted)
    extra = [p for p, (name, text) in zip(context, read_files(list(context))[0])
             if not _errors(parse_unit(name, text, settings)[1])]
    by_name = {str(p): p for p in files}
    for name, text in texts:
        _, diags = parse_unit(name, text, settings)
        errs = _errors(diags)
        if errs:
            per_file[by_name.get(name, Path(name))] = errs
        else:
            parseable.append(by_name.get(name, Path(name)))
    for d in _errors(read_diags):
        per_file.setdefault(Path(d.span.file), []).append(d)
    if parseable:
        _, diags, _ = check(resolve(extra + parseable, _options(dialect, libraries)))
        resolved = {p.resolve(): p for p in parseable}
        for d in _errors(diags):
            owner = resolved.get(Path(d.span.file).resolve()) if d.span.file else None
            if owner is not None:
                per_file[owner].append(d)
    messages = Counter(_key(d) for errs in per_file.values() for d in errs)
    return per_file, messages


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("projects", nargs="+", type=Path)
    parser.add_argument("--dialect", default="twincat", choices=("twincat", "codesys", "iec"))
    parser.add_argument("--library", action="append", default=[], metavar="NAME=DIR")
    parser.add_argument("--context", action="append", default=[], type=Path, metavar="DIR",
                        help="another project whose files that parse are checked with each project "
                             "(unqualified, errors not counted): a library a project uses by short names")
    parser.add_argument("--append-end", action="store_true",
                        help="add the missing END_PROGRAM/END_FUNCTION_BLOCK/… of a .st POU (CODESYS "
                             "exports omit it) in a copy before checking")
    parser.add_argument("--mode", default="project", choices=("project", "alone"))
    parser.add_argument("--top", type=int, default=15)
    parser.add_argument("--json", type=Path, help="write the numbers as JSON to this file")
    args = parser.parse_args(argv)
    libraries = [tuple(part.strip() for part in lib.split("=", 1)) for lib in args.library]
    scratch = Path(tempfile.mkdtemp(prefix="stvm-survey-"))
    libraries = parseable_libraries(libraries, args.dialect, scratch)
    report = {}
    for root in args.projects:
        files = project_files(root)
        if args.append_end:
            files = closed_copies(files, root, scratch)
        if not files:
            print(f"{root}: no sources", file=sys.stderr)
            continue
        start = time.monotonic()
        context = [p for folder in args.context for p in project_files(folder)]
        per_file, messages = (survey_alone(files, args.dialect, libraries) if args.mode == "alone"
                              else survey_project(files, args.dialect, libraries, context))
        clean = sum(1 for errs in per_file.values() if not errs)
        # the first error of each file: what blocks it (later ones often follow from it, e.g. a
        # variable of an unknown type has no members)
        first = Counter(_key(min(errs, key=lambda d: (d.span.line, d.span.column)))
                        for errs in per_file.values() if errs)
        print(f"== {root}: {clean} of {len(per_file)} files clean ({args.mode}, {args.dialect}, "
              f"{time.monotonic() - start:.0f} s)")
        print("  first error of each file not clean:")
        for text, count in first.most_common(args.top):
            print(f"  {count:5d}  {text}")
        print("  all errors:")
        for text, count in messages.most_common(args.top):
            print(f"  {count:5d}  {text}")
        report[str(root)] = {"files": len(per_file), "clean": clean, "mode": args.mode,
                             "dialect": args.dialect, "first": first.most_common(args.top),
                             "top": messages.most_common(args.top)}
    if args.json:
        args.json.write_text(json.dumps(report, indent=1), encoding="utf-8")
    shutil.rmtree(scratch, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
