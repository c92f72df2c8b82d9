"""The OMPL workers' shared entry: the result file's error line, and the exit status after the work."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from drd_planner.cli.worker_entry import write_result


def test_an_exception_is_written_to_the_result_file_and_raised(tmp_path: Path) -> None:
    path = tmp_path / "result.jsonl"
    write_result(path, lambda out: out.write('{"done": true}\n'))
    assert path.read_text() == '{"done": true}\n'

    def fail(out: object) -> None:
        raise ValueError("no graph")

    with pytest.raises(ValueError, match="no graph"):
        write_result(path, fail)
    assert json.loads(path.read_text()) == {"error": "ValueError: no graph"}


@pytest.mark.parametrize(("body", "code"), [("pass", 0), ("raise RuntimeError('boom')", 1)])
def test_the_process_leaves_with_the_work_s_status(body: str, code: int) -> None:
    script = (
        "from drd_planner.cli.worker_entry import exit_after\n"
        f"def work():\n    {body}\n"
        "exit_after('worker', work)\n"
        "print('never reached')\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == code
    assert "never reached" not in done.stdout
    assert ("worker: RuntimeError: boom" in done.stderr) == (code == 1)
