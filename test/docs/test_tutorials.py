"""The tutorial notebooks are stored without outputs (the site's build executes them) and
cover the topics issue 32 asks for."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

TUTORIALS = sorted((Path(__file__).resolve().parents[2] / "docs" / "tutorials").glob("*.ipynb"))
TOPICS = ["first run", "sweeps", "continuation", "lyapunov", "covariant", "census", "basins"]


@pytest.mark.parametrize("notebook", TUTORIALS, ids=lambda p: p.name)
def test_stored_without_outputs(notebook: Path) -> None:
    cells = json.loads(notebook.read_text())["cells"]
    code = [c for c in cells if c["cell_type"] == "code"]
    assert code and all(not c["outputs"] and c["execution_count"] is None for c in code)


def test_the_topics_have_a_tutorial() -> None:
    titles = " ".join(json.loads(p.read_text())["cells"][0]["source"][0].lower()
                      for p in TUTORIALS)
    assert [t for t in TOPICS if t not in titles] == []
