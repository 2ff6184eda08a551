"""Every notebook runs top to bottom (nbclient), in a scratch folder, with the public API only."""
from __future__ import annotations

import shutil
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

NOTEBOOKS = sorted((Path(__file__).resolve().parents[2] / "notebooks").glob("*.ipynb"))


def test_notebooks_are_committed_without_outputs():
    assert len(NOTEBOOKS) >= 6
    for path in NOTEBOOKS:
        nb = nbformat.read(path, as_version=4)
        for cell in nb.cells:
            if cell.cell_type == "code":
                assert not cell.outputs and cell.execution_count is None, path.name


def test_notebooks_use_only_the_public_api():
    import re

    for path in NOTEBOOKS:
        text = "\n".join(c.source for c in nbformat.read(path, as_version=4).cells if c.cell_type == "code")
        # No submodule imports and no private names of the three packages.
        assert not re.search(r"from (rx90sym|identify|excitation)\.", text), path.name
        assert not re.search(r"\b(rx90sym|identify|excitation)\.(?!__)_", text), path.name


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_runs(path, tmp_path):
    nb = nbformat.read(path, as_version=4)
    work = tmp_path / path.stem
    work.mkdir()
    shutil.copy(path, work / path.name)
    if (path.parent / "data").is_dir():  # what the notebooks read beside them (notebooks/data/README.md)
        shutil.copytree(path.parent / "data", work / "data")
    NotebookClient(nb, timeout=600, kernel_name="python3",
                   resources={"metadata": {"path": str(work)}}).execute()
