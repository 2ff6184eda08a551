"""The docs run: scripts/run_docs.py on README.md and docs/*.md (the fast blocks; `make docs` runs
the slow ones), and the runner itself on small pages written here: it fails on a broken command and
on a broken Python block, keeps a page's Python session, counts skips with their reasons."""
from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RUNNER = ROOT / "scripts" / "run_docs.py"


def run_docs(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(RUNNER), *args], capture_output=True, text=True, timeout=1800)


def doc_blocks():
    spec = importlib.util.spec_from_file_location("doc_blocks", ROOT / "scripts" / "doc_blocks.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["doc_blocks"] = module
    spec.loader.exec_module(module)
    return module


def counts(output: str) -> dict[str, int]:
    line = re.search(r"^docs: (\d+) ran, (\d+) slow .*?, (\d+) skipped, (\d+) failed", output, re.M)
    assert line, output
    return dict(zip(("ran", "slow", "skipped", "failed"), map(int, line.groups())))


@pytest.mark.slow
def test_the_docs_run():
    done = run_docs()
    print(done.stdout[-3000:])
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-2000:]
    found = counts(done.stdout)
    assert found["ran"] >= 5 and found["failed"] == 0


def test_every_fence_of_the_docs_is_tagged():
    module = doc_blocks()
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    blocks = [block for page in pages for block in module.read_blocks(page)]
    assert blocks and all(block.tag for block in blocks)
    assert any(block.kind == "python" for block in blocks) and any(block.kind == "shell" for block in blocks)


def test_a_broken_command_fails_the_page(tmp_path):
    page = tmp_path / "broken.md"
    page.write_text("# A page\n\n```sh\nrx90 --version\n```\n\n```console\n$ rx90 model --robot no-such-robot\n"
                    "54 base parameters\n```\n")
    done = run_docs(str(page))
    assert done.returncode == 1, done.stdout
    assert "FAIL  " in done.stdout and "broken.md:7 (console)" in done.stdout
    assert "no-such-robot" in done.stdout  # the command's own message is shown
    assert counts(done.stdout) == {"ran": 2, "slow": 0, "skipped": 0, "failed": 1}


def test_a_broken_python_block_fails_and_names_its_line(tmp_path):
    page = tmp_path / "tour.md"
    page.write_text("# Tour\n\n```python\nimport rx90sym\nrobot = rx90sym.load_robot('rx90')\n```\n\n"
                    "```python\nn = robot.n\ntau = robot.inverse_dynamics(q, qd, qdd, chi)\n```\n")
    done = run_docs(str(page))
    assert done.returncode == 1, done.stdout
    assert "NameError" in done.stdout and "name 'q' is not defined" in done.stdout
    assert re.search(r"tour\.md\", line 10", done.stdout), done.stdout  # the page's own line number
    assert counts(done.stdout)["failed"] == 1


def test_one_folder_and_one_session_per_page_skips_counted(tmp_path):
    page = tmp_path / "page.md"
    page.write_text(
        "```text\nrx90 identify REC.csv [--json FILE]\n```\n\n"
        "```sh\nprintf 't,x\\n0,1\\n' > made.csv\n```\n\n"
        "```python\nrows = open('made.csv').read().split()\n```\n\n"
        "<!-- docs: skip (make test: the whole suite) -->\n```sh\nexit 1\n```\n\n"
        "<!-- docs: slow -->\n```python\nraise RuntimeError('only in make docs')\n```\n\n"
        "```python\nassert rows == ['t,x', '0,1'], rows\n```\n")
    done = run_docs(str(page))
    assert done.returncode == 0, done.stdout + done.stderr
    assert counts(done.stdout) == {"ran": 3, "slow": 1, "skipped": 1, "failed": 0}
    assert "skipped 1: make test: the whole suite" in done.stdout
    everything = run_docs(str(page), "--all")  # the slow block now runs, and fails
    assert everything.returncode == 1 and "only in make docs" in everything.stdout


def test_untagged_fence_and_unknown_marker_are_refused(tmp_path):
    untagged = tmp_path / "untagged.md"
    untagged.write_text("text\n\n```\nrx90 model\n```\n")
    done = run_docs(str(untagged))
    assert done.returncode == 2 and "untagged.md:3: untagged fence" in done.stderr
    marker = tmp_path / "marker.md"
    marker.write_text("<!-- docs: skipp (typo) -->\n```sh\ntrue\n```\n")
    done = run_docs(str(marker))
    assert done.returncode == 2 and "unknown docs marker 'skipp'" in done.stderr


def test_console_output_written_back_with_its_excerpt(tmp_path):
    page = tmp_path / "out.md"
    page.write_text("before\n\n<!-- docs: excerpt ^b@2 ^e -->\n```console\n$ printf 'a\\nb\\nc\\nd\\ne\\nf\\n'\n"
                    "old output\n```\n\nafter\n")
    done = run_docs(str(page), "--all", "--update")
    assert done.returncode == 0, done.stdout + done.stderr
    assert page.read_text() == ("before\n\n<!-- docs: excerpt ^b@2 ^e -->\n```console\n"
                                "$ printf 'a\\nb\\nc\\nd\\ne\\nf\\n'\n...\nb\nc\n...\ne\n...\n```\n\nafter\n")


def test_blocks_on_the_shared_data_skip_when_it_is_absent(tmp_path):
    shared = tmp_path / "shared"
    (shared / "data").mkdir(parents=True)
    (shared / "data" / "log.csv").write_text("t,q1\n0,0.5\n")
    page = tmp_path / "real.md"
    page.write_text("```sh\nhead -1 ../shared/data/log.csv | grep -q t,q1\n```\n")
    done = run_docs(str(page), "--shared", str(shared))
    assert done.returncode == 0 and counts(done.stdout)["ran"] == 1, done.stdout + done.stderr
    done = run_docs(str(page), "--shared", str(tmp_path / "absent"))
    assert done.returncode == 0, done.stdout + done.stderr
    assert counts(done.stdout) == {"ran": 0, "slow": 0, "skipped": 1, "failed": 0}
    assert "shared data absent" in done.stdout
