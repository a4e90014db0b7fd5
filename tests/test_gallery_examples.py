"""Every gallery example (examples/gallery/plot_*.py) runs and draws its figures.

``make docs`` executes the gallery too (and CI builds the docs with warnings as errors),
but the examples call the library's public API, so an API change that breaks one should
fail ``make test`` first, with a traceback, rather than a docs build. Each script runs
in-process (Agg backend) in a fresh namespace; it must bind at least one matplotlib
Figure, which is what the docs' gallery scraper saves. The four longest examples (λ scan,
basin grid, rods regime map, dissipation-peak runs; 5–10 s each on an idle 2-core
machine) are marked slow.
"""

from __future__ import annotations

import runpy
from pathlib import Path

import matplotlib
import pytest
from matplotlib.figure import Figure

matplotlib.use("Agg")

GALLERY = Path(__file__).resolve().parents[1] / "examples" / "gallery"
SCRIPTS = sorted(GALLERY.glob("plot_*.py"))
SLOW = {"plot_07_rods_limit_frequency.py", "plot_08_lambda_dissipation.py",
        "plot_09_basins.py", "plot_11_dissipation_peak.py"}


def test_gallery_has_an_example_for_every_figure_of_the_papers():
    assert len(SCRIPTS) >= 11
    for path in SCRIPTS:
        doc = path.read_text(encoding="utf-8").split('"""')[1]
        title, underline = doc.strip().splitlines()[:2]
        assert set(underline) == {"="} and len(underline) >= len(title), path.name
        assert "Run time" in doc, path.name


@pytest.mark.parametrize("path", [
    pytest.param(p, id=p.stem, marks=[pytest.mark.slow] if p.name in SLOW else [])
    for p in SCRIPTS])
def test_gallery_example_runs_and_draws(path, monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    namespace = runpy.run_path(str(path), run_name="__main__")
    figures = [v for v in namespace.values() if isinstance(v, Figure)]
    assert figures, f"{path.name} binds no Figure"
    for fig in figures:
        assert fig.axes, f"{path.name}: an empty figure"
