"""A release-ready package: one version everywhere, the example cases and schemas inside
the wheel, typed public API (mypy), valid citation metadata and changelog."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from importlib.metadata import metadata, version
from pathlib import Path

import pytest

import slipcycle
from slipcycle.cli.main import main
from slipcycle.examples import list_examples

ROOT = Path(__file__).resolve().parents[1]


def test_one_version_for_the_command_line_the_metadata_the_package_and_the_docs(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    printed = capsys.readouterr().out.strip()
    assert printed == f"slipcycle {slipcycle.__version__}"
    assert version("slipcycle") == slipcycle.__version__
    cff = (ROOT / "CITATION.cff").read_text(encoding="utf-8")
    assert re.search(rf'^version: "?{re.escape(slipcycle.__version__)}"?$', cff, re.M)
    changelog = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    assert f"## [{slipcycle.__version__}]" in changelog
    conf = ROOT / "docs" / "conf.py"
    if conf.exists():
        assert "slipcycle.__version__" in conf.read_text(encoding="utf-8")
    # pyproject takes the version from the package, not a second literal
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert "version" in project.get("dynamic", []) and "version" not in project


def test_project_metadata_is_complete():
    meta = metadata("slipcycle")
    assert meta["Summary"] and meta["Requires-Python"]
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert {"Homepage", "Documentation", "Source", "Issues"} <= set(project["urls"])
    assert "Typing :: Typed" in project["classifiers"]
    assert project["keywords"] and project["authors"]


def test_citation_file_is_valid_cff_1_2_0():
    yaml = pytest.importorskip("yaml")
    data = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert data["cff-version"] == "1.2.0"
    for key in ("message", "title", "authors", "version", "license", "type"):
        assert data[key], key
    assert data["type"] in ("software", "dataset")
    for ref in data.get("references", []):
        assert ref["type"] and ref["title"] and ref["authors"]
        for person in ref["authors"]:
            assert person.get("family-names") or person.get("name")


def test_changelog_follows_keep_a_changelog():
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    assert text.startswith("# Changelog")
    assert "## [Unreleased]" in text
    versions = re.findall(r"^## \[(\d+\.\d+\.\d+)\] - (\d{4}-\d{2}-\d{2})$", text, re.M)
    assert versions, "no released version with a date"
    for heading in re.findall(r"^### (.+)$", text, re.M):
        assert heading in ("Added", "Changed", "Deprecated", "Removed", "Fixed", "Security")


def test_examples_and_schemas_are_package_data():
    pkg = Path(slipcycle.__file__).parent
    assert (pkg / "py.typed").exists()
    assert {p.stem for p in (pkg / "examples").glob("*.toml")} == set(list_examples())
    assert len(list_examples()) >= 10
    for name in ("summary", "case"):
        assert (pkg / "schemas" / f"{name}.schema.json").exists()
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    globs = data["tool"]["setuptools"]["package-data"]["slipcycle"]
    assert {"examples/*.toml", "schemas/*.json", "py.typed"} <= set(globs)


@pytest.mark.slow
def test_public_api_passes_mypy():
    pytest.importorskip("mypy", reason="needs mypy")
    proc = subprocess.run([sys.executable, "-m", "mypy"], cwd=ROOT, capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr


@pytest.mark.slow
def test_wheel_holds_the_example_cases_and_passes_twine(tmp_path):
    pytest.importorskip("build", reason="needs the build package")
    # built from a copy of the sources (a build writes build/ beside pyproject.toml), in
    # an isolated environment: the build-system requirements of pyproject.toml
    src = tmp_path / "src"
    shutil.copytree(ROOT / "src", src / "src", ignore=shutil.ignore_patterns(
        "__pycache__", "*.egg-info", "*.nbi", "*.nbc"))
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(ROOT / name, src / name)
    proc = subprocess.run([sys.executable, "-m", "build", "--wheel",
                           "--outdir", str(tmp_path), str(src)], capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    wheel = next(tmp_path.glob("slipcycle-*.whl"))
    assert wheel.name.startswith(f"slipcycle-{slipcycle.__version__}-")
    names = set(zipfile.ZipFile(wheel).namelist())
    for example in list_examples():
        assert f"slipcycle/examples/{example}.toml" in names, example
    assert {"slipcycle/py.typed", "slipcycle/schemas/summary.schema.json",
            "slipcycle/schemas/case.schema.json"} <= names
    twine = subprocess.run([sys.executable, "-m", "twine", "check", "--strict", str(wheel)],
                           capture_output=True, text=True, timeout=300)
    if "No module named twine" not in twine.stderr:
        assert twine.returncode == 0, twine.stdout + twine.stderr
