"""The README's instructions for a new user: reach ``drd``, install elsewhere, write outside tracked folders."""

from __future__ import annotations

import itertools
import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
README = (REPO / "README.md").read_text()
#: Options of ``drd`` that name a file or folder it writes.
OUTPUT_OPTIONS = ("--out", "--json", "--markdown", "--figures")


def _code() -> list[str]:
    """Every fenced block's lines and every inline code span (line breaks inside it joined)."""
    fenced = re.findall(r"^```[a-z]*\n(.*?)^```", README, flags=re.S | re.M)
    prose = re.sub(r"^```[a-z]*\n.*?^```", "", README, flags=re.S | re.M)
    lines = [line for block in fenced for line in block.splitlines()]
    return lines + [" ".join(span.split()) for span in re.findall(r"`([^`]+)`", prose)]


def _drd_commands() -> list[list[str]]:
    """The README's ``drd`` command lines as words (comments dropped; several per line after '#' or '=')."""
    commands = []
    for text in _code():
        for part in re.split(r"#|(?<=\s)=(?=\s)", text):
            words = [w.strip("\"'") for w in part.split()]
            if "drd" in words:
                commands.append(words[words.index("drd") :])
    return commands


def _ignored_top_folders() -> set[str]:
    return {
        line.strip().strip("/") for line in (REPO / ".gitignore").read_text().splitlines() if line.strip()
    }


def test_examples_write_only_into_git_ignored_folders() -> None:
    ignored = _ignored_top_folders()
    assert {"out", "results"} <= ignored
    written = []
    for words in _drd_commands():
        for option, value in itertools.pairwise(words):
            if option in OUTPUT_OPTIONS and not value.isupper():  # DIR, FILE: placeholders
                written.append(value)
                top = Path(value).parts[0]
                assert top in ignored, (
                    f"README: drd {' '.join(words[1:])} writes {value}, not in an ignored folder"
                )
                assert top != "trees", value
    assert len(written) >= 6, written  # the examples were found


def test_says_how_to_reach_the_installed_commands() -> None:
    assert "\n. .venv/bin/activate" in README
    assert "`.venv/bin/drd ...`" in README


def test_own_environment_install_upgrades_pip_before_installing_with_extras() -> None:
    lines = [line.split("#")[0].strip() for line in _code()]
    upgrade = lines.index("python -m pip install --upgrade pip")
    install = next(i for i, line in enumerate(lines) if line.startswith("python -m pip install -e"))
    assert upgrade < install
    assert '"ros2_ws/src/drd_planner[plots,test]"' in lines[install]


def test_run_sh_demo_says_how_to_reach_the_commands() -> None:
    script = (REPO / "scripts" / "run.sh").read_text()
    demo = script[script.index("  demo)\n") : script.index(";;", script.index("  demo)\n"))]
    assert ". $venv/bin/activate" in demo and ">&2" in demo
