"""The docs agree with the code, in both directions: every scene key, CLI flag and subcommand,
output file and expression name in docs/user-guide.md exists, and everything that exists is
documented; the Sphinx site (the Markdown pages and the API reference) builds without a
warning; demo comments cite files that exist."""
import argparse
import dataclasses
import os
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

import pytest

from ngfrac.cli import build_parser
from ngfrac.scene.expressions import CONSTANTS, FUNCTIONS, VARIABLES
from ngfrac.scene import LISTS, SECTIONS, SceneError

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "user-guide.md"
SLIT = str(ROOT / "demos" / "mode3_slit.toml")
# P1 on a coarse uniform mesh, 4 steps with a checkpoint: a run that writes every kind of file
TINY = ["--set", "phase_field.epsilon=0.08", "--set", "geometry.mesh_size=0.04",
        "--set", "adaptivity.enabled=false", "--set", "discretization.order=1",
        "--set", "time.t_end=0.002", "--set", "output.checkpoint_every=2", "--no-progress"]


def section(title: str) -> str:
    """The guide's text under a heading (up to the next heading of the same or a higher level)."""
    text = GUIDE.read_text()
    level = title.split(" ")[0]
    if f"\n{title}\n" not in text:
        pytest.fail(f"docs/user-guide.md has no heading {title!r}")
    start = text.index(f"\n{title}\n")
    end = re.search(rf"\n#{{1,{len(level)}}} ", text[start + 1:])
    return text[start: start + 1 + end.start()] if end else text[start:]


def table_rows(text: str) -> list[list[str]]:
    """The cells of each table row, without header and rule rows."""
    lines = text.splitlines()
    return [[cell.strip() for cell in line.strip().strip("|").split(" | ")]
            for line, after in zip(lines, lines[1:] + [""])
            if line.startswith("| ") and not after.startswith("|---")]


# -- scene keys -------------------------------------------------------------------------------
def documented_keys():
    text = GUIDE.read_text()
    keys = {}
    for block in re.split(r"\n#{2,3} ", text):  # a "## " heading ends a section's table
        header = re.match(r"`\[+([a-z_]+)\]+`", block)
        if not header:
            continue
        rows = re.findall(r"^\| ([^|]+) \|", block, flags=re.M)
        names = set()
        for row in rows:
            names.update(part.strip() for part in row.split(","))
        keys[header.group(1)] = names - {"key"}
    return keys


def test_every_scene_key_is_in_the_user_guide():
    keys = documented_keys()
    missing = []
    for section_name, cls in {**SECTIONS, **LISTS}.items():
        for field in dataclasses.fields(cls):
            if field.name not in keys.get(section_name, set()):
                missing.append(f"{section_name}.{field.name}")
    assert not missing, f"scene keys missing from docs/user-guide.md: {missing}"


def test_every_documented_scene_key_exists():
    classes = {**SECTIONS, **LISTS}
    unknown = []
    for section_name, names in documented_keys().items():
        if section_name not in classes:
            unknown.append(f"[{section_name}]")
            continue
        fields = {f.name for f in dataclasses.fields(classes[section_name])}
        unknown += [f"{section_name}.{name}" for name in sorted(names - fields)]
    assert not unknown, f"docs/user-guide.md documents keys the scene does not have: {unknown}"


# -- the command line -------------------------------------------------------------------------
def parser_actions() -> dict[str, list[set[str]]]:
    """{"ngfrac": [spellings of each top-level option], "run": [...], ...}; a positional is
    named by its dest in upper case (SCENE); help is left out."""
    def arguments(parser: argparse.ArgumentParser) -> list[set[str]]:
        return [set(action.option_strings or [action.dest.upper()])
                for action in parser._actions  # argparse has no public walk
                if not isinstance(action, (argparse._HelpAction, argparse._SubParsersAction))]

    top = build_parser()
    out = {"ngfrac": arguments(top)}
    for action in top._actions:
        if isinstance(action, argparse._SubParsersAction):
            out.update({name: arguments(sub) for name, sub in action.choices.items()})
    return out


def documented_arguments() -> dict[str, set[str]]:
    found: dict[str, set[str]] = {}
    for row in table_rows(section("## The command line")):
        if len(row) != 3 or not re.fullmatch(r"[a-z]+", row[0]):
            continue  # the file table below has other columns
        names = {token.split(" ")[0] for token in re.findall(r"`([^`]+)`", row[1])}
        found.setdefault(row[0], set()).update(names)
    return found


def test_cli_table_lists_every_subcommand_and_flag_and_nothing_else():
    code = {command: set().union(*spellings) for command, spellings in parser_actions().items()}
    docs = documented_arguments()
    assert set(docs) == set(code), f"subcommands: parser {sorted(code)}, guide {sorted(docs)}"
    for command in code:
        assert docs[command] == code[command], (
            f"ngfrac {command}: undocumented {sorted(code[command] - docs[command])}, "
            f"documented but absent {sorted(docs[command] - code[command])}")


def test_cli_summary_shows_every_subcommand_and_flag():
    block = re.search(r"```\n(.*?)```", section("## The command line"), flags=re.S).group(1)
    for command, actions in parser_actions().items():
        prefix = "ngfrac " if command == "ngfrac" else f"ngfrac {command} "
        text = " ".join(line for line in block.splitlines() if line.startswith(prefix))
        assert text, f"the summary has no line for ngfrac {command}"
        missing = [sorted(spellings) for spellings in actions
                   if not any(re.search(rf"(?<![\w-]){re.escape(name)}(?![\w-])", text)
                              for name in spellings if name.startswith("-"))
                   and any(name.startswith("-") for name in spellings)]
        assert not missing, f"ngfrac {command}: the summary lacks {missing}"


# -- output files -----------------------------------------------------------------------------
def documented_files() -> dict[str, re.Pattern]:
    """Each documented file name as a pattern: NNNNN is a number, <t> any time."""
    patterns = {}
    for row in table_rows(section("### Files in a run folder")):
        for name in re.findall(r"`([^`]+)`", row[0]):
            regex = (re.escape(name).replace("NNNNN", r"\d{5}").replace("NNN", r"\d{3}")
                     .replace("<t>", r"[^/]+"))
            patterns[name] = re.compile(regex)
    return patterns


@pytest.fixture(scope="module")
def written_files(tmp_path_factory):
    """The files a tiny `ngfrac run` and `ngfrac plot` write into a run folder (both run in
    this process, :func:`ngfrac.cli.main`: the files are the same as from ``python -m ngfrac``,
    without a new interpreter importing NGSolve twice; tests/io/test_cli.py runs those)."""
    from ngfrac.cli import main

    out = tmp_path_factory.mktemp("docs") / "run"
    for args in (["run", SLIT, "--out", str(out), *TINY], ["plot", str(out)]):
        assert main(args) == 0, f"ngfrac {' '.join(args)} failed (its stderr is above)"
    return sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())


def test_every_file_a_run_writes_is_documented(written_files):
    patterns = documented_files()
    undocumented = [name for name in written_files
                    if not any(p.fullmatch(name) for p in patterns.values())]
    assert not undocumented, f"files written but not in the guide's file table: {undocumented}"


def test_every_documented_file_is_written(written_files):
    absent = [name for name, p in documented_files().items()
              if not any(p.fullmatch(f) for f in written_files)]
    assert not absent, f"files in the guide that a run does not write: {absent} ({written_files})"


# -- one meaning for output.vtk_every = 0 ------------------------------------------------------
def test_vtk_every_zero_means_only_the_last_step(tmp_path):
    from ngfrac.runner import run_scene
    from ngfrac.testing.scenes import quick_slit

    row = next(r for r in table_rows(section("### `[output]`")) if r[0] == "vtk_every")
    assert "0: only the last step" in row[3]
    with pytest.raises(SceneError, match=r"0: only the last step"):
        quick_slit("output.vtk_every=-1")
    scene = quick_slit("output.vtk_every=0", "time.t_end=0.002", "discretization.order=1",
                       "output.results=false", "phase_field.epsilon=0.08",
                       "geometry.mesh_size=0.04")
    summary = run_scene(scene, tmp_path / "run", plots=False)
    assert summary.n_snapshots == 1
    pvd = (tmp_path / "run" / "vtk" / "fields.pvd").read_text()
    (t,) = re.findall(r'timestep="([^"]+)"', pvd)
    assert float(t) == summary.last.t == pytest.approx(0.002)


# -- expressions ------------------------------------------------------------------------------
def test_expression_names_in_the_guide_are_those_allowed():
    text = section("## Scene files")
    paragraph = text[text.index("Expressions are strings"): text.index("refused when")]
    documented = {token for token in re.findall(r"`([^`]+)`", paragraph)
                  if re.fullmatch(r"[a-z_][a-z0-9_]*", token)}
    allowed = set(VARIABLES) | set(CONSTANTS) | set(FUNCTIONS)
    assert documented == allowed, (f"undocumented {sorted(allowed - documented)}, "
                                   f"documented but refused {sorted(documented - allowed)}")


# -- the Sphinx site and demos ----------------------------------------------------------------
def public_modules(package: str) -> list[str]:
    """The package and its modules whose names do not start with ``_``, at any depth."""
    root = __import__(package)
    return [package] + [m.name for m in pkgutil.walk_packages(root.__path__, f"{package}.")
                        if not any(part.startswith("_") for part in m.name.split("."))]


@pytest.fixture(scope="module")
def built_site(tmp_path_factory):
    """One `sphinx-build -W` of the docs for the tests of the site: its result and html folder."""
    html = tmp_path_factory.mktemp("site") / "html"
    result = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-b", "html", "-q",
                             str(ROOT / "docs"), str(html)], capture_output=True, text=True,
                            env={**os.environ, "NGFRAC_THREADS": "1"})
    return result, html


def test_sphinx_builds_the_docs_without_a_warning(built_site):
    """`python3 dev.py docs` as CI sees it: any warning (a broken link between the pages, a
    docstring docutils cannot parse, an ambiguous reference, a module that fails to import)
    fails the build. Every public module gets a page, and a sentinel default such as
    ``scene.REQUIRED`` shows by name, not as an object (whose repr would differ every run)."""
    result, html = built_site
    assert result.returncode == 0, (
        f"sphinx-build -W failed (sphinx and myst-parser come with pip install -e '.[test]'):\n"
        f"{result.stderr}")
    missing = [name for package in ("ngfrac", "estimators") for name in public_modules(package)
               if not (html / "generated" / f"{name}.html").exists()]
    assert not missing, f"modules without a page in the API reference: {missing}"
    scene = re.sub(r"<[^>]+>", "", (html / "generated" / "ngfrac.scene.sections.html").read_text())
    assert "PhaseField(epsilon: float = REQUIRED," in scene, "PhaseField's signature lacks REQUIRED"
    shown_objects = [page.name for page in html.rglob("*.html")
                     if re.search(r" at 0x|&lt;object object", page.read_text())]
    assert not shown_objects, f"pages that show an object's repr as a default: {shown_objects}"


def test_the_built_guide_renders_every_table_row(built_site):
    """Markdown that MyST does not render as a table (a row after a subsection, a blank line
    inside a table) shows as raw "| a | b |" text on the site, and "<c>" outside code is
    taken for HTML and vanishes: the built pages hold no raw row, and the history table holds
    the reaction columns by name."""
    result, html = built_site
    assert (html / "user-guide.html").exists(), result.stderr  # -W keeps going: the pages exist
    raw_row = re.compile(r"(?m)^(?:<p>)?\|[^\n]*\|\s*(?:</p>)?$")  # a line "| a | b |"
    raw = {page.name: raw_row.findall(page.read_text()) for page in html.glob("*.html")}
    raw = {name: found for name, found in raw.items() if found}
    assert not raw, f"table rows rendered as text: {raw}"
    guide = (html / "user-guide.html").read_text()
    start = guide.index('id="history-csv"')
    table = guide[start: guide.index("</table>", start)]
    cells = [re.sub(r"<[^>]+>", "", cell).strip()
             for cell in re.findall(r"<td>(.*?)</td>", table, flags=re.S)]
    for column in ("crack_volume", "F&lt;c&gt;_&lt;boundary&gt;, u&lt;c&gt;_&lt;boundary&gt;",
                   "path_length", "step_s, solve_s, adapt_s"):
        assert column in cells, f"{column!r} is not a cell of the built history table"


def test_the_guides_first_api_example_sets_the_threads():
    text = section("## The Python API")
    first = re.search(r"```python\n(.*?)```", text, flags=re.S).group(1)
    assert "set_threads(" in first.split("PhaseFieldStepper(scene)")[0]


def test_demo_comments_cite_files_that_exist():
    missing = []
    for demo in sorted((ROOT / "demos").iterdir()):
        if demo.suffix not in (".py", ".toml"):
            continue
        for name in re.findall(r"(?<![\w/])((?:[\w-]+/)*[\w-]+\.(?:md|py|toml))\b", demo.read_text()):
            if "NAME" in name or name.startswith("OUT_DIR"):
                continue  # a placeholder, or an output
            if not any((base / name).exists() for base in (ROOT, ROOT / "demos", ROOT / "docs")):
                missing.append(f"{demo.name}: {name}")
    assert not missing, f"demo comments cite files that are not in the project: {missing}"
