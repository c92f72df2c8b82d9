"""The instructions a new user reads (README.md and the docs pages in docs/): reach ``drd``, install elsewhere,
write outside tracked folders; the README stays short, and no file cites a document the repository lacks."""

from __future__ import annotations

import itertools
import re
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
README = (REPO / "README.md").read_text()
#: The docs page with the install and ``drd`` walk-through.
GETTING_STARTED = (REPO / "docs" / "getting-started.md").read_text()
#: Where a user reads commands: the README and every docs page.
PAGES = {"README.md": README} | {f"docs/{path.name}": path.read_text() for path in sorted((REPO / "docs").glob("*.md"))}
#: Options of ``drd`` that name a file or folder it writes.
OUTPUT_OPTIONS = ("--out", "--json", "--markdown", "--figures")
#: The README's size limit in bytes: what it is, the two commands, an example, the node; the rest is in docs/.
README_MAX_BYTES = 15_000
#: Design notes that are not in the repository: the code and docs cite the docs pages instead. (Spelt in two
#: parts so that this file does not cite them itself.)
MISSING_DOCUMENTS = ("DESIGN" + ".md", "ALGORITHMS" + ".md")
#: The same documents cited by their bare names and a section number (the name, a space, a digit).
MISSING_SECTIONS = re.compile(rb"\b(?:DESIGN|ALGORITHMS)(?:\.md)? (?:section )?\d")


def _code(text: str) -> list[str]:
    """Every fenced block's lines and every inline code span (line breaks inside it joined) of ``text``."""
    fenced = re.findall(r"^```[a-z]*\n(.*?)^```", text, flags=re.S | re.M)
    prose = re.sub(r"^```[a-z]*\n.*?^```", "", text, flags=re.S | re.M)
    lines = [line for block in fenced for line in block.splitlines()]
    return lines + [" ".join(span.split()) for span in re.findall(r"`([^`]+)`", prose)]


def _drd_commands(text: str) -> list[list[str]]:
    """The ``drd`` command lines of ``text`` as words (comments dropped; several per line after '#' or '=')."""
    commands = []
    for line in _code(text):
        for part in re.split(r"#|(?<=\s)=(?=\s)", line):
            words = [w.strip("\"'") for w in part.split()]
            if "drd" in words:
                commands.append(words[words.index("drd") :])
    return commands


def _ignored_top_folders() -> set[str]:
    return {line.strip().strip("/") for line in (REPO / ".gitignore").read_text().splitlines() if line.strip()}


def test_examples_write_only_into_git_ignored_folders() -> None:
    ignored = _ignored_top_folders()
    assert {"out", "results"} <= ignored
    written = []
    for page, text in PAGES.items():
        for words in _drd_commands(text):
            for option, value in itertools.pairwise(words):
                if option in OUTPUT_OPTIONS and not value.isupper():  # DIR, FILE: placeholders
                    written.append(value)
                    top = Path(value).parts[0]
                    assert top in ignored, f"{page}: drd {' '.join(words[1:])} writes {value}, not in an ignored folder"
                    assert top != "trees", value
    assert len(written) >= 6, written  # the examples were found


def test_says_how_to_reach_the_installed_commands() -> None:
    assert "\n. .venv/bin/activate" in GETTING_STARTED
    assert "`.venv/bin/drd ...`" in GETTING_STARTED
    assert "`. .venv/bin/activate`" in README


def test_own_environment_install_upgrades_pip_before_installing_with_extras() -> None:
    lines = [line.split("#")[0].strip() for line in _code(GETTING_STARTED)]
    upgrade = lines.index("python -m pip install --upgrade pip")
    install = next(i for i, line in enumerate(lines) if line.startswith("python -m pip install -e"))
    assert upgrade < install
    assert '"ros2_ws/src/drd_planner[plots,test]"' in lines[install]


def test_run_sh_demo_says_how_to_reach_the_commands() -> None:
    script = (REPO / "scripts" / "run.sh").read_text()
    demo = script[script.index("  demo)\n") : script.index(";;", script.index("  demo)\n"))]
    assert ". $venv/bin/activate" in demo
    assert ">&2" in demo


def test_readme_is_short_and_no_file_cites_documents_the_repository_lacks() -> None:
    size = len(README.encode())
    assert size <= README_MAX_BYTES, f"README.md is {size} bytes; move detail to a page in docs/"
    tracked = subprocess.run(["git", "ls-files", "-z"], cwd=REPO, capture_output=True, check=True).stdout.split(b"\0")
    citations = []
    for name in filter(None, tracked):
        path = REPO / name.decode()
        if not path.is_file():  # deleted in the work tree, not yet committed
            continue
        for number, line in enumerate(path.read_bytes().splitlines(), start=1):
            for document in MISSING_DOCUMENTS:
                if document.encode() in line:
                    citations.append(f"{name.decode()}:{number}: {document}")
            if MISSING_SECTIONS.search(line) and not any(d.encode() in line for d in MISSING_DOCUMENTS):
                citations.append(f"{name.decode()}:{number}: {line.decode(errors='replace').strip()}")
    assert not citations, (
        "these cite documents that are not in the repository (cite the docs page that explains it):\n"
        + "\n".join(citations)
    )
