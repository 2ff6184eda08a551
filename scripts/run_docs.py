"""Run the docs: every `sh`/`console`/`python` block of README.md and docs/*.md, in a temporary folder.

    python scripts/run_docs.py [PAGE.md ...] [--all] [--update] [--keep DIR]

The blocks of one page run in order in one folder (a page's shell blocks each in a fresh bash with
`set -e -o pipefail`, its Python blocks in one interpreter session), with `rx90` and `python` of
this interpreter's environment first on PATH and this checkout first on PYTHONPATH (as
tests/end_to_end/test_cli.py runs the command). The folders sit side by side under one temporary root beside
a link `shared` to the shared data (../shared of the checkout): a block that reads `../shared` is
skipped, saying so, when it is absent. Markers (scripts/doc_blocks.py): `<!-- docs: skip (reason)
-->`, `<!-- docs: slow -->` (run with --all: `make docs`), `<!-- docs: files PATH ... -->`,
`<!-- docs: excerpt ... -->`. With --update (needs --all) each console block's output is written back
into its page from what its commands printed (stdout, excerpted).

Prints one line per block and the counts (ran, slow, skipped with reasons); exit status 0 when every
block run passed, 1 when one failed, 2 when a page cannot be read (untagged fence, unknown marker).
"""
from __future__ import annotations

import argparse
import json
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from doc_blocks import Block, DocError, read_blocks, with_output  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
BLOCK_TIMEOUT_S = 1800.0
SLOW_HINT_S = 20.0  # a block not marked slow that takes longer is named (not failed: machines vary)

# The Python session: reads one JSON request a line ({"code", "file"}), runs it in one namespace,
# answers on the result pipe with {"ok", "error"}.
_SESSION = r"""
import json, os, sys, traceback
results = os.fdopen(int(sys.argv[1]), "w")
namespace = {"__name__": "__main__"}
for request in sys.stdin:
    block = json.loads(request)
    try:
        exec(compile(block["code"], block["file"], "exec"), namespace)
        answer = {"ok": True, "error": ""}
    except BaseException:
        answer = {"ok": False, "error": traceback.format_exc()}
    sys.stdout.flush(); sys.stderr.flush()
    results.write(json.dumps(answer) + "\n"); results.flush()
"""


def default_pages() -> list[Path]:
    return [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]


def environment(bin_dir: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([str(bin_dir), env.get("PATH", "")])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(REPO), env.get("PYTHONPATH", "")) if p)
    env["MPLBACKEND"] = "Agg"
    return env


def command_bin(root: Path) -> Path:
    """A folder with `python` and `rx90` of this interpreter (the venv's own when they are there)."""
    venv_bin = Path(sys.executable).parent
    if (venv_bin / "rx90").exists() and (venv_bin / "python").exists():
        return venv_bin
    shims = root / "bin"
    shims.mkdir(exist_ok=True)
    for name, line in (("python", f'exec "{sys.executable}" "$@"'),
                       ("rx90", f'exec "{sys.executable}" -m identify.app.cli "$@"')):
        (shims / name).write_text(f"#!/bin/sh\n{line}\n")
        (shims / name).chmod(0o755)
    return shims


class PythonSession:
    """One interpreter for a page's Python blocks, its output in a log file."""

    def __init__(self, folder: Path, env: dict[str, str], log: Path) -> None:
        read_end, write_end = os.pipe()
        self.log = log.open("a")
        self.process = subprocess.Popen([sys.executable, "-c", _SESSION, str(write_end)], cwd=folder, env=env,
                                        stdin=subprocess.PIPE, stdout=self.log, stderr=subprocess.STDOUT,
                                        text=True, pass_fds=(write_end,))
        os.close(write_end)
        self.results = os.fdopen(read_end)

    def run(self, block: Block) -> tuple[bool, str]:
        code = "\n" * block.start + "\n" + block.body  # tracebacks name the page's own line numbers
        try:
            self.process.stdin.write(json.dumps({"code": code, "file": str(block.page)}) + "\n")
            self.process.stdin.flush()
        except (BrokenPipeError, ValueError):
            return False, "the page's Python session had ended (an earlier block crashed or timed out)"
        ready, _, _ = select.select([self.results], [], [], BLOCK_TIMEOUT_S)
        if not ready:
            self.process.kill()
            return False, f"timed out after {BLOCK_TIMEOUT_S:.0f} s (the page's Python session was ended)"
        line = self.results.readline()
        if not line:
            return False, "the Python session ended (crashed or was killed)"
        answer = json.loads(line)
        return answer["ok"], answer["error"]

    def close(self) -> None:
        if self.process.poll() is None:
            try:
                self.process.stdin.close()
            except BrokenPipeError:
                pass
            try:
                self.process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.process.kill()
        self.results.close()
        self.log.close()


def run_shell(block: Block, folder: Path, env: dict[str, str]) -> tuple[bool, str, str]:
    """(passed, stdout, message) of a shell block run by bash in `folder`."""
    try:
        done = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", block.commands()], cwd=folder, env=env,
                              capture_output=True, text=True, timeout=BLOCK_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        return False, "", f"timed out after {BLOCK_TIMEOUT_S:.0f} s"
    if done.returncode != 0:
        tail = done.stdout.strip().splitlines()[-5:] + done.stderr.strip().splitlines()[-10:]
        return False, done.stdout, f"exit status {done.returncode}:\n" + "\n".join(tail)
    return True, done.stdout, ""


def _link_files(block: Block, folder: Path) -> None:
    for name in block.files:
        source = REPO / name
        if not source.exists():
            raise DocError(f"{block.where}: files marker: {name} is not in the repository")
        target = folder / source.name
        if not target.exists():
            target.symlink_to(source)


def run_page(page: Path, blocks: list[Block], folder: Path, env: dict[str, str], run_slow: bool,
             update: bool, tally: Counter, skips: Counter, failures: list[str]) -> None:
    folder.mkdir(parents=True)
    session: PythonSession | None = None
    outputs: list[tuple[Block, list[str]]] = []
    text_read = page.read_text(encoding="utf-8")
    blocks = read_blocks(page, text_read)  # as the page is now (it may have been edited since it was checked)
    name = page.relative_to(REPO) if page.is_relative_to(REPO) else page
    try:
        for block in blocks:
            if block.kind == "none":
                continue
            label = f"{name}:{block.line} ({block.tag})"
            if block.skip:
                tally["skipped"] += 1
                skips[block.skip] += 1
                print(f"  skip  {label}: {block.skip}")
                continue
            if block.slow and not run_slow:
                tally["slow"] += 1
                print(f"  slow  {label}: left to make docs")
                continue
            if "../shared" in block.body and not (folder.parent / "shared").exists():
                reason = "shared data absent (../shared not found)"
                tally["skipped"] += 1
                skips[reason] += 1
                print(f"  skip  {label}: {reason}")
                continue
            _link_files(block, folder)
            began = time.perf_counter()
            stdout = ""
            if block.kind == "python":
                session = session or PythonSession(folder, env, folder / "python-session.log")
                passed, message = session.run(block)
            else:
                passed, stdout, message = run_shell(block, folder, env)
            took = time.perf_counter() - began
            tally["slow" if block.slow else "ran"] += 1
            note = "" if block.slow or took <= SLOW_HINT_S else f"  (over {SLOW_HINT_S:.0f} s: mark it slow?)"
            print(f"  {'ok' if passed else 'FAIL':4}  {label} {took:.1f} s{note}", flush=True)
            if not passed:
                failures.append(f"{label}: {message.strip()}")
                print("        " + message.strip().replace("\n", "\n        "))
                continue
            if update and block.tag == "console":
                output = stdout.rstrip("\n").split("\n") if stdout.strip() else []
                if block.excerpt is not None:
                    output = block.excerpt.apply(output)
                outputs.append((block, output))
        if outputs and page.read_text(encoding="utf-8") != text_read:
            failures.append(f"{name}: the page changed while its blocks ran: output not written back (run again)")
            print(f"  FAIL  {failures[-1]}")
        elif outputs:
            lines = text_read.split("\n")
            for block, output in reversed(outputs):  # from the end: earlier blocks' lines stay where they were
                lines = with_output(lines, block, output)
            page.write_text("\n".join(lines), encoding="utf-8")
            print(f"  wrote {len(outputs)} console output(s) back into {name}")
    finally:
        if session is not None:
            session.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("pages", nargs="*", type=Path, help="markdown pages (default: README.md docs/*.md)")
    parser.add_argument("--all", action="store_true", help="also the blocks marked slow (make docs)")
    parser.add_argument("--update", action="store_true", help="write console blocks' output back (with --all)")
    parser.add_argument("--shared", type=Path, default=SHARED, help="the shared data (default: ../shared of the checkout)")
    parser.add_argument("--keep", type=Path, help="run in this new folder and keep it (default: a temporary one)")
    args = parser.parse_args(argv)
    if args.update and not args.all:
        parser.error("--update needs --all (a console block's output comes from its whole page being run)")
    pages = [p.resolve() for p in args.pages] or default_pages()
    try:
        parsed = [(page, read_blocks(page)) for page in pages]
    except (DocError, OSError) as error:
        print(f"run_docs: error: {error}", file=sys.stderr)
        return 2
    root = Path(tempfile.mkdtemp(prefix="docs-")) if args.keep is None else args.keep
    root.mkdir(parents=True, exist_ok=True)
    if args.shared.exists():
        (root / "shared").symlink_to(args.shared.resolve())
    env = environment(command_bin(root))
    tally: Counter = Counter()
    skips: Counter = Counter()
    failures: list[str] = []
    began = time.perf_counter()
    try:
        for page, blocks in parsed:
            if any(block.kind != "none" for block in blocks):
                print(f"{page.relative_to(REPO) if page.is_relative_to(REPO) else page}", flush=True)
                folder = root / page.stem
                while folder.exists():
                    folder = folder.with_name(folder.name + "_")
                run_page(page, blocks, folder, env, args.all, args.update, tally, skips, failures)
    except DocError as error:
        print(f"run_docs: error: {error}", file=sys.stderr)
        return 2
    finally:
        if args.keep is None:
            shutil.rmtree(root, ignore_errors=True)
    took = time.perf_counter() - began
    slow = f"{tally['slow']} slow ({'ran' if args.all else 'left to make docs'})"
    print(f"docs: {tally['ran']} ran, {slow}, {tally['skipped']} skipped, {len(failures)} failed in {took:.1f} s")
    for reason, count in sorted(skips.items()):
        print(f"  skipped {count}: {reason}")
    for failure in failures:
        print(f"FAILED {failure.splitlines()[0]}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
