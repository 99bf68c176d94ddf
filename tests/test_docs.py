"""The documentation builds, its examples run, and what it says is generated stays so."""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import pytest

import pairflock_env
from pairflock_env import ObsLayout

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _python_blocks(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(), flags=re.S)


@pytest.mark.skipif(
    importlib.util.find_spec("mkdocs") is None or importlib.util.find_spec("mkdocstrings") is None,
    reason="the docs tooling (mkdocs, mkdocstrings) is in the dev extra",
)
def test_the_site_builds_without_a_warning(tmp_path):
    # --strict: a broken link or anchor, a page missing from the nav, or an API object that
    # does not resolve fails the build
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    run = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(tmp_path / "site")],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    api = (tmp_path / "site" / "api" / "core" / "index.html").read_text()
    assert 'id="pairflock_env.PairFlockCore"' in api  # the reference is generated
    cli = (tmp_path / "site" / "api" / "cli" / "index.html").read_text()
    assert "usage: python -m train" in cli  # and so is each --help


def test_the_environment_page_shows_the_generated_observation_table():
    assert ObsLayout(2, 6).markdown_table() in (DOCS / "environment.md").read_text()


def test_the_home_page_example_is_the_readme_example():
    readme = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.S)
    assert _python_blocks(DOCS / "index.md")[0] == readme[0]  # tests/test_readme.py runs it


def test_the_extending_page_examples_run():
    """The page's blocks run top to bottom in a fresh interpreter (they register a controller,
    a preset and the toy plug-ins); a block that shows a file's part (``--8<--``) runs when
    that file is imported, as the page says."""
    blocks = _python_blocks(DOCS / "extending.md")
    shown = [b for b in blocks if b.lstrip().startswith("--8<--")]
    assert len(shown) == 4  # the four seams, shown from tests/plugins/pairflock_toys.py
    for b in shown:
        path, _, part = b.strip().split('"')[1].partition(":")
        assert f"--8<-- [start:{part}]" in (ROOT / path).read_text(), b
    code = "\n".join(b for b in blocks if b not in shown)
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(ROOT / "tests" / "plugins"), str(ROOT)]),
    }
    run = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300
    )
    assert run.returncode == 0, run.stderr[-3000:]
    error = float(re.search(r"pair error after 20 s: ([-+0-9.]+) m", run.stdout)[1])
    assert abs(error) < 0.5  # the example controller brings the pair into the 0.5 m band
    assert re.search(r"\[\d+\.\d+\]", run.stdout)  # the toy observation field, read by name


def test_the_version_is_written_once():
    tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "version" not in project["project"] and "version" in project["project"]["dynamic"]
    attr = project["tool"]["setuptools"]["dynamic"]["version"]["attr"]
    assert attr == "pairflock_env.__version__"
    assert re.fullmatch(r"\d+\.\d+\.\d+(\.dev\d+|rc\d+)?", pairflock_env.__version__)
    assert metadata.version("pairflock-env") == pairflock_env.__version__, (
        "the installed metadata is stale: reinstall with pip install -e ."
    )


def test_the_doctests_run_with_the_suite():
    tomllib = pytest.importorskip("tomllib")
    options = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    assert "--doctest-modules" in options["addopts"].split()
    assert "pairflock_env" in options["testpaths"]


# a repository path as the docs write it: a top-level folder of the project, then a path
_REPO_PATH = re.compile(
    r"(?<![\w./-])((?:pairflock_env|baselines|train|tests|benchmarks|docs|models|\.ci)"
    r"/[\w.\-/]*\w)"
)


def test_every_repository_path_the_docs_name_exists():
    """A file the README or a docs page points to (`pairflock_env/config/presets.py`) exists.

    Moving a module leaves these behind silently, and mkdocs checks only links."""
    pages = [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]
    missing = [
        f"{page.relative_to(ROOT)}:{number}: {path}"
        for page in pages
        for number, line in enumerate(page.read_text().splitlines(), 1)
        for path in _REPO_PATH.findall(line)
        if "*" not in path and not (ROOT / path).exists()
    ]
    assert not missing, "paths named in the docs that do not exist:\n" + "\n".join(missing)


def test_every_console_script_has_its_section_on_the_command_lines_page():
    """docs/api/cli.md documents each console script under its ``python -m`` command (the
    launcher the script runs: ``baselines.benchmark``, ``train.sweep.__main__``), with the
    ``--help`` of a parser."""
    tomllib = pytest.importorskip("tomllib")
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    page = (DOCS / "api" / "cli.md").read_text()
    headed = set(re.findall(r"^## .*`python -m ([\w.]+)`$", page, flags=re.M))
    commands = {t.split(":")[0].removesuffix(".__main__") for t in scripts.values()}
    missing = sorted(commands - headed)
    assert not missing, f"console scripts without a section in docs/api/cli.md: {missing}"
    assert len(re.findall(r"<!-- cli-help: [\w.]+:\w+ -->", page)) >= len(commands) - 1


#: the records of measured results (tables with the commands that give them, the history of
#: the measurements): the nav's "Results records", exempt from the guides' length limit
RECORDS = (
    "reproduction.md",
    "benchmark.md",
    "safety-results.md",
    "swarm-safety-results.md",
    "learning-results.md",
    "crazyflie-results.md",
    "speed.md",
    "large-swarms.md",
)
README_MAX_LINES, GUIDE_MAX_LINES = 150, 400


def test_the_readme_and_every_guide_stay_short():
    """The README says what the project is, how to set it up, the main job, how to extend it
    and where to read on, in at most 150 lines; a guide (every docs page but the records)
    says what a part is, how to use it and what it guarantees in at most 400, and links to its
    record for the measured tables."""
    readme = len((ROOT / "README.md").read_text().splitlines())
    assert readme <= README_MAX_LINES, (
        f"README.md has {readme} lines (at most {README_MAX_LINES}): link to the docs instead"
    )
    long = [
        f"docs/{name}: {lines} lines"
        for path in sorted(DOCS.rglob("*.md"))
        if (name := path.relative_to(DOCS).as_posix()) not in RECORDS
        and (lines := len(path.read_text().splitlines())) > GUIDE_MAX_LINES
    ]
    assert not long, (
        f"guides longer than {GUIDE_MAX_LINES} lines (move measured results to a record page):\n"
        + "\n".join(long)
    )


def test_the_records_are_marked_and_listed_as_records():
    yaml = pytest.importorskip("yaml")
    nav = yaml.safe_load((ROOT / "mkdocs.yml").read_text())["nav"]
    (section,) = [
        e["Results records"] for e in nav if isinstance(e, dict) and "Results records" in e
    ]
    assert sorted(page for entry in section for page in entry.values()) == sorted(RECORDS)
    home = (DOCS / "index.md").read_text()
    for page in RECORDS:
        title = (DOCS / page).read_text().splitlines()[0]
        assert title.startswith("# ") and title.endswith("(measured records)"), (page, title)
        assert f"]({page})" in home, f"the home page does not list the record {page}"


def test_the_readme_links_to_pages_and_headings_that_exist():
    """mkdocs checks the site's links; the README is not part of the site."""
    slugify = pytest.importorskip("markdown.extensions.toc").slugify
    links = re.findall(r"\]\((docs/[^)#]+)(?:#([^)]+))?\)", (ROOT / "README.md").read_text())
    assert links
    for path, anchor in links:
        text = (ROOT / path).read_text()
        assert text, path
        if anchor:
            headings = re.findall(r"^#+ (.+)$", re.sub(r"```.*?```", "", text, flags=re.S), re.M)
            slugs = {slugify(h.replace("`", "").strip(), "-") for h in headings}
            assert anchor in slugs, f"README links to {path}#{anchor}, which has no such heading"
